#pragma once

// Text of the diagnosis for people (internal): the note of each candidate's verdict, and the parts
// of DiagnosisVerdict.

#include <string>

#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {

// The note of a verdict: why it was kept, dropped, not refined, confounded or not significant.
std::string VerdictNote(const EffectVerdict& v, const DiagnosisOptions& options);

// The lines of DiagnosisVerdict: where (component, band, stretch), which (the kept effects, the
// confounding notes and the other candidates' notes), and how far (the held-out gap per component
// after each kept effect).
std::string WhereText(const Diagnosis& d);
std::string WhichText(const Diagnosis& d);
std::string HowFarText(const Diagnosis& d);

}  // namespace rotorid::internal

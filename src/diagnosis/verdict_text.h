#pragma once

// Text of the diagnosis for people (internal): the note of each candidate's verdict, and the parts
// of DiagnosisVerdict.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {

// The note of a verdict: why it was kept, dropped, not refined, confounded or not significant. A
// kept effect's note is its held-out shrink; what the final fit says about it follows after "; ".
// The size above which the data would reveal an absent effect is computed with the `selected`
// effects in the model, and the note says so: another effect may hide part of it.
std::string VerdictNote(const EffectVerdict& v, const DiagnosisOptions& options,
                        const std::vector<EffectKind>& selected);

// A scale-free test's values in the units the row fixes: "rotor_inertia_kgm2 / kd = 980.1 +- 12".
std::string ScaleFreeValueText(const ScaleFreeTest& test);

// What the scale-free test of a verdict (which has one) found: the component, the values, the
// held-out relative error of the row before and after, the test, and the SI value or why there is none.
std::string ScaleFreeStatement(const EffectVerdict& v);

// "motor_lag = 300 ms is on its upper bound (300 ms): the data push it further", for an effect
// that its refinement ended on a bound (RefineResult::on_bound): the coordinates nearest a non-zero
// bound of its descriptor (the refinement keeps estimates inside those; a zero bound, tau >= 0, is a
// physical limit, not a failure to fit). Such an estimate is not an optimum but a clipped value, so
// the diagnosis reports the effect implausible rather than selecting it.
std::string OnBoundStatement(EffectKind kind, const Eigen::VectorXd& value);

// The lines of DiagnosisVerdict: where (component, band, stretch), which (the kept effects with
// what the final fit says about them, the confounding notes and the other candidates' notes), and
// how far (the held-out gap per component after each kept effect).
std::string WhereText(const Diagnosis& d);
std::string WhichText(const Diagnosis& d);
std::string HowFarText(const Diagnosis& d);

}  // namespace rotorid::internal

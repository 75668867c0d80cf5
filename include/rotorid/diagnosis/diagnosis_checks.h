#pragma once

#include <vector>

#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/ident/checks.h"

namespace rotorid {

// The plausibility checks (rotorid/ident/checks.h) of a diagnosis: the linear and the final
// parameters (values only: the diagnosis keeps no std), each with physical_consistency of the
// configurations in `mass_kg` (ConfigurationMasses), finite effects, held-out Table III.
std::vector<Check> CheckDiagnosis(const Diagnosis& diagnosis, const std::vector<std::string>& configs,
                                  const std::map<std::string, double>& mass_kg);

// Whether the linear model's residual shows the signature of an unmodelled effect: each candidate
// of `options` that the flights can carry is fitted alone to first order at the TLS solution (the
// essential parameters profiled out, as the diagnosis screens), and one whose fit removes at least
// `min_shrink_pct` of the in-sample residual at the diagnosis' significance level is named, with
// the commands that test it ("residual_signature", a warning; ok when none shows). A first-order
// fit understates large delays and lags: the shrink it gives is a lower bound.
Check CheckResidualSignature(const IdentificationResult& linear, const DiagnosisOptions& options = {},
                             double min_shrink_pct = 5.0);

}  // namespace rotorid

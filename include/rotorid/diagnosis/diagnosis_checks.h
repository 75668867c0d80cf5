#pragma once

#include <vector>

#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/ident/checks.h"

namespace rotorid {

// The plausibility checks (rotorid/ident/checks.h) of a diagnosis: the linear and the final
// parameters (values only: the diagnosis keeps no std), finite effects, held-out Table III.
std::vector<Check> CheckDiagnosis(const Diagnosis& diagnosis, const std::vector<std::string>& configs);

}  // namespace rotorid

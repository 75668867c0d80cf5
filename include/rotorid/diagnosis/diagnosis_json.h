#pragma once

// The diagnose report (INTERFACE.md section 5: baseline.relative_error_pct, where.component,
// ranking[] {effect, significant, shrink_pct, magnitude}, selected[], final.relative_error_pct)
// with the richer details documented in docs/diagnosis.md.

#include <nlohmann/json.hpp>

#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid {

nlohmann::json DiagnosisOptionsJson(const DiagnosisOptions& options);
nlohmann::json DiagnosisJson(const Diagnosis& diagnosis);

}  // namespace rotorid

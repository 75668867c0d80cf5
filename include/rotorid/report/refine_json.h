#pragma once

// JSON of refinement results (INTERFACE.md section 5: refined.parameters, refined.effects,
// refined.relative_error_pct), shared by refine, delay, ablate and diagnose.

#include <nlohmann/json.hpp>

#include "rotorid/refine/refine.h"

namespace rotorid {

nlohmann::json RefineOptionsJson(const RefineOptions& options);
// {"delay_s": {"value", "std", "enabled", "on_bound"}, ...} for every effect parameter.
nlohmann::json EffectsJson(const Effects& value, const Effects& std_dev, const std::vector<EffectKind>& enabled,
                           const std::vector<EffectKind>& on_bound = {});
nlohmann::json SolverJson(const SolverReport& solver);
// The "refined" block.
nlohmann::json RefinedJson(const IdentificationResult& linear, const RefineResult& refined);
// Effects from a report's "refined.effects" block (zeros when absent).
Effects EffectsFromReport(const nlohmann::json& report);

}  // namespace rotorid

#pragma once

// JSON of refinement results (INTERFACE.md section 5: refined.parameters, refined.effects,
// refined.relative_error_pct), shared by refine, delay, ablate and diagnose; the ablation and
// delay results.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/refine/ablate.h"
#include "rotorid/refine/delay.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

nlohmann::json RefineOptionsJson(const RefineOptions& options);

// One entry of refined.effects: an effect's parameter, or one coefficient of an effect whose
// coefficients INTERFACE.md names one by one, with its estimate.
struct EffectParameterEstimate {
  std::string name;  // delay_s, acc_bias, rotor_drag_coefficient, ...
  Eigen::VectorXd value;
  Eigen::VectorXd std;
  bool scalar = true;  // written as a number, else as an array
  bool enabled = false;
  bool on_bound = false;
  std::vector<std::string> held;  // coordinates held at the vehicle file's value, not estimated
  std::string held_why;           // why (EffectDescriptor::Info::held_why), when some are
};
// Every effect parameter of the registry, in its order.
std::vector<EffectParameterEstimate> EffectParameterEstimates(const Effects& value, const Effects& std_dev,
                                                              const std::vector<EffectKind>& enabled,
                                                              const std::vector<EffectKind>& on_bound = {});
// {"delay_s": {"value", "std", "enabled", "on_bound"}, ...} for every effect parameter.
nlohmann::json EffectsJson(const Effects& value, const Effects& std_dev, const std::vector<EffectKind>& enabled,
                           const std::vector<EffectKind>& on_bound = {});
nlohmann::json SolverJson(const SolverReport& solver);
// The "refined" block.
nlohmann::json RefinedJson(const IdentificationResult& linear, const RefineResult& refined);
// The "ablation" rows: per subset of effects, its size, information criteria, relative errors
// (held-out ones when there were held-out flights), kt, kd and the effects.
nlohmann::json AblationJson(const AblationResult& ablation);
// The delay command's results: delay_s, delay_std_s, grid_best_s, motor_tau_s, motor_tau_std_s,
// criterion_curve [[delay, criterion], ...], the "refined" block of its refinement and warnings.
nlohmann::json DelayJson(const IdentificationResult& linear, const DelayEstimate& estimate);
// Effects from a report's "refined.effects" block (zeros when absent).
Effects EffectsFromReport(const nlohmann::json& report);

}  // namespace rotorid

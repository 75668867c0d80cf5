#include "rotorid/refine/refine_checks.h"

#include <cmath>

namespace rotorid {
namespace {

bool OnBound(double value, double low, double high) {
  const double tolerance = 1e-6 * (high - low);
  return value <= low + tolerance || value >= high - tolerance;
}

// Effects whose estimate is not finite, and those that sit on the bound of their range.
std::vector<Check> EffectChecks(const RefineResult& refined, const RefineOptions& options, const std::string& label) {
  std::string not_finite, bounded;
  for (EffectKind kind : refined.enabled) {
    if (!refined.effects.Get(kind).allFinite() || !refined.effects_std.Get(kind).allFinite())
      not_finite += (not_finite.empty() ? "" : ", ") + std::string(EffectParameterName(kind));
  }
  const Effects& e = refined.effects;
  if (options.Enabled(EffectKind::kDelay) && OnBound(e.delay_s, options.delay_search_min_s, options.delay_search_max_s))
    bounded += "delay_s";
  if (options.Enabled(EffectKind::kMotorLag) && OnBound(e.motor_tau_s, 0.0, options.max_motor_tau_s))
    bounded += std::string(bounded.empty() ? "" : ", ") + "motor_tau_s";
  if (options.Enabled(EffectKind::kAccBias) &&
      e.acc_bias.cwiseAbs().maxCoeff() >= options.max_acc_bias_mps2 * (1 - 1e-6))
    bounded += std::string(bounded.empty() ? "" : ", ") + "acc_bias";
  if (options.Enabled(EffectKind::kGyroBias) &&
      e.gyro_bias.cwiseAbs().maxCoeff() >= options.max_gyro_bias_radps * (1 - 1e-6))
    bounded += std::string(bounded.empty() ? "" : ", ") + "gyro_bias";
  std::vector<Check> checks;
  if (!not_finite.empty())
    checks.push_back({"effects_finite", CheckStatus::kError, label + ": NaN or inf in " + not_finite});
  if (!bounded.empty())
    checks.push_back({"effects_on_bounds", CheckStatus::kWarning,
                      label + ": " + bounded +
                          " ended on the bound of its range: the flights do not determine it, or the residual has a "
                          "cause outside the modelled effects"});
  else
    checks.push_back({"effects_on_bounds", CheckStatus::kOk, label + ": every effect inside its range"});
  return checks;
}

void Append(std::vector<Check>* to, std::vector<Check> from) {
  for (Check& c : from) to->push_back(std::move(c));
}

}  // namespace

std::vector<Check> CheckRefinement(const IdentificationResult& linear, const RefineResult& refined,
                                   const RefineOptions& options, const std::string& label) {
  std::vector<Check> checks =
      CheckParameters(CheckedFromSolution(linear.system, refined.refined), linear.system.config_names, label);
  Append(&checks, EffectChecks(refined, options, label));
  Append(&checks, CheckRelativeError(refined.relative_error_pct, label, /*held_out=*/false));
  return checks;
}

std::vector<Check> CheckDelay(const IdentificationResult& linear, const DelayEstimate& estimate,
                              const DelayOptions& options) {
  std::vector<Check> checks = CheckParameters(CheckedFromSolution(linear.system, estimate.refined.refined),
                                              linear.system.config_names, "delay");
  if (!std::isfinite(estimate.delay_s) || !std::isfinite(estimate.delay_std_s) ||
      !std::isfinite(estimate.motor_tau_s) || !std::isfinite(estimate.motor_tau_std_s))
    checks.push_back({"effects_finite", CheckStatus::kError, "delay: the delay or its std is NaN or inf"});
  if (OnBound(estimate.delay_s, options.min_s, options.max_s))
    checks.push_back({"effects_on_bounds", CheckStatus::kWarning,
                      "delay: " + std::to_string(1000.0 * estimate.delay_s) +
                          " ms is on the edge of the searched range: widen --min-s/--max-s"});
  else
    checks.push_back({"effects_on_bounds", CheckStatus::kOk, "delay: inside the searched range"});
  return checks;
}

}  // namespace rotorid

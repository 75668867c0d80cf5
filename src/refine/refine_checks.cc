#include "rotorid/refine/refine_checks.h"

#include <cmath>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"

namespace rotorid {
namespace {

bool OnBound(double value, double low, double high) {
  const double tolerance = 1e-6 * (high - low);
  return value <= low + tolerance || value >= high - tolerance;
}

// Effects whose estimate is not finite, and those that sit on the bound of their range (as Refine found).
std::vector<Check> EffectChecks(const RefineResult& refined, const std::string& label, CheckStatus on_bound_status) {
  std::string not_finite, bounded;
  for (EffectKind kind : refined.enabled) {
    if (!refined.effects.Get(kind).allFinite() || !refined.effects_std.Get(kind).allFinite())
      not_finite += (not_finite.empty() ? "" : ", ") + std::string(EffectParameterName(kind));
  }
  for (EffectKind kind : refined.on_bound)
    bounded += (bounded.empty() ? "" : ", ") + std::string(EffectParameterName(kind));
  std::vector<Check> checks;
  if (!not_finite.empty())
    checks.push_back({"effects_finite", CheckStatus::kError, label + ": NaN or inf in " + not_finite});
  if (!bounded.empty())
    checks.push_back({"effects_on_bounds", on_bound_status,
                      label + ": " + bounded +
                          " ended on the bound of its range, so the bound clipped it: the flights do not determine it, "
                          "or it absorbs a cause outside the modelled effects"});
  else
    checks.push_back({"effects_on_bounds", CheckStatus::kOk, label + ": every effect inside its range"});
  return checks;
}

void Append(std::vector<Check>* to, std::vector<Check> from) {
  for (Check& c : from) to->push_back(std::move(c));
}

// The parameter checks of a refined model. Without a covariance (not asked for, as in ablation, or a
// rank-deficient joint Jacobian: a delay and a lag both near zero are the same to first order) every
// std is 0 meaning "not known", not "exactly determined"; the confounded coordinates are named.
std::vector<Check> RefinedParameterChecks(const IdentificationResult& linear, const RefineResult& refined,
                                          const std::string& label) {
  CheckedParameters parameters = CheckedFromSolution(linear.system, refined.refined);
  if (!refined.has_covariance) parameters.std.clear();
  std::vector<Check> checks = CheckParameters(parameters, linear.system.config_names, label);
  if (refined.rank_deficient) {
    const std::string names = Join(refined.confounded);
    checks.push_back({"refined_identifiable", CheckStatus::kWarning,
                      label + ": the refined parameters are not jointly identifiable (confounded: " + names +
                          "), so no std is reported; refine fewer effects (rotorid ablate compares subsets)"});
  }
  for (const std::string& pair : refined.resting_on_discarded)
    checks.push_back({"refined_identifiable", CheckStatus::kWarning,
                      label + ": " + pair.substr(0, pair.find(" ~ ")) + " is confounded with " +
                          pair.substr(pair.find(" ~ ") + 3) +
                          ", which the essential selection holds at 0: its value assumes that parameter is 0, "
                          "and its std does not include that assumption"});
  return checks;
}

}  // namespace

std::vector<Check> CheckRefinement(const IdentificationResult& linear, const RefineResult& refined,
                                   const std::string& label, CheckStatus on_bound_status) {
  std::vector<Check> checks = RefinedParameterChecks(linear, refined, label);
  Append(&checks, EffectChecks(refined, label, on_bound_status));
  Append(&checks, CheckRelativeError(refined.relative_error_pct, label, /*held_out=*/false));
  return checks;
}

void ExcuseLinearErrorTheRefinementExplains(const IdentificationResult& linear, const RefineResult& refined,
                                            std::vector<Check>* checks) {
  for (const std::optional<double>& e : refined.relative_error_pct)
    if (e && !(*e <= 100.0)) return;  // above 100 % or not finite: the refined model does not explain it either
  for (const std::optional<double>& e : linear.relative_error_pct)
    if (e && !std::isfinite(*e)) return;  // a failure of the computation, not of the model
  const std::string refined_errors = RelativeErrorList(refined.relative_error_pct, -HUGE_VAL);
  const std::string linear_above = RelativeErrorList(linear.relative_error_pct, 100.0);
  if (refined_errors.empty() || linear_above.empty()) return;
  const Check above = CheckRelativeError(linear.relative_error_pct, "linear", /*held_out=*/false).front();
  for (Check& check : *checks)
    if (check.name == above.name && check.status == CheckStatus::kError && check.message == above.message)
      check = {check.name, CheckStatus::kWarning,
               "linear: relative error above 100 % (" + linear_above +
                   "): the linear model lacks what the refined effects supply (refined: " + refined_errors + ")"};
}

bool HoldsAtHalfCutoff(const Eigen::VectorXd& at_cutoff, const Eigen::VectorXd& at_half,
                       const Eigen::VectorXd& at_half_std) {
  bool holds = at_half.size() == at_cutoff.size() && at_half_std.size() == at_half.size();
  for (Eigen::Index k = 0; holds && k < at_half.size(); ++k)
    holds = std::abs(at_half[k]) >= 3.0 * at_half_std[k] && std::abs(at_half[k]) >= 0.5 * std::abs(at_cutoff[k]);
  return holds;
}

std::vector<Check> CheckTimingAtHalfCutoff(const IdentificationResult& linear, const IdentifyOptions& identify,
                                           const RefineResult& refined, const RefineOptions& options) {
  // Only a significant estimate can fail to hold: a delay and a lag refined together without the data
  // to tell them apart have stds of hundreds of ms at the cut-off already.
  std::vector<EffectKind> checked;
  for (EffectKind kind : refined.enabled) {
    const Eigen::ArrayXd value = refined.effects.Get(kind).array().abs();
    if (kind->info().checked_at_half_cutoff && value.maxCoeff() > 0.0 &&
        (value >= 3.0 * refined.effects_std.Get(kind).array()).all())
      checked.push_back(kind);
  }
  if (checked.empty()) return {};
  const char* kName = "timing_at_half_cutoff";
  const ButterworthOptions& filter = identify.observation.filter;
  const ButterworthOptions half{filter.order, FilterBand::kLowPass, 0.5 * filter.cutoff_hz, 0.0};
  std::vector<ProcessedFlight> flights;
  for (const ProcessedFlight& flight : linear.flights)
    flights.push_back(LowPassFurther(flight, half, identify.observation.source));
  RefineOptions again = options;
  again.effects = refined.enabled;
  again.initial = refined.effects;
  again.coarse_delay_search = false;
  RefineResult at_half;
  try {
    at_half = Refine(IdentifyProcessed(std::move(flights), identify), again);
  } catch (const Error& e) {
    return {{kName, CheckStatus::kWarning,
             "the timing effects were not checked at half the cut-off (" + std::string(e.what()) + ")"}};
  }
  std::string held, failed;
  for (EffectKind kind : checked) {
    const Eigen::VectorXd value = at_half.effects.Get(kind), std_dev = at_half.effects_std.Get(kind);
    std::ostringstream both;
    both << kind->parameter_name() << " = " << kind->Format(refined.effects.Get(kind), refined.effects_std.Get(kind))
         << " at the " << filter.cutoff_hz << " Hz cut-off, " << kind->Format(value, std_dev) << " at "
         << half.cutoff_hz << " Hz";
    std::string& list = HoldsAtHalfCutoff(refined.effects.Get(kind), value, std_dev) ? held : failed;
    list += (list.empty() ? "" : "; ") + both.str();
  }
  if (!failed.empty())
    return {{kName, CheckStatus::kWarning,
             failed + ": what it fits lies between the two cut-offs, where the rotor signal of a closed-loop "
                      "flight follows the controller's reply to sensor noise, not the motors' timing"}};
  return {{kName, CheckStatus::kOk, "holds at half the low-pass cut-off (" + held + ")"}};
}

std::vector<Check> CheckDelay(const IdentificationResult& linear, const DelayEstimate& estimate,
                              const DelayOptions& options) {
  std::vector<Check> checks = RefinedParameterChecks(linear, estimate.refined, "delay");
  if (!std::isfinite(estimate.delay_s) || !std::isfinite(estimate.delay_std_s) ||
      !std::isfinite(estimate.motor_tau_s) || !std::isfinite(estimate.motor_tau_std_s))
    checks.push_back({"effects_finite", CheckStatus::kError, "delay: the delay or its std is NaN or inf"});
  if (OnBound(estimate.delay_s, options.search.min_s, options.search.max_s))
    checks.push_back({"effects_on_bounds", CheckStatus::kError,
                      "delay: " + std::to_string(1000.0 * estimate.delay_s) +
                          " ms is on the edge of the searched range: widen --min-s/--max-s"});
  else
    checks.push_back({"effects_on_bounds", CheckStatus::kOk, "delay: inside the searched range"});
  return checks;
}

}  // namespace rotorid

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
  const CheckedParameters parameters = CheckedFromRefinement(linear, refined);
  std::vector<Check> checks = CheckParameters(parameters, linear.system.config_names, label);
  if (refined.rank_deficient) {
    const std::string names = Join(refined.confounded);
    checks.push_back({"refined_identifiable", CheckStatus::kWarning,
                      label + ": the refined parameters are not jointly identifiable (confounded: " + names +
                          "), so no std is reported; refine fewer effects (rotorid ablate compares subsets)"});
  }
  // The refined block's essential parameters come from the re-selection on corrected rows; its own
  // covariance can then put one above the %sigma limit the selection applies. Refine discards kd and
  // the diagonal inertia by that rule (NanoBench B3+B5+B10 with rotor drag and motor lag: I_xx and I_yy
  // at 31 and 32 %); a first moment or product of inertia would be held at 0, which changes the model,
  // so it stays essential: said, not hidden.
  std::string above_limit;
  const double limit = linear.options.tls.max_rel_std_pct;
  if (refined.has_covariance && refined.refined.method == TlsMethod::kNoiseAware)
    for (int k = 0; k < linear.system.num_parameters(); ++k)
      if (refined.refined.essential[k] && refined.refined.rel_std_pct[k] > limit)
        above_limit += (above_limit.empty() ? "" : ", ") + linear.system.parameter_names[k] + " " +
                       ShortNumber(refined.refined.rel_std_pct[k]) + " %";
  if (!above_limit.empty())
    checks.push_back({"refined_identifiable", CheckStatus::kWarning,
                      label + ": essential with a relative std above the selection's " + ShortNumber(limit) +
                          " % limit (" + above_limit +
                          "): kept by the re-selection on the corrected rows, known to this std only"});
  for (const std::string& pair : refined.resting_on_discarded)
    checks.push_back({"refined_identifiable", CheckStatus::kWarning,
                      label + ": " + pair.substr(0, pair.find(" ~ ")) + " is confounded with " +
                          pair.substr(pair.find(" ~ ") + 3) +
                          ", which the essential selection holds at 0: its value assumes that parameter is 0, "
                          "and its std does not include that assumption"});
  return checks;
}

// The relative-error part of ExcuseLinearErrorsTheRefinementExplains.
void ExcuseLinearRelativeError(const IdentificationResult& linear, const RefineResult& refined,
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

}  // namespace

CheckedParameters CheckedFromRefinement(const IdentificationResult& linear, const RefineResult& refined) {
  CheckedParameters parameters = CheckedFromSolution(linear, refined.refined);
  if (!refined.has_covariance) {
    parameters.std.clear();
    parameters.predicts_with_std.clear();
    parameters.profiled_std.clear();
    parameters.covariance_names.clear();
  }
  return parameters;
}

std::vector<Check> CheckRefinement(const IdentificationResult& linear, const RefineResult& refined,
                                   const std::string& label, CheckStatus on_bound_status) {
  std::vector<Check> checks = RefinedParameterChecks(linear, refined, label);
  Append(&checks, EffectChecks(refined, label, on_bound_status));
  Append(&checks, CheckRelativeError(refined.relative_error_pct, label, /*held_out=*/false));
  return checks;
}

void ExcuseLinearErrorsTheRefinementExplains(const IdentificationResult& linear, const RefineResult& refined,
                                             std::vector<Check>* checks) {
  ExcuseLinearParameterErrors(
      CheckParameters(CheckedFromSolution(linear, linear.solution), linear.system.config_names, "linear"),
      RefinedParameterChecks(linear, refined, "refined"), checks);
  ExcuseLinearRelativeError(linear, refined, checks);
}

ButterworthOptions HalfCutoff(const ButterworthOptions& filter) {
  return {filter.order, FilterBand::kLowPass, 0.5 * filter.cutoff_hz, 0.0};
}

IdentificationResult IdentifyAtHalfCutoff(const IdentificationResult& full, const IdentifyOptions& identify) {
  std::vector<ProcessedFlight> flights;
  for (const ProcessedFlight& flight : full.flights)
    flights.push_back(LowPassFurther(flight, HalfCutoff(identify.observation.filter), identify.observation.source));
  return IdentifyProcessed(std::move(flights), identify);
}

HalfCutoffComparison CompareAtHalfCutoff(EffectKind kind, const RefineResult& at_cutoff, const RefineResult& at_half,
                                         double cutoff_hz) {
  const Eigen::VectorXd full_value = at_cutoff.effects.Get(kind);
  const Eigen::VectorXd value = at_half.effects.Get(kind), std_dev = at_half.effects_std.Get(kind);
  HalfCutoffComparison out;
  out.holds = value.size() == full_value.size() && std_dev.size() == value.size();
  for (Eigen::Index k = 0; out.holds && k < value.size(); ++k)
    out.holds = std::abs(value[k]) >= 3.0 * std_dev[k] && std::abs(value[k]) >= 0.5 * std::abs(full_value[k]);
  std::ostringstream both;
  both << kind->Format(full_value, at_cutoff.effects_std.Get(kind)) << " at the " << cutoff_hz << " Hz cut-off, "
       << kind->Format(value, std_dev) << " at " << 0.5 * cutoff_hz << " Hz";
  out.values = both.str();
  return out;
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
  RefineOptions again = options;
  again.effects = refined.enabled;
  again.initial = refined.effects;
  again.coarse_delay_search = false;
  RefineResult at_half;
  try {
    at_half = Refine(IdentifyAtHalfCutoff(linear, identify), again);
  } catch (const Error& e) {
    return {{kName, CheckStatus::kWarning,
             "the timing effects were not checked at half the cut-off (" + std::string(e.what()) + ")"}};
  }
  std::string held, failed;
  for (EffectKind kind : checked) {
    const HalfCutoffComparison comparison =
        CompareAtHalfCutoff(kind, refined, at_half, identify.observation.filter.cutoff_hz);
    std::string& list = comparison.holds ? held : failed;
    list += (list.empty() ? "" : "; ") + kind->parameter_name() + " = " + comparison.values;
  }
  if (!failed.empty())
    return {{kName, CheckStatus::kWarning, failed + ": " + kBetweenTheCutoffs + ", not the motors' timing"}};
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

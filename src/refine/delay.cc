#include "rotorid/refine/delay.h"

#include <algorithm>
#include <cmath>

#include "refine/grid_search.h"
#include "rotorid/core/error.h"

namespace rotorid {

EffectKind DelayEffect() {
  static const EffectKind kind = ParseEffectKind("delay");
  return kind;
}

std::string DelayOptions::Validate() const {
  if (const std::string problem = search.Validate(); !problem.empty()) return problem;
  if (num_threads < 1) return "num_threads must be at least 1";
  return {};
}

std::vector<double> DelayCriterionCurve(const IdentificationResult& linear, const std::vector<double>& delays_s,
                                        int num_threads) {
  return internal::CriterionOverGrid(linear, Effects{}, DelayEffect(), delays_s, num_threads);
}

namespace {

// The refinement EstimateDelay runs from the best grid point.
RefineOptions DelayRefinement(const DelayOptions& options, double start_s) {
  RefineOptions refine;
  refine.effects = {DelayEffect()};
  if (options.with_motor_lag) refine.effects.push_back(ParseEffectKind("motor_lag"));
  refine.coarse_delay_search = false;
  refine.delay_search = options.search;  // which bounds the delay
  refine.initial.Set(DelayEffect(), start_s);
  refine.num_threads = options.num_threads;
  return refine;
}

}  // namespace

int DelaySteps(const DelayOptions& options) { return 1 + RefineSteps(DelayRefinement(options, 0.0)); }

DelayEstimate EstimateDelay(const IdentificationResult& linear, const DelayOptions& options,
                            const StepProgress& progress) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  DelayEstimate out;
  out.grid_s = options.search.Grid();
  out.criterion = DelayCriterionCurve(linear, out.grid_s, options.num_threads);
  const size_t best = std::min_element(out.criterion.begin(), out.criterion.end()) - out.criterion.begin();
  out.grid_best_s = out.grid_s[best];
  if (best == 0 || best + 1 == out.grid_s.size())
    out.warnings.push_back("the best delay lies at the edge of the searched range [" +
                           std::to_string(options.search.min_s) + ", " + std::to_string(options.search.max_s) +
                           "] s; widen it");
  const RefineOptions refine = DelayRefinement(options, out.grid_best_s);
  const EffectKind lag = ParseEffectKind("motor_lag");
  const int total_steps = DelaySteps(options);
  if (progress) progress(1, total_steps);
  out.refined = Refine(linear, refine, OffsetProgress(progress, 1, total_steps));
  out.delay_s = out.refined.effects.Scalar(DelayEffect());
  out.delay_std_s = out.refined.effects_std.Scalar(DelayEffect());
  out.motor_tau_s = out.refined.effects.Scalar(lag);
  out.motor_tau_std_s = out.refined.effects_std.Scalar(lag);
  // The refinement must stay in the basin the global search found.
  if (std::abs(out.delay_s - out.grid_best_s) > 3 * options.search.step_s)
    out.warnings.push_back("the refined delay moved " + std::to_string(1000 * (out.delay_s - out.grid_best_s)) +
                           " ms away from the best grid point; the criterion may have several minima");
  out.warnings.insert(out.warnings.end(), out.refined.warnings.begin(), out.refined.warnings.end());
  return out;
}

}  // namespace rotorid

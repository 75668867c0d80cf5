#include "rotorid/refine/ablate.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>

#include "core/parallel_for.h"
#include "rotorid/core/error.h"

namespace rotorid {

AblationResult Ablate(const IdentificationResult& linear, const std::vector<ProcessedFlight>& held_out,
                      const std::vector<EffectKind>& effects, const RefineOptions& base, int num_threads,
                      const std::function<void(int done, int total)>& on_done) {
  if (effects.size() > 8) throw Error("ablation over more than 8 effects (256 refinements) is not supported");
  if (const std::string problem = base.Validate(); !problem.empty()) throw Error(problem);
  const int subsets = 1 << effects.size();
  // Every subset with a grid-searched effect (the delay) would start from the same global search:
  // do it once.
  RefineOptions shared = base;
  if (shared.coarse_delay_search) {
    for (EffectKind kind : effects)
      if (kind->info().grid_searched) shared.initial.Set(kind, CoarseDelaySearch(linear, base, kind));
    shared.coarse_delay_search = false;
  }
  AblationResult out;
  out.entries.resize(subsets);
  std::atomic<int> done{0};
  std::mutex progress_mutex;
  internal::ParallelFor(subsets, num_threads, [&](int s) {
    {
      AblationEntry& entry = out.entries[s];
      for (size_t k = 0; k < effects.size(); ++k)
        if (s & (1 << k)) entry.effects.push_back(effects[k]);
      RefineOptions options = shared;
      options.effects = entry.effects;
      // Subsets without a searched effect keep it at the caller's initial value, not the search's.
      for (EffectKind kind : effects)
        if (!options.Enabled(kind)) options.initial.Set(kind, base.initial.Get(kind));
      options.num_threads = 1;
      options.compute_covariance = false;
      entry.result = Refine(linear, options);
      const auto values = NamedParameters(linear.system, PredictionChi(entry.result.refined));
      entry.relative_error_pct = entry.result.relative_error_pct;
      if (!held_out.empty())
        entry.held_out_relative_error_pct = RelativeErrorWithEffects(held_out, values, entry.result.effects);
      int free = 0;
      for (bool e : linear.solution.essential) free += e;
      // A zero-sum effect's sum is pinned: one free value fewer.
      for (EffectKind k : entry.effects) free += k->FreeDimension(linear.flights.front().vehicle);
      entry.num_parameters = free;
    }
    const int finished = ++done;
    if (on_done) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      on_done(finished, subsets);
    }
  });

  // Information criteria on the whitened residuals, with the sample count divided by the
  // autocorrelation factor of the fit with every candidate effect (the least misspecified one: the
  // effect-free residual's memory is mostly the missing effects'), so that every subset is charged
  // alike. The residuals are whitened by the linear step's weights and metric for every subset
  // (refined_criterion): each refinement's own final cost is not comparable across subsets, since
  // re-running the TLS on effect-corrected rows re-estimates the weights.
  const double rows = static_cast<double>(linear.system.num_rows());
  const double factor = std::max(1.0, out.entries.back().result.autocorrelation_factor);
  out.effective_samples = rows / factor;
  for (AblationEntry& entry : out.entries) {
    const double mean_square = std::max(entry.result.refined_criterion, 1e-300);
    const double log_term = out.effective_samples * std::log(mean_square);
    entry.aic = log_term + 2.0 * entry.num_parameters;
    entry.bic = log_term + entry.num_parameters * std::log(out.effective_samples);
  }
  return out;
}

}  // namespace rotorid

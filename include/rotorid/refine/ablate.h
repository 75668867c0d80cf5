#pragma once

// Ablation study: the refinement with every subset of a set of effects, each judged on the
// identification flights and on held-out flights, with information criteria.

#include <functional>
#include <optional>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

struct AblationEntry {
  std::vector<EffectKind> effects;
  RefineResult result;
  std::vector<std::optional<double>> relative_error_pct;           // identification flights
  std::vector<std::optional<double>> held_out_relative_error_pct;  // empty without held-out flights
  int num_parameters = 0;   // free chi entries plus effect parameters
  double aic = 0.0;         // on the whitened residuals, with the effective sample size
  double bic = 0.0;
};

struct AblationResult {
  std::vector<AblationEntry> entries;  // in order of subsets: {}, {e1}, {e2}, {e1,e2}, ...
  double effective_samples = 0.0;
};

// `base` supplies the refinement settings; its effects list is replaced per subset. Subsets run
// on `num_threads` threads. `on_done` (optional) is called after each subset (progress).
AblationResult Ablate(const IdentificationResult& linear, const std::vector<ProcessedFlight>& held_out,
                      const std::vector<EffectKind>& effects, const RefineOptions& base, int num_threads,
                      const std::function<void(int done, int total)>& on_done = nullptr);

}  // namespace rotorid

#pragma once

// Internal: the one grid search of the criterion over a scalar effect (the delay's coarse search
// in refine, delay and diagnose, and the diagnosis' grid screening).

#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/model/effects.h"

namespace rotorid::internal {

// min, min + step, ... up to max (inclusive to round-off), accumulated as every caller did.
std::vector<double> SearchGrid(double min, double max, double step);

// The TLS criterion (EffectCriterion) with `kind` at each grid value and the other effects at
// `base`, the grid split over `threads`.
std::vector<double> CriterionOverGrid(const IdentificationResult& linear, const Effects& base, EffectKind kind,
                                      const std::vector<double>& grid, int threads);

}  // namespace rotorid::internal

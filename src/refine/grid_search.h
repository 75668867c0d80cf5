#pragma once

// Internal: the one grid search of the criterion over a scalar effect (the delay's coarse search
// in refine, delay and diagnose, and the diagnosis' grid screening).

#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/model/effects.h"

namespace rotorid::internal {

// The system's `columns` (in that order) of every flight's rows with `effects`, as the linear
// system lays them out; without the other columns, and without any second copy of them.
Eigen::MatrixXd SystemColumnsWithEffects(const IdentificationResult& linear, const Effects& effects,
                                         const std::vector<int>& columns);

// min, min + step, ... up to max (inclusive to round-off), accumulated as every caller did.
std::vector<double> SearchGrid(double min, double max, double step);

// The TLS criterion (EffectCriterion) with `kind` at each grid value and the other effects at
// `base`, the grid split over `threads`.
std::vector<double> CriterionOverGrid(const IdentificationResult& linear, const Effects& base, EffectKind kind,
                                      const std::vector<double>& grid, int threads);

}  // namespace rotorid::internal

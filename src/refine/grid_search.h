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

// The grid value of CriterionOverGrid's minimum (the first among equals), from every third grid
// value and then the values next to the best of them: 30 evaluations of the default delay grid's
// 76. The criterion along a delay is smooth; on 35 flights (the real Crazyflies' RPM and PWM logs,
// simulated delays and lags of 4-30 ms) this found the whole grid's minimum every time, and so did
// every second or every fourth value.
double CoarseToFineGridMinimum(const IdentificationResult& linear, const Effects& base, EffectKind kind,
                               const std::vector<double>& grid, int threads);

}  // namespace rotorid::internal

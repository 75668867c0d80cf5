#include "refine/grid_search.h"

#include "refine/parallel_for.h"
#include "rotorid/refine/refine.h"

namespace rotorid::internal {

std::vector<double> SearchGrid(double min, double max, double step) {
  std::vector<double> grid;
  for (double value = min; value <= max + 1e-12; value += step) grid.push_back(value);
  return grid;
}

std::vector<double> CriterionOverGrid(const IdentificationResult& linear, const Effects& base, EffectKind kind,
                                      const std::vector<double>& grid, int threads) {
  std::vector<double> criterion(grid.size(), 0.0);
  ParallelFor(static_cast<int>(grid.size()), threads, [&](int i) {
    Effects trial = base;
    trial.Set(kind, grid[static_cast<size_t>(i)]);
    criterion[static_cast<size_t>(i)] = EffectCriterion(linear, trial);
  });
  return criterion;
}

}  // namespace rotorid::internal

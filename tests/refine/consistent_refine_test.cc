// The refinement on log-Cholesky charts (RefineOptions::consistent_bodies, issue 37) where the truth is
// a body and the flights fix it: configurations A and B of MODEL.md 6 together, simulated. There the
// constrained estimate is the unconstrained one, and the core accuracy stays.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "rotorid/refine/refine.h"
#include "rotorid/sim/presets.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// Seeds 1..N; N from ROTORID_CONSISTENT_SEEDS (docs/physical_consistency.md ran 20), else 2.
int NumSeeds() {
  const char* env = std::getenv("ROTORID_CONSISTENT_SEEDS");
  return env && std::atoi(env) > 0 ? std::atoi(env) : 2;
}

TEST(ConsistentRefineTest, EqualsTheUnconstrainedRefinementWhereTheTruthIsABody) {
  const double seconds = 60.0;
  double worst_move_std = 0.0, worst_kd_pct = 0.0, worst_izz_pct = 0.0;
  for (int seed = 1; seed <= NumSeeds(); ++seed) {
    const SimulationResult a = testing::SimulatePreset("A", seconds, 1000 * seed);
    const SimulationResult b = testing::SimulatePreset("B", seconds, 1000 * seed + 1);
    IdentifyOptions identify;
    identify.allow_partial = true;
    const IdentificationResult linear = Identify({{a.vehicle, a.log, 1.0}, {b.vehicle, b.log, 1.0}}, identify);
    RefineOptions options;
    options.effects = {};
    const RefineResult constrained = Refine(linear, options);
    options.consistent_bodies = false;
    const RefineResult unconstrained = Refine(linear, options);
    const TlsSolution& c = constrained.refined;
    const TlsSolution& u = unconstrained.refined;
    EXPECT_EQ(constrained.body_constraint.charted.size(), 2u) << "seed " << seed;
    for (int k = 0; k < linear.system.num_parameters(); ++k) {
      ASSERT_EQ(c.essential[k], u.essential[k]) << linear.system.parameter_names[k];
      if (!c.essential[k]) continue;
      const double move = std::abs(c.chi[k] - u.chi[k]) / u.std[k];
      worst_move_std = std::max(worst_move_std, move);
      EXPECT_LT(move, 0.1) << linear.system.parameter_names[k] << ", seed " << seed;
    }
    EXPECT_LT(constrained.body_constraint.unconstrained_distance_std, 0.1) << "seed " << seed;
    const auto pct = [&](const std::string& name, double truth) {
      const int k = linear.system.Column(name);
      EXPECT_TRUE(c.essential[k]) << name;
      return 100.0 * std::abs(c.chi[k] / truth - 1.0);
    };
    worst_kd_pct = std::max(worst_kd_pct, pct("kd", a.truth.rotor.kd));
    worst_izz_pct =
        std::max({worst_izz_pct, pct("A.I_zz", a.truth.body.inertia(2, 2)), pct("B.I_zz", b.truth.body.inertia(2, 2))});
  }
  std::printf("over %d seeds: largest constrained - unconstrained %.3g std; kd %.3g %%, I_zz %.3g %%\n", NumSeeds(),
              worst_move_std, worst_kd_pct, worst_izz_pct);
  EXPECT_LT(worst_kd_pct, 1.0);
  EXPECT_LT(worst_izz_pct, 1.0);
}

}  // namespace
}  // namespace rotorid

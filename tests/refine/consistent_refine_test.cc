// The refinement on log-Cholesky charts (RefineOptions::consistent_bodies, issue 37) where the truth is
// a body and the flights fix it: configurations A and B of MODEL.md 6 together, simulated. There the
// constrained estimate is the unconstrained one, and the core accuracy stays.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "rotorid/model/physical_consistency.h"
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

// B alone for 30 s with the bundled flights' 5 ms delay and 20 ms lag left out: kd is discarded and the
// unconstrained refinement's body is none (its profiled I_zz below the triangle inequality); on the
// charts it is one, and the report says how far the unconstrained optimum lies.
TEST(ConsistentRefineTest, AnEstimateThatIsNoBodyEndsOnABody) {
  Effects unmodelled;
  unmodelled.Set("delay_s", 0.005);
  unmodelled.Set("motor_tau_s", 0.02);
  const SimulationResult b = testing::SimulatePreset("B", 30.0, 1, unmodelled);
  IdentifyOptions identify;
  identify.allow_partial = true;
  const IdentificationResult linear = Identify({{b.vehicle, b.log, 1.0}}, identify);
  RefineOptions options;
  options.effects = {};
  const auto body_of = [&](const TlsSolution& s) {
    const Eigen::VectorXd chi = s.chi + s.profiled_chi;
    Eigen::Matrix<double, kNumBodyParameters, 1> values;
    for (int k = 0; k < kNumBodyParameters; ++k) values[k] = chi[linear.system.flight_body_columns[0][k]];
    return BodyParameters::FromVector(values);
  };
  options.consistent_bodies = false;
  const RefineResult unconstrained = Refine(linear, options);
  ASSERT_FALSE(CheckPhysicalConsistency(b.truth.mass_kg, body_of(unconstrained.refined)).consistent);
  options.consistent_bodies = true;
  const RefineResult constrained = Refine(linear, options);
  // Positive definite; the chart's end lies below the check's 1e-9 for flat (consistent_chi.cc).
  EXPECT_TRUE(CheckPhysicalConsistency(b.truth.mass_kg, body_of(constrained.refined), 0.0).consistent)
      << CheckPhysicalConsistency(b.truth.mass_kg, body_of(constrained.refined)).problem;
  EXPECT_EQ(constrained.body_constraint.charted, std::vector<std::string>{"B"});
  EXPECT_GT(constrained.body_constraint.start_distance_std, 0.0);
  EXPECT_GT(constrained.body_constraint.unconstrained_distance_std, 0.0);
  EXPECT_LT(constrained.refined_criterion, 1.1 * unconstrained.refined_criterion);
}

}  // namespace
}  // namespace rotorid

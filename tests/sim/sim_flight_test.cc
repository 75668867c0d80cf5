// Closed-loop flights: safe for any seed, paper-like excitation, determinism, any layout, jitter,
// motion capture, presets, vehicle files with a simulation: mapping, the truth JSON, option checks.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rotorid/core/error.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"
#include "rotorid/sim/truth.h"
#include "sim/sim_test_options.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;

using testing::kOptimisedBuild;
using testing::TestOptions;

SimulationResult Fly(const std::string& preset, SimulationOptions options) {
  const SimulationVehicle vehicle = PresetVehicle(preset);
  return Simulate(vehicle.vehicle, vehicle.parameters, options);
}

Vehicle Ring(const std::string& name, int num_rotors, double radius_m, double mass_kg) {
  Vehicle vehicle;
  vehicle.name = name;
  vehicle.mass_kg = mass_kg;
  for (int i = 0; i < num_rotors; ++i) {
    const double angle = kPi / num_rotors + 2.0 * kPi * i / num_rotors;
    vehicle.rotors.push_back(
        {Eigen::Vector3d(radius_m * std::cos(angle), radius_m * std::sin(angle), 0.0), i % 2 ? -1 : 1});
  }
  return vehicle;
}

void ExpectSafe(const FlightSummary& summary, const std::string& what) {
  EXPECT_LT(summary.max_tilt_deg, 45.0) << what;
  EXPECT_GT(summary.altitude_range_m[0], 0.5) << what;
  EXPECT_LT(summary.altitude_range_m[1], 2.5) << what;
  EXPECT_LT(summary.max_horizontal_distance_m, 10.0) << what;
}

TEST(SimFlightTest, SeveralSeedsNeverCrash) {
  const std::uint64_t num_seeds = kOptimisedBuild ? 4 : 1;
  for (const char* preset : {"A", "B"}) {
    for (std::uint64_t seed = 1; seed <= num_seeds; ++seed) {
      SimulationOptions options = TestOptions(90.0, 2.0);
      options.seed = seed;
      options.effects.Assign("delay_s=0.005");
      options.effects.Assign("motor_tau_s=0.02");
      ExpectSafe(Fly(preset, options).summary, std::string(preset) + " seed " + std::to_string(seed));
    }
  }
}

TEST(SimFlightTest, StaysSafeAtTheLargestAllowedDelayAndLag) {
  SimulationOptions options = TestOptions(90.0, 2.0);
  options.effects.Assign("delay_s=0.05");
  options.effects.Assign("motor_tau_s=0.08");
  for (std::uint64_t seed = 1; seed <= (kOptimisedBuild ? 2u : 1u); ++seed) {
    options.seed = seed;
    ExpectSafe(Fly("B", options).summary, "B seed " + std::to_string(seed));
  }
}

TEST(SimFlightTest, ExcitationLooksLikeTheHandFlownFlights) {
  if (!kOptimisedBuild) GTEST_SKIP() << "statistics of a 60 s flight: checked in optimised builds";
  SimulationOptions options;
  options.duration_s = 60.0;
  const SimulationResult flight = Fly("A", options);
  const FlightSummary& s = flight.summary;
  const double roll_peak = std::max(-s.roll_range_deg[0], s.roll_range_deg[1]);
  const double pitch_peak = std::max(-s.pitch_range_deg[0], s.pitch_range_deg[1]);
  const double yaw_rate_peak = std::max(-s.yaw_rate_range_radps[0], s.yaw_rate_range_radps[1]);
  EXPECT_GT(roll_peak, 15.0);
  EXPECT_LT(roll_peak, 32.0);
  EXPECT_GT(pitch_peak, 8.0);
  EXPECT_LT(pitch_peak, 20.0);
  EXPECT_GT(yaw_rate_peak, 0.5);
  EXPECT_LT(yaw_rate_peak, 1.4);
  const Eigen::VectorXd roll = flight.states.bryant_rad.col(0), pitch = flight.states.bryant_rad.col(1);
  EXPECT_GT(roll.norm(), 1.4 * pitch.norm());  // roll excited more than pitch
  // Angular accelerations of a few rad/s^2 on every axis (identifiability of the inertia).
  EXPECT_GT(s.angular_acceleration_rms_radps2[0], 2.0);
  EXPECT_GT(s.angular_acceleration_rms_radps2[1], 1.0);
  EXPECT_GT(s.angular_acceleration_rms_radps2[2], 0.5);
  // Thrust varies by +-20-30 % (RMS around 10 %).
  EXPECT_GT(s.thrust_rms_variation_pct, 7.0);
  EXPECT_LT(s.thrust_rms_variation_pct, 16.0);
  // The rotors stay within the mixer's [0.3, 1.6] x hover range.
  EXPECT_GE(s.rotor_speed_range_radps[0], 0.3 * flight.controller.hover_speed_radps - 1e-9);
  EXPECT_LE(s.rotor_speed_range_radps[1], 1.6 * flight.controller.hover_speed_radps + 1e-9);
  // The controller's model is wrong by 5-10 %.
  const double kt_error = std::abs(flight.controller.kt / flight.truth.rotor.kt - 1.0);
  EXPECT_GE(kt_error, 0.05 - 1e-12);
  EXPECT_LE(kt_error, 0.10 + 1e-12);
}

TEST(SimFlightTest, SameSeedSameFlightDifferentSeedDifferentFlight) {
  SimulationOptions options = TestOptions(5.0, 1.0);
  options.mocap = true;
  options.jitter_s = 0.0005;
  const SimulationResult first = Fly("B", options), second = Fly("B", options);
  EXPECT_EQ(first.log.t_s, second.log.t_s);
  EXPECT_EQ(first.log.gyro_radps, second.log.gyro_radps);
  EXPECT_EQ(first.log.acc_mps2, second.log.acc_mps2);
  EXPECT_EQ(first.log.rotor_radps, second.log.rotor_radps);
  EXPECT_EQ(first.log.mocap->bryant_rad, second.log.mocap->bryant_rad);
  options.seed = 2;
  const SimulationResult other = Fly("B", options);
  const double roll_difference = (other.states.bryant_rad.col(0) - first.states.bryant_rad.col(0)).norm();
  EXPECT_GT(roll_difference, 0.3 * first.states.bryant_rad.col(0).norm());
}

TEST(SimFlightTest, HexaAndOctoFly) {
  for (const Vehicle& vehicle : {Ring("hexa", 6, 0.3, 2.1), Ring("octo", 8, 0.4, 3.5)}) {
    SimulationOptions options = TestOptions(20.0, 1.5);
    options.hover_lead_in_s = 0.0;
    options.effects.Assign("motor_tau_s=0.03");
    const SimulationResult flight = Simulate(vehicle, DeriveSimulationParameters(vehicle), options);
    ExpectSafe(flight.summary, vehicle.name);
    EXPECT_EQ(flight.log.num_rotors(), vehicle.num_rotors());
    // Excited like the quads (the references fade in over 2 s, longer than Debug builds fly).
    if (kOptimisedBuild) {
      EXPECT_GT(flight.summary.angular_acceleration_rms_radps2[0], 1.0) << vehicle.name;
    }
  }
}

TEST(SimFlightTest, RefusesALayoutWithoutYawControl) {
  Vehicle same_spin = Ring("S", 4, 0.2, 1.0);
  for (Rotor& rotor : same_spin.rotors) rotor.spin = 1;
  SimulationOptions options;
  options.duration_s = 1.0;
  EXPECT_THROW(Simulate(same_spin, DeriveSimulationParameters(same_spin), options), Error);
}

TEST(SimFlightTest, JitteredSamplesKeepIncreasingAndAreLoggedWhereTaken) {
  SimulationOptions options = TestOptions(10.0, 2.0);
  options.jitter_s = 0.0008;  // 0.16 of the 5 ms interval
  const SimulationResult flight = Fly("A", options);
  const Eigen::VectorXd& t = flight.log.t_s;
  double sum_sq = 0.0;
  for (Eigen::Index i = 0; i < t.size(); ++i) {
    if (i > 0) {
      ASSERT_GT(t[i], t[i - 1]);
    }
    sum_sq += std::pow(t[i] - i / options.log_rate_hz, 2);
  }
  EXPECT_NEAR(std::sqrt(sum_sq / t.size()), options.jitter_s, 0.1 * options.jitter_s);
  EXPECT_EQ(flight.states.t_s, t);
}

TEST(SimFlightTest, MotionCaptureFollowsThePoseWithItsNoise) {
  SimulationOptions options = TestOptions(20.0, 2.0);
  options.mocap = true;
  const SimulationResult flight = Fly("A", options);
  ASSERT_TRUE(flight.log.mocap.has_value());
  const Eigen::MatrixX3d position_error = flight.log.mocap->position_w_m - flight.states.position_w_m;
  const Eigen::MatrixX3d angle_error = flight.log.mocap->bryant_rad - flight.states.bryant_rad;
  const double n = flight.log.num_samples();
  EXPECT_NEAR(std::sqrt(position_error.squaredNorm() / (3 * n)), 0.5e-3, 0.05e-3);
  EXPECT_NEAR(std::sqrt(angle_error.squaredNorm() / (3 * n)), 0.002, 0.0002);
  // Yaw is continuous (unwrapped), as a differentiable signal must be.
  for (int i = 1; i < flight.log.num_samples(); ++i)
    ASSERT_LT(std::abs(flight.log.mocap->bryant_rad(i, 2) - flight.log.mocap->bryant_rad(i - 1, 2)), 0.1);
}

TEST(SimFlightTest, LogCarriesGravityAndMetadataButNotTheEffects) {
  SimulationOptions options = TestOptions(1.0, 1.0);
  options.gravity_mps2 = 9.81;
  options.effects.Assign("delay_s=0.01");
  const SimulationResult flight = Fly("A", options);
  EXPECT_EQ(flight.log.gravity_mps2, 9.81);
  EXPECT_EQ(flight.log.metadata.at("gravity"), "9.81");
  EXPECT_EQ(flight.log.metadata.at("seed"), "1");
  EXPECT_EQ(flight.log.metadata.at("noise"), "pixhawk");
  for (const auto& [key, value] : flight.log.metadata) EXPECT_EQ(key.find("delay"), std::string::npos) << key;
  EXPECT_EQ(flight.log.num_samples(), 200);
}

TEST(SimPresetTest, BIsAPlusTwoPointMassesExactly) {
  const SimulationVehicle a = PresetVehicle("A"), b = PresetVehicle("B");
  EXPECT_EQ(a.vehicle.name, "A");
  EXPECT_EQ(b.vehicle.name, "B");
  EXPECT_DOUBLE_EQ(b.vehicle.mass_kg, 1.452);
  EXPECT_DOUBLE_EQ(b.parameters.mass_kg, 1.452);
  BodyParameters expected = AddPointMass(a.parameters.body, 0.125, Eigen::Vector3d(0.375, 0.0, -0.04));
  expected = AddPointMass(expected, 0.042, Eigen::Vector3d(0.0, -0.43, -0.04));
  EXPECT_EQ(b.parameters.body.ToVector(), expected.ToVector());
  EXPECT_DOUBLE_EQ(a.parameters.body.inertia(0, 2), -4e-5);
  EXPECT_DOUBLE_EQ(a.parameters.rotor.kt, 3.6e-6);
  EXPECT_DOUBLE_EQ(a.vehicle.rotors[0].position_m.y(), -0.225);
  EXPECT_EQ(a.vehicle.rotors[2].spin, -1);
  EXPECT_THROW(PresetVehicle("C"), Error);
}

TEST(SimPresetTest, VehicleFileSimulationMappingSetsTheTruth) {
  const std::string yaml = R"(name: Q
mass: 1.5
rotors:
  - {position: [0.2, 0.2, 0], spin: +1}
  - {position: [-0.2, -0.2, 0], spin: +1}
  - {position: [0.2, -0.2, 0], spin: -1}
  - {position: [-0.2, 0.2, 0], spin: -1}
simulation:
  kt: 4.0e-6
  kd: 6.0e-8
  ms: [0.001, -0.002, -0.008]
  inertia: [0.02, 0.021, 0.035, 1.0e-5, -2.0e-5, 3.0e-5]
)";
  const SimulationVehicle q = ParseSimulationVehicle(yaml, "q.yaml");
  EXPECT_EQ(q.vehicle.name, "Q");
  EXPECT_DOUBLE_EQ(q.parameters.rotor.kt, 4.0e-6);
  EXPECT_DOUBLE_EQ(q.parameters.rotor.kd, 6.0e-8);
  EXPECT_DOUBLE_EQ(q.parameters.body.first_moment.z(), -0.008);
  EXPECT_DOUBLE_EQ(q.parameters.body.inertia(1, 2), 3.0e-5);
  EXPECT_DOUBLE_EQ(q.parameters.body.inertia(2, 1), 3.0e-5);
  EXPECT_NE(q.parameters_source.find("simulation: mapping"), std::string::npos);

  const std::string without = yaml.substr(0, yaml.find("simulation:"));
  const SimulationVehicle derived = ParseSimulationVehicle(without, "plain.yaml");
  EXPECT_NE(derived.parameters_source.find("derived"), std::string::npos);
  EXPECT_GT(derived.parameters.rotor.kt, 0.0);
  ExpectSafe(Simulate(derived.vehicle, derived.parameters, TestOptions(5.0, 1.0)).summary, "derived X quad");

  EXPECT_THROW(ParseSimulationVehicle(without + "simulation: {kt: -1}\n", "bad.yaml"), Error);
  EXPECT_THROW(ParseSimulationVehicle(without + "simulation: {inertia: [1, 2]}\n", "bad.yaml"), Error);
  EXPECT_THROW(ParseSimulationVehicle(without + "simulation: {kz: 1}\n", "bad.yaml"), Error);
}

TEST(SimTruthTest, TruthJsonRoundTrips) {
  SimulationOptions options = TestOptions(1.0, 0.5);
  options.seed = 17;
  options.effects.Assign("motor_tau_s=0.02");
  options.effects.Assign("gyro_bias=0.01,-0.02,0.03");
  const SimulationResult flight = Fly("B", options);
  const SimulationTruth truth = ParseTruthJson(TruthToJson(flight), "truth.json");
  EXPECT_EQ(truth.vehicle_name, "B");
  EXPECT_EQ(truth.seed, 17u);
  EXPECT_EQ(truth.noise_preset, "pixhawk");
  EXPECT_DOUBLE_EQ(truth.parameters.mass_kg, 1.452);
  EXPECT_EQ(truth.parameters.body.ToVector(), flight.truth.body.ToVector());
  EXPECT_EQ(truth.parameters.rotor.kt, flight.truth.rotor.kt);
  EXPECT_EQ(truth.effects.Scalar("motor_tau_s"), 0.02);
  EXPECT_EQ(truth.effects.Get("gyro_bias"), options.effects.Get("gyro_bias"));
  EXPECT_THROW(ParseTruthJson("{\"vehicle\": \"B\"}", "t.json"), Error);
}

TEST(SimOptionsTest, ValidateNamesTheViolatedConstraint) {
  auto problem = [](auto edit) {
    SimulationOptions options;
    edit(options);
    return options.Validate();
  };
  EXPECT_EQ(problem([](SimulationOptions&) {}), "");
  EXPECT_NE(problem([](SimulationOptions& o) { o.duration_s = -1; }).find("duration"), std::string::npos);
  EXPECT_NE(problem([](SimulationOptions& o) { o.log_rate_hz = 10; }).find("rate"), std::string::npos);
  EXPECT_NE(problem([](SimulationOptions& o) { o.physics_rate_hz = 500; }).find("physics"), std::string::npos);
  EXPECT_NE(problem([](SimulationOptions& o) { o.effects.Set("delay_s", 0.5); }).find("delay_s"), std::string::npos);
  EXPECT_NE(problem([](SimulationOptions& o) { o.effects.Set("motor_tau_s", -0.1); }).find("motor_tau_s"),
            std::string::npos);
  EXPECT_NE(problem([](SimulationOptions& o) { o.jitter_s = 0.01; }).find("jitter"), std::string::npos);
  EXPECT_NE(problem([](SimulationOptions& o) { o.noise.acc_std_mps2 = -1; }).find("noise"), std::string::npos);
  EXPECT_THROW(NoiseLevels::Preset("loud"), Error);
  SimulationOptions bad;
  bad.duration_s = 0.0;
  EXPECT_THROW(Fly("A", bad), Error);
}

}  // namespace
}  // namespace rotorid

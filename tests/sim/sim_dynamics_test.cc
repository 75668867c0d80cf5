// The simulator's equations of motion: conservation in torque-free motion, RK4's order, hover
// trim, motor lag, and the portable random numbers.

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/sim/dynamics.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/random.h"
#include "rotorid/sim/simulator.h"
#include "sim/sim_test_options.h"

namespace rotorid {
namespace {

using testing::TestSeconds;

constexpr double kPi = 3.14159265358979323846;

// Configuration B's body: full inertia tensor with products, centre of mass well away from O_d.
VehicleParameters AsymmetricBody() { return PresetVehicle("B").parameters; }

SimState SpinningAboutNonPrincipalAxis() {
  SimState state;
  state.position_w_m = Eigen::Vector3d(1.0, -2.0, 3.0);
  state.velocity_w_mps = Eigen::Vector3d(0.3, -0.2, 0.1);
  state.attitude_wb = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, -1).normalized()));
  state.angular_velocity_b_radps = Eigen::Vector3d(2.0, -1.0, 3.0);
  return state;
}

double RelativeChange(const Eigen::Vector3d& before, const Eigen::Vector3d& after) {
  return (after - before).norm() / before.norm();
}

TEST(SimDynamicsTest, TorqueFreeRotationConservesMomentumAndEnergy) {
  const VehicleParameters body = AsymmetricBody();
  const SimState initial = SpinningAboutNonPrincipalAxis();
  // The axis is not principal: the angular velocity itself must change (tumbling) ...
  const Eigen::Vector3d w = initial.angular_velocity_b_radps;
  ASSERT_GT((body.body.inertia * w).normalized().cross(w.normalized()).norm(), 0.05);
  const SimState final_state = IntegrateFreeBody(body.mass_kg, body.body, initial, TestSeconds(3.0, 0.5), 1.0 / 2000.0);
  EXPECT_GT((final_state.angular_velocity_b_radps - w).norm(), 0.1);
  // ... while momentum and energy stay.
  const double h_change = RelativeChange(AngularMomentumWorld(body.mass_kg, body.body, initial),
                                         AngularMomentumWorld(body.mass_kg, body.body, final_state));
  const double p_change = RelativeChange(LinearMomentumWorld(body.mass_kg, body.body, initial),
                                         LinearMomentumWorld(body.mass_kg, body.body, final_state));
  const double t_before = KineticEnergy(body.mass_kg, body.body, initial);
  const double t_change = std::abs(KineticEnergy(body.mass_kg, body.body, final_state) - t_before) / t_before;
  RecordProperty("angular_momentum_rel_change", std::to_string(h_change));
  RecordProperty("kinetic_energy_rel_change", std::to_string(t_change));
  EXPECT_LT(h_change, 1e-9);
  EXPECT_LT(p_change, 1e-9);
  EXPECT_LT(t_change, 1e-9);
  EXPECT_NEAR(final_state.attitude_wb.norm(), 1.0, 1e-12);
}

TEST(SimDynamicsTest, TorqueFreeRotationWithCentreOfMassAtOriginAlsoConserves) {
  VehicleParameters body = PresetVehicle("A").parameters;
  body.body.first_moment.setZero();
  SimState initial = SpinningAboutNonPrincipalAxis();
  initial.velocity_w_mps.setZero();
  const SimState final_state = IntegrateFreeBody(body.mass_kg, body.body, initial, TestSeconds(3.0, 0.5), 1.0 / 2000.0);
  EXPECT_LT(RelativeChange(AngularMomentumWorld(body.mass_kg, body.body, initial),
                           AngularMomentumWorld(body.mass_kg, body.body, final_state)),
            1e-9);
  // With ms = 0, O_d is the centre of mass and stays put.
  EXPECT_LT((final_state.position_w_m - initial.position_w_m).norm(), 1e-12);
}

TEST(SimDynamicsTest, Rk4IsFourthOrder) {
  const VehicleParameters body = AsymmetricBody();
  const SimState initial = SpinningAboutNonPrincipalAxis();
  const double duration = TestSeconds(1.0, 0.1);
  const SimState reference = IntegrateFreeBody(body.mass_kg, body.body, initial, duration, 1.0 / 8000.0);
  auto error = [&](double step) {
    const SimState s = IntegrateFreeBody(body.mass_kg, body.body, initial, duration, step);
    return (s.angular_velocity_b_radps - reference.angular_velocity_b_radps).norm();
  };
  const double ratio = error(1.0 / 250.0) / error(1.0 / 500.0);
  EXPECT_GT(ratio, 12.0);  // 16 for a fourth-order method
  EXPECT_LT(ratio, 20.0);
}

Vehicle Hexa() {
  Vehicle hexa;
  hexa.name = "H";
  hexa.mass_kg = 2.1;
  for (int i = 0; i < 6; ++i) {
    const double angle = kPi / 6.0 + i * kPi / 3.0;
    hexa.rotors.push_back({Eigen::Vector3d(0.3 * std::cos(angle), 0.3 * std::sin(angle), 0.0), i % 2 ? -1 : 1});
  }
  return hexa;
}

TEST(SimDynamicsTest, HoverRotorSpeedsHoldTheVehicleStill) {
  std::vector<std::pair<Vehicle, VehicleParameters>> cases;
  for (const char* name : {"A", "B"}) {
    const SimulationVehicle preset = PresetVehicle(name);
    cases.emplace_back(preset.vehicle, preset.parameters);
  }
  cases.emplace_back(Hexa(), DeriveSimulationParameters(Hexa()));
  for (const auto& [vehicle, parameters] : cases) {
    const Eigen::VectorXd hover = HoverRotorSpeeds(vehicle, parameters, kStandardGravity);
    const MultirotorDynamics dynamics(vehicle, parameters, kStandardGravity, 0.0);
    const BodyAcceleration acc = dynamics.Accelerations(0.0, SimState(), hover);
    EXPECT_LT((acc.specific_force_b_mps2 - Eigen::Vector3d(0, 0, kStandardGravity)).norm(), 1e-12) << vehicle.name;
    EXPECT_LT(acc.angular_acceleration_b_radps2.norm(), 1e-12) << vehicle.name;
  }
  // Configuration A hovers near the paper's 930 rad/s.
  const SimulationVehicle a = PresetVehicle("A");
  EXPECT_NEAR(HoverRotorSpeeds(a.vehicle, a.parameters, kStandardGravity).mean(), 935.0, 15.0);
}

// An external force enters the wrench at O_d as [R^T F; 0] (so the accelerometer sees it), and its
// horizontal part turns about z: a quarter period turns +x into +y.
TEST(SimDynamicsTest, ExternalForceTurnsInTheWorldAndEntersTheWrenchAtTheOrigin) {
  const SimulationVehicle a = PresetVehicle("A");
  const Eigen::VectorXd hover = HoverRotorSpeeds(a.vehicle, a.parameters, kStandardGravity);
  ExternalForce force;
  force.world_n = Eigen::Vector3d(0.5, 0.0, -0.2);
  force.turn_period_s = 8.0;
  EXPECT_LT((force.At(2.0) - Eigen::Vector3d(0.0, 0.5, -0.2)).norm(), 1e-12);
  EXPECT_LT((force.At(8.0) - force.world_n).norm(), 1e-12);
  const MultirotorDynamics pushed(a.vehicle, a.parameters, kStandardGravity, 0.0, {}, force);
  const MultirotorDynamics free(a.vehicle, a.parameters, kStandardGravity, 0.0);
  SimState yawed;  // body x along world y: the force at t = 2 s (+y) lies along body +x
  yawed.attitude_wb = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * kPi, Eigen::Vector3d::UnitZ()));
  const BodyAcceleration with = pushed.Accelerations(2.0, yawed, hover);
  const BodyAcceleration without = free.Accelerations(2.0, yawed, hover);
  const Eigen::Vector3d ds = with.specific_force_b_mps2 - without.specific_force_b_mps2;
  const Eigen::Vector3d dw = with.angular_acceleration_b_radps2 - without.angular_acceleration_b_radps2;
  const Eigen::Vector3d& ms = a.parameters.body.first_moment;
  EXPECT_LT((a.parameters.mass_kg * ds - ms.cross(dw) - Eigen::Vector3d(0.5, 0.0, -0.2)).norm(), 1e-9);
  EXPECT_LT((ms.cross(ds) + a.parameters.body.inertia * dw).norm(), 1e-9);
}

TEST(SimDynamicsTest, MotorLagFollowsAStepWithItsTimeConstant) {
  const SimulationVehicle a = PresetVehicle("A");
  const double tau = 0.03;
  const MultirotorDynamics dynamics(a.vehicle, a.parameters, kStandardGravity, tau);
  const MultirotorDynamics::RotorCommand step = [](double) { return Eigen::VectorXd::Constant(4, 1000.0); };
  SimState state;
  state.rotor_speed_radps = Eigen::VectorXd::Constant(4, 500.0);
  const double h = 1.0 / 2000.0;
  double max_error = 0.0;
  for (int k = 1; k <= 400; ++k) {
    state = dynamics.Step((k - 1) * h, state, h, step);
    const double expected = 1000.0 - 500.0 * std::exp(-k * h / tau);
    max_error = std::max(max_error, (state.rotor_speed_radps.array() - expected).abs().maxCoeff());
    if (k == 60) {  // t = tau: 63.2 % of the step
      EXPECT_NEAR((state.rotor_speed_radps[0] - 500.0) / 500.0, 1.0 - std::exp(-1.0), 1e-9);
    }
  }
  EXPECT_LT(max_error, 1e-6);
}

// A step of the command from 500 to 1000 rad/s (no lag): Omega_acting^2 = (1 - a) 1000^2 + a S with
// S = 1000^2 - (1000^2 - 500^2) exp(-rate t), and the acting rate is the derivative of that root.
TEST(SimDynamicsTest, SlowActuationFollowsAStepOfTheSquareWithItsRate) {
  const SimulationVehicle a = PresetVehicle("A");
  const SlowActuation slow{0.4, 2.0 * M_PI * 0.5};
  const MultirotorDynamics dynamics(a.vehicle, a.parameters, kStandardGravity, 0.0, {}, {}, slow);
  const MultirotorDynamics::RotorCommand step = [](double) { return Eigen::VectorXd::Constant(4, 1000.0); };
  SimState state;
  state.rotor_speed_radps = Eigen::VectorXd::Constant(4, 500.0);
  state.slow_square_radps2 = Eigen::VectorXd::Constant(4, 500.0 * 500.0);
  auto expected_square = [&](double t) {
    return (1.0 - slow.fraction) * 1e6 + slow.fraction * (1e6 - 0.75e6 * std::exp(-slow.rate_per_s * t));
  };
  const double h = 1.0 / 1000.0;
  double max_error = 0.0;
  for (int k = 1; k <= 1000; ++k) {
    state = dynamics.Step((k - 1) * h, state, h, step);
    const double t = k * h;
    max_error =
        std::max(max_error, std::abs(dynamics.ActingRotorSpeeds(t, state, step)[1] - std::sqrt(expected_square(t))));
  }
  EXPECT_LT(max_error, 1e-6);
  // At 1 s, 95.7 % of the slow part has arrived: 0.6 of the square at once, 0.4 (1 - e^-pi) of it later.
  EXPECT_NEAR(state.slow_square_radps2[3], 1e6 - 0.75e6 * std::exp(-M_PI), 1e-3);
  const double t = 1.0, dt = 1e-6;
  const double numeric = (std::sqrt(expected_square(t + dt)) - std::sqrt(expected_square(t - dt))) / (2 * dt);
  EXPECT_NEAR(dynamics.ActingRotorRates(t, state, step)[0], numeric, 1e-6 * std::abs(numeric));
}

TEST(SimDynamicsTest, WithoutLagTheRotorsAreTheCommand) {
  const SimulationVehicle a = PresetVehicle("A");
  const MultirotorDynamics dynamics(a.vehicle, a.parameters, kStandardGravity, 0.0);
  const MultirotorDynamics::RotorCommand ramp = [](double t) {
    return Eigen::VectorXd::Constant(4, 900.0 + 100.0 * t);
  };
  SimState state;
  state = dynamics.Step(0.0, state, 0.01, ramp);
  EXPECT_DOUBLE_EQ(state.rotor_speed_radps[2], 901.0);
  EXPECT_DOUBLE_EQ(dynamics.ActingRotorSpeeds(0.5, state, ramp)[0], 950.0);
}

TEST(SimDynamicsTest, RejectsAnImpossibleBody) {
  VehicleParameters body = PresetVehicle("A").parameters;
  body.body.inertia(0, 0) = -1.0;
  EXPECT_THROW(MultirotorDynamics(PresetVehicle("A").vehicle, body, kStandardGravity, 0.0), Error);
}

TEST(SimRandomTest, PortableNormalsHaveUnitMomentsAndRepeat) {
  RandomStream a(42, 7), b(42, 7), c(42, 8), d(43, 7);
  double sum = 0.0, sum_sq = 0.0;
  bool differs_by_stream = false, differs_by_seed = false;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = a.Normal();
    ASSERT_EQ(x, b.Normal());
    differs_by_stream = differs_by_stream || x != c.Normal();
    differs_by_seed = differs_by_seed || x != d.Normal();
    sum += x;
    sum_sq += x * x;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sum_sq / n, 1.0, 0.01);
  EXPECT_TRUE(differs_by_stream);
  EXPECT_TRUE(differs_by_seed);
  RandomStream u(1);
  for (int i = 0; i < 1000; ++i) {
    const double x = u.Uniform();
    ASSERT_GE(x, 0.0);
    ASSERT_LT(x, 1.0);
  }
}

}  // namespace
}  // namespace rotorid

// On the simulator's noise-free true states the IDIM equations of MODEL.md hold exactly:
// IdimRows(w, w', s, Omega) [kt kd chi 1]^T = 0 for every sample, any layout, with every effect on.

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "rotorid/model/rigid_body.h"
#include "rotorid/model/rotation.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"
#include "sim/sim_test_options.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;

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

SimulationOptions ShortFlightWithEffects(std::uint64_t seed) {
  SimulationOptions options = testing::TestOptions(8.0, 1.0);
  options.hover_lead_in_s = 0.0;  // excite from the start
  options.seed = seed;
  options.effects.Assign("delay_s=0.012");
  options.effects.Assign("motor_tau_s=0.025");
  options.effects.Assign("acc_bias=0.1,-0.2,0.3");
  options.effects.Assign("gyro_bias=0.01,0.02,-0.01");
  options.effects.Assign("misalignment_rad=0.01,-0.02,0.03");
  options.jitter_s = 0.0005;
  return options;
}

// Largest |e| / |rotor wrench| over the flight, e = IdimRows [kt kd chi 1]^T.
double WorstIdimResidual(const SimulationResult& flight) {
  Eigen::Matrix<double, kNumIdimColumns, 1> theta;
  theta << flight.truth.rotor.kt, flight.truth.rotor.kd, flight.truth.body.ToVector(), 1.0;
  const TrueStates& s = flight.states;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < s.t_s.size(); ++i) {
    const Eigen::Vector3d w = s.angular_velocity_b_radps.row(i).transpose();
    const Eigen::Vector3d w_dot = s.angular_acceleration_b_radps2.row(i).transpose();
    const Eigen::Vector3d sf = s.specific_force_b_mps2.row(i).transpose();
    const Eigen::VectorXd omega = s.rotor_speed_radps.row(i).transpose();
    const Wrench<double> e = IdimRows<double>(w, w_dot, sf, omega, flight.vehicle) * theta;
    const Wrench<double> rotor =
        RotorWrench<double>(omega, flight.truth.rotor.kt, flight.truth.rotor.kd, flight.vehicle);
    worst = std::max(worst, e.norm() / rotor.norm());
  }
  return worst;
}

void ExpectIdimHolds(const Vehicle& vehicle, const VehicleParameters& truth, std::uint64_t seed) {
  const SimulationResult flight = Simulate(vehicle, truth, ShortFlightWithEffects(seed));
  const double worst = WorstIdimResidual(flight);
  std::ostringstream text;
  text << std::scientific << worst;
  ::testing::Test::RecordProperty("worst_relative_residual_" + vehicle.name, text.str());
  EXPECT_LT(worst, 1e-9) << vehicle.name;
  // The flight does move: otherwise the check would be trivial (Debug builds fly only the fade-in).
  EXPECT_GT(flight.summary.angular_acceleration_rms_radps2.minCoeff(), testing::kOptimisedBuild ? 0.3 : 0.05)
      << vehicle.name;
}

TEST(SimIdimTest, EquationsHoldOnTrueStatesOfA) {
  const SimulationVehicle a = PresetVehicle("A");
  ExpectIdimHolds(a.vehicle, a.parameters, 1);
}

TEST(SimIdimTest, EquationsHoldOnTrueStatesOfB) {
  const SimulationVehicle b = PresetVehicle("B");
  ExpectIdimHolds(b.vehicle, b.parameters, 2);
}

TEST(SimIdimTest, EquationsHoldOnTrueStatesOfAHexa) { ExpectIdimHolds(Hexa(), DeriveSimulationParameters(Hexa()), 3); }

TEST(SimIdimTest, TrueStatesAreConsistentWithTheirOwnDerivatives) {
  // w' recorded per sample is the derivative of the recorded w (central differences, 1 kHz log).
  const SimulationVehicle a = PresetVehicle("A");
  SimulationOptions options = testing::TestOptions(3.0, 1.0);
  options.hover_lead_in_s = 0.0;
  options.log_rate_hz = 1000.0;
  // Smooth rotor speeds (no noise in the loop, a motor lag), so that differences are accurate.
  options.noise = NoiseLevels::Preset("none");
  options.effects.Set("motor_tau_s", 0.02);
  const SimulationResult flight = Simulate(a.vehicle, a.parameters, options);
  const TrueStates& s = flight.states;
  double worst = 0.0, scale = 0.0;
  for (Eigen::Index i = 1; i + 1 < s.t_s.size(); ++i) {
    const Eigen::Vector3d numeric =
        (s.angular_velocity_b_radps.row(i + 1) - s.angular_velocity_b_radps.row(i - 1)) / (s.t_s[i + 1] - s.t_s[i - 1]);
    worst = std::max(worst, (numeric - s.angular_acceleration_b_radps2.row(i).transpose()).norm());
    scale = std::max(scale, s.angular_acceleration_b_radps2.row(i).norm());
  }
  EXPECT_LT(worst, 0.02 * scale);
  // Velocity of O_d: a_world = R s + g_w.
  for (Eigen::Index i = 1; i + 1 < s.t_s.size(); i += 97) {
    const Eigen::Vector3d a_numeric =
        (s.velocity_w_mps.row(i + 1) - s.velocity_w_mps.row(i - 1)).transpose() / (s.t_s[i + 1] - s.t_s[i - 1]);
    const Eigen::Quaterniond q(s.attitude_wxyz(i, 0), s.attitude_wxyz(i, 1), s.attitude_wxyz(i, 2),
                               s.attitude_wxyz(i, 3));
    const Eigen::Vector3d a_model =
        q * s.specific_force_b_mps2.row(i).transpose() - Eigen::Vector3d(0, 0, kStandardGravity);
    EXPECT_LT((a_numeric - a_model).norm(), 0.02) << "sample " << i;
  }
}

}  // namespace
}  // namespace rotorid

// Each unmodelled effect has the sign and size of its definition (INTERFACE.md section 1).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rotorid/model/rotation.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"
#include "sim/sim_test_options.h"

namespace rotorid {
namespace {

using testing::TestOptions;

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

SimulationResult Fly(const SimulationOptions& options, const std::string& preset = "A") {
  const SimulationVehicle vehicle = PresetVehicle(preset);
  return Simulate(vehicle.vehicle, vehicle.parameters, options);
}

SimulationOptions Hover(const std::string& noise) {
  SimulationOptions options = TestOptions(10.0, 2.0);
  options.excitation = 0.0;
  options.noise = NoiseLevels::Preset(noise);
  return options;
}

// The logged rotor signal interpolated linearly at t (held outside the log).
Eigen::VectorXd InterpolateLog(const FlightLog& log, double t) {
  const Eigen::VectorXd& ts = log.t_s;
  if (t <= ts[0]) return log.rotor_radps.row(0).transpose();
  if (t >= ts[ts.size() - 1]) return log.rotor_radps.row(ts.size() - 1).transpose();
  const Eigen::Index upper = std::upper_bound(ts.data(), ts.data() + ts.size(), t) - ts.data();
  const double fraction = (t - ts[upper - 1]) / (ts[upper] - ts[upper - 1]);
  return ((1.0 - fraction) * log.rotor_radps.row(upper - 1) + fraction * log.rotor_radps.row(upper)).transpose();
}

// Lag (in samples) at which the rotor roll torque kt sum y_i Omega_i^2 computed from the LOGGED
// rotor column best correlates with the measured roll acceleration (gyro differentiated).
int RollResponseLag(const SimulationResult& flight) {
  const FlightLog& log = flight.log;
  const int n = log.num_samples();
  Eigen::VectorXd torque(n), response(n);
  for (int k = 0; k < n; ++k) {
    torque[k] = 0.0;
    for (int r = 0; r < log.num_rotors(); ++r)
      torque[k] += flight.truth.rotor.kt * flight.vehicle.rotors[r].position_m.y() * std::pow(log.rotor_radps(k, r), 2);
    const int before = std::max(k - 1, 0), after = std::min(k + 1, n - 1);
    response[k] = (log.gyro_radps(after, 0) - log.gyro_radps(before, 0)) / (log.t_s[after] - log.t_s[before]);
  }
  torque.array() -= torque.mean();
  response.array() -= response.mean();
  int best_lag = 0;
  double best = -1e300;
  for (int lag = -60; lag <= 60; ++lag) {
    double c = 0.0;
    for (int k = 100; k < n - 100; ++k) c += torque[k] * response[k + lag];
    if (c > best) {
      best = c;
      best_lag = lag;
    }
  }
  return best_lag;
}

TEST(SimEffectsTest, DelayShiftsTheResponseToTheLoggedRotorsByItsLength) {
  // Statistics of two 20 s flights at 1 kHz; Debug builds check the delay's definition exactly below.
  if (!testing::kOptimisedBuild) GTEST_SKIP() << "needs long 1 kHz flights: checked in optimised builds";
  SimulationOptions options = TestOptions(20.0, 20.0);
  options.log_rate_hz = 1000.0;
  options.noise = NoiseLevels::Preset("low");
  const int lag_without = RollResponseLag(Fly(options));
  options.effects.Assign("delay=0.02");
  const int lag_with = RollResponseLag(Fly(options));
  RecordProperty("lag_without_samples", lag_without);
  RecordProperty("lag_with_samples", lag_with);
  EXPECT_LE(std::abs(lag_without), 1);
  EXPECT_NEAR(lag_with - lag_without, 20, 1);  // 20 ms at 1 kHz, the response comes later
}

TEST(SimEffectsTest, MotorsGetTheLoggedSignalDelayedAndInterpolated) {
  SimulationOptions options = TestOptions(5.0, 1.0);
  options.jitter_s = 0.0008;
  options.effects.Assign("delay_s=0.0137");
  const SimulationResult flight = Fly(options);
  double worst = 0.0;
  for (int i = 0; i < flight.log.num_samples(); ++i) {
    if (flight.log.t_s[i] - options.effects.Scalar("delay_s") < flight.log.t_s[0]) continue;  // needs unlogged warm-up
    const Eigen::VectorXd expected = InterpolateLog(flight.log, flight.log.t_s[i] - options.effects.Scalar("delay_s"));
    worst = std::max(worst, (flight.states.rotor_speed_radps.row(i).transpose() - expected).norm() / expected.norm());
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(SimEffectsTest, MotorLagIsTheFirstOrderResponseToTheDelayedLog) {
  SimulationOptions options = TestOptions(5.0, 1.0);
  options.jitter_s = 0.0008;
  options.effects.Assign("delay_s=0.0137");
  options.effects.Assign("motor_tau_s=0.03");
  const SimulationResult flight = Fly(options);
  const FlightLog& log = flight.log;
  const double delay = options.effects.Scalar("delay_s"), tau = options.effects.Scalar("motor_tau_s");
  // Integrate tau x' = u - x exactly for the piecewise-linear u(t) = Omega_log(t - delay), from
  // the first sample whose input is fully logged, through every breakpoint t_j + delay.
  int i = 0;
  while (log.t_s[i] < log.t_s[0] + delay) ++i;
  Eigen::VectorXd x = flight.states.rotor_speed_radps.row(i).transpose();
  double t = log.t_s[i];
  int next_break = 1;
  double worst = 0.0, moved = 0.0;
  for (int k = i + 1; k < log.num_samples(); ++k) {
    while (t < log.t_s[k]) {
      while (next_break < log.num_samples() && log.t_s[next_break] + delay <= t) ++next_break;
      const double t_end = std::min(log.t_s[k], next_break < log.num_samples() ? log.t_s[next_break] + delay : 1e300);
      const double h = t_end - t;
      const Eigen::VectorXd u0 = InterpolateLog(log, t - delay), u1 = InterpolateLog(log, t_end - delay);
      const Eigen::VectorXd slope = (u1 - u0) / h;
      // x(t + h) = u(t + h) - slope tau + (x(t) - u(t) + slope tau) exp(-h / tau)
      x = u1 - slope * tau + (x - u0 + slope * tau) * std::exp(-h / tau);
      t = t_end;
    }
    const Eigen::VectorXd actual = flight.states.rotor_speed_radps.row(k).transpose();
    worst = std::max(worst, (actual - x).norm() / x.norm());
    moved = std::max(moved, (actual - InterpolateLog(log, log.t_s[k] - delay)).norm() / x.norm());
  }
  RecordProperty("lag_relative_error", std::to_string(worst * 1e12) + "e-12");
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(moved, 1e-3);  // the lag is visible: the rotors are not the delayed log itself
}

TEST(SimEffectsTest, AccelerometerBiasShowsInTheHoverMean) {
  SimulationOptions options = Hover("pixhawk");
  const Eigen::Vector3d bias(0.3, -0.2, 0.5);
  options.effects.Set("acc_bias", bias);
  const SimulationResult flight = Fly(options);
  const Eigen::Vector3d mean = flight.log.acc_mps2.colwise().mean();
  const double std_of_mean = 0.15 / std::sqrt(flight.log.num_samples());
  EXPECT_LT((mean - Eigen::Vector3d(0, 0, kStandardGravity) - bias).norm(), 0.01 + 6.0 * std_of_mean);
  // Against the true specific force the bias is exact within the noise of the mean.
  const Eigen::Vector3d measured_minus_true =
      (flight.log.acc_mps2 - flight.states.specific_force_b_mps2).colwise().mean();
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(measured_minus_true[a], bias[a], 4.0 * std_of_mean) << "axis " << a;
}

TEST(SimEffectsTest, GyroBiasShowsInTheHoverMean) {
  SimulationOptions options = Hover("pixhawk");
  const Eigen::Vector3d bias(0.02, -0.01, 0.015);
  options.effects.Set("gyro_bias", bias);
  const SimulationResult flight = Fly(options);
  const Eigen::Vector3d mean = flight.log.gyro_radps.colwise().mean();
  EXPECT_LT((mean - bias).norm(), 0.001 + 6.0 * 0.01 / std::sqrt(flight.log.num_samples()));
  EXPECT_LT(flight.states.angular_velocity_b_radps.colwise().mean().norm(), 0.002);  // the vehicle itself does not turn
}

TEST(SimEffectsTest, MisalignmentRotatesTheHoverSpecificForceByItsAngle) {
  SimulationOptions options = Hover("none");
  const Eigen::Vector3d r(0.02, -0.03, 0.0);  // perpendicular to the hover specific force
  options.effects.Set("misalignment_rad", r);
  const SimulationResult flight = Fly(options);
  const Eigen::Vector3d measured = flight.log.acc_mps2.colwise().mean();
  const Eigen::Vector3d true_force = flight.states.specific_force_b_mps2.colwise().mean();
  const double angle_deg = std::acos(measured.normalized().dot(true_force.normalized())) * kRadToDeg;
  RecordProperty("rotation_deg", std::to_string(angle_deg));
  EXPECT_NEAR(angle_deg, r.norm() * kRadToDeg, 0.05);
  // Direction: the measured vector is Exp(r) times the true one (v_imu = Exp(r) v_body), for
  // both sensors and at every sample.
  const Eigen::Matrix3d imu_from_body = ExpSO3<double>(r);
  for (int i = 0; i < flight.log.num_samples(); i += 50) {
    EXPECT_LT((flight.log.acc_mps2.row(i).transpose() -
               imu_from_body * flight.states.specific_force_b_mps2.row(i).transpose())
                  .norm(),
              1e-12);
    EXPECT_LT((flight.log.gyro_radps.row(i).transpose() -
               imu_from_body * flight.states.angular_velocity_b_radps.row(i).transpose())
                  .norm(),
              1e-12);
  }
  // The hover specific force itself is the vertical within a fraction of the misalignment.
  EXPECT_LT(std::acos(true_force.normalized().z()) * kRadToDeg, 0.05);
}

TEST(SimEffectsTest, SensorModelAppliesRotationThenBiasThenNoise) {
  SimulationOptions options = TestOptions(3.0, 1.0);
  options.noise = NoiseLevels::Preset("none");
  options.effects.Assign("misalignment=0.05,0.02,-0.04");
  options.effects.Assign("acc_bias=0.2,0.1,-0.3");
  options.effects.Assign("gyro_bias=0.01,-0.02,0.03");
  const SimulationResult flight = Fly(options, "B");
  const Eigen::Matrix3d imu_from_body = ExpSO3<double>(options.effects.Get("misalignment_rad"));
  for (int i = 0; i < flight.log.num_samples(); i += 7) {
    const Eigen::Vector3d acc =
        imu_from_body * flight.states.specific_force_b_mps2.row(i).transpose() + options.effects.Get("acc_bias");
    const Eigen::Vector3d gyro =
        imu_from_body * flight.states.angular_velocity_b_radps.row(i).transpose() + options.effects.Get("gyro_bias");
    ASSERT_LT((flight.log.acc_mps2.row(i).transpose() - acc).norm(), 1e-12);
    ASSERT_LT((flight.log.gyro_radps.row(i).transpose() - gyro).norm(), 1e-12);
  }
}

TEST(SimEffectsTest, NoiseHasThePresetStandardDeviation) {
  const SimulationOptions options = TestOptions(20.0, 3.0);
  const SimulationResult flight = Fly(options);
  const Eigen::MatrixX3d acc_noise = flight.log.acc_mps2 - flight.states.specific_force_b_mps2;
  const Eigen::MatrixX3d gyro_noise = flight.log.gyro_radps - flight.states.angular_velocity_b_radps;
  const double n = flight.log.num_samples();
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(std::sqrt(acc_noise.col(a).squaredNorm() / n), 0.15, 0.01);
    EXPECT_NEAR(std::sqrt(gyro_noise.col(a).squaredNorm() / n), 0.01, 0.0007);
  }
}

}  // namespace
}  // namespace rotorid

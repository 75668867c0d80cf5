#pragma once

// The simulated pilot and flight controller (internal to the simulator).
//
// Pilot: band-limited random references, sums of sinusoids with random frequencies and phases,
// shaped like the paper's hand-flown flights (roll and thrust excited more than pitch and yaw).
// Controller: runs at the log rate on the measured gyro and the true pose (a perfect estimator),
// SO(3) attitude PID with feed-forward, altitude PID, a weak horizontal position loop, and a
// mixer built from the controller's own, slightly wrong, idea of the vehicle.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <deque>
#include <vector>

#include "rotorid/core/vehicle.h"
#include "rotorid/sim/random.h"
#include "rotorid/sim/simulator.h"

namespace rotorid::internal {

// Upper rotor speed bound of the mixer, relative to the controller's hover speed.
constexpr double kMaxSpeedRatio = 1.6;

// x(t) = envelope-free sum_i a_i sin(w_i t + phi_i), with its first two time derivatives.
class SinusoidSum {
 public:
  SinusoidSum() = default;
  // `num_components` frequencies spread log-uniformly (stratified) over [low_hz, high_hz]; the
  // amplitude of the `shaped_derivative`-th derivative of each component grows as f^exponent,
  // and that derivative's RMS is `rms`.
  SinusoidSum(RandomStream* random, int num_components, double low_hz, double high_hz, int shaped_derivative,
              double exponent, double rms);
  void Evaluate(double t_s, double* value, double* rate, double* acceleration) const;

 private:
  std::vector<double> amplitude_, omega_radps_, phase_rad_;
};

// What the pilot asks for at one instant (Bryant angles and altitude with their derivatives).
struct PilotReference {
  Eigen::Vector3d bryant_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d bryant_rate = Eigen::Vector3d::Zero();
  Eigen::Vector3d bryant_acceleration = Eigen::Vector3d::Zero();
  double altitude_m = 0.0;
  double climb_rate_mps = 0.0;
  double vertical_acceleration_mps2 = 0.0;
  // Horizontal position of O_d (world x, y) with its derivatives: zero except for the circle.
  Eigen::Vector2d position_w_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_w_mps = Eigen::Vector2d::Zero();
  Eigen::Vector2d acceleration_w_mps2 = Eigen::Vector2d::Zero();
};

struct PilotOptions {
  double excitation = 1.0;  // scales every reference; 0 = hover
  double start_s = 1.0;     // references are zero before this time ...
  double ramp_s = 2.0;      // ... then fade in over this long
  double hover_altitude_m = 1.5;
  double roll_rms_rad = 0.14;          // about 8 deg RMS, peaks 20-25 deg
  double pitch_rms_rad = 0.075;        // about 4.3 deg RMS, peaks 12-15 deg
  double yaw_rate_rms_radps = 0.3;     // peaks 0.7-1 rad/s
  double vertical_acc_rms_mps2 = 1.1;  // thrust variations of +-20-30 %
  // The profile's part, added to the references above (faded in with them).
  FlightProfile profile = FlightProfile::kPaper;
  double spin_rate_radps = 0.0;  // yaw-spin: peak of the yaw-rate swing S sin(2 pi t / spin_period_s)
  double spin_period_s = 12.0;
  double circle_radius_m = 0.0, circle_speed_mps = 0.0;
  double high_altitude_m = 0.5;  // take-off / landing: hover_altitude_m (low) <-> this, 12 s cycles
};

class Pilot {
 public:
  Pilot(const PilotOptions& options, RandomStream* random);
  PilotReference At(double t_s) const;

 private:
  enum Channel { kRoll, kPitch, kYaw, kAltitude, kNorth, kEast, kNumChannels };
  struct Signal {
    double value = 0.0, rate = 0.0, acceleration = 0.0;
  };
  // The profile's part of one channel (before the fade-in envelope).
  Signal ProfileChannel(int channel, double t_s) const;

  PilotOptions options_;
  SinusoidSum roll_, pitch_, yaw_, altitude_;
};

// The controller's idea of the vehicle: right mass, wrong kt, kd and inertia, CoM at O_d.
struct ControllerModel {
  double mass_kg = 0.0;
  double kt = 0.0;
  double kd = 0.0;
  Eigen::Vector3d inertia_diagonal = Eigen::Vector3d::Zero();
};

struct ControllerInput {
  Eigen::Vector3d position_w_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_w_mps = Eigen::Vector3d::Zero();
  Eigen::Quaterniond attitude_wb = Eigen::Quaterniond::Identity();
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();  // measured, with bias and noise
};

class FlightController {
 public:
  // loop_latency_s: time from a measurement to the effect of the command computed from it
  // (one control period, the delay, about one motor time constant). The controller predicts its
  // state that far ahead from the commands still in the pipeline (a Smith predictor), so that
  // delays and motor lags of tens of ms do not destabilise it; motor_time_constant_s softens the attitude
  // loop for slow motors. Throws rotorid::Error when the layout cannot produce independent
  // thrust, roll, pitch and yaw.
  // max_speed_radps > 0 caps the mixer's rotor speeds below 1.6 x the hover speed (the motors' range);
  // horizontal_omega_radps: the position loop's natural frequency (weak by default, stiffer to
  // track a moving reference).
  FlightController(const Vehicle& vehicle, const ControllerModel& model, double gravity_mps2, double loop_latency_s,
                   double motor_time_constant_s, double max_speed_radps = 0.0, double horizontal_omega_radps = 0.6);

  // Presets the integrators so that, at rest on the reference, the output is these rotor speeds
  // (the vehicle took off and is trimmed when the simulation starts).
  void Trim(const Eigen::VectorXd& rotor_speed_radps, const PilotReference& reference);
  // One control step at time t, dt seconds after the previous one; returns the rotor speed
  // command (rad/s). `reference_ahead` is the pilot's reference one loop latency later, which the
  // predicted state is compared with (and whose accelerations are fed forward).
  Eigen::VectorXd Update(double t_s, double dt_s, const ControllerInput& input, const PilotReference& reference_ahead);

  // [thrust; torques] = allocation * Omega^2 in the controller's model.
  const Eigen::Matrix<double, 4, Eigen::Dynamic>& allocation() const { return allocation_; }
  double hover_speed_radps() const { return hover_speed_radps_; }
  double loop_latency_s() const { return loop_latency_s_; }

 private:
  Eigen::VectorXd Mix(double thrust_n, const Eigen::Vector3d& torque_nm) const;

  // A command still in the pipeline: the net accelerations it asked for (integral terms
  // excluded, as they only cancel disturbances), issued at t for dt seconds.
  struct PendingCommand {
    double t_s = 0.0;
    double dt_s = 0.0;
    Eigen::Vector3d angular_acceleration = Eigen::Vector3d::Zero();
    double vertical_acceleration = 0.0;
  };

  ControllerModel model_;
  double gravity_mps2_;
  double loop_latency_s_;
  Eigen::Matrix<double, 4, Eigen::Dynamic> allocation_;
  Eigen::Matrix<double, Eigen::Dynamic, 4> allocation_pinv_;
  double hover_speed_radps_ = 0.0;
  double min_speed_sq_ = 0.0, max_speed_sq_ = 0.0;

  // Gains (angular ones per unit of angular acceleration).
  Eigen::Vector3d attitude_kp_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d attitude_kd_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d attitude_ki_ = Eigen::Vector3d::Zero();
  double altitude_kp_ = 0.0, altitude_kd_ = 0.0, altitude_ki_ = 0.0;
  double horizontal_kp_ = 0.0, horizontal_kd_ = 0.0;

  Eigen::Vector3d attitude_integral_ = Eigen::Vector3d::Zero();  // integral of the attitude error (rad s)
  double altitude_integral_ = 0.0;                               // integral of the altitude error (m s)
  std::deque<PendingCommand> pending_;
};

}  // namespace rotorid::internal

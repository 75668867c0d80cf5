#pragma once

// rotorid's flight simulator: closed-loop flights of a multirotor with known parameters and known
// unmodelled effects (INTERFACE.md section 1), logged as INTERFACE.md's flight log. See
// docs/simulator.md for the model, the controller and the sensor model.
//
//   SimulationVehicle a = PresetVehicle("A");
//   SimulationOptions options;
//   options.duration_s = 30;
//   options.effects.Set("delay", 0.01);
//   SimulationResult flight = Simulate(a.vehicle, a.parameters, options);
//   // flight.log: what a real log would hold; flight.states: the noise-free truth per sample.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/parameters.h"
#include "rotorid/sim/dynamics.h"

namespace rotorid {

// White-noise standard deviations per logged sample (at the log rate, vibration included).
struct NoiseLevels {
  std::string name = "pixhawk";  // preset name, written to the log and the truth (say "custom" if edited)
  double gyro_std_radps = 0.01;
  double acc_std_mps2 = 0.15;
  double mocap_position_std_m = 0.5e-3;
  double mocap_angle_std_rad = 0.002;

  // "none", "low" (a good IMU on a quiet frame), "pixhawk" (a Pixhawk IMU in flight) or "bmi088"
  // (a Crazyflie's BMI088 in flight, docs/simulator.md 3). Throws rotorid::Error for other names.
  static NoiseLevels Preset(const std::string& name);
};

// What the pilot flies (docs/simulator.md 4): the paper-like random references, or one of the
// profiles that excite a particular effect of real vehicles on top of them.
enum class FlightProfile {
  kPaper,           // the paper-like flight (default)
  kYawSpin,         // slow yaw-rate swings to the vehicle's yaw authority (rotor inertia, lever arm)
  kCircle,          // a horizontal circle at constant speed (rotor drag)
  kTakeoffLanding,  // cycles of low hover near the ground, climb, hover at 0.5 m, descent (ground effect)
};
// "paper", "yaw-spin", "circle", "takeoff-landing"; Parse throws rotorid::Error for other names.
FlightProfile ParseFlightProfile(const std::string& name);
std::string FlightProfileName(FlightProfile profile);

// A one-cell battery feeding the motors, for command logs with a voltage (the `battery` effect):
// V(t) = open circuit (full_v -> empty_v, linear over the flight) - hover_sag_v x thrust / hover thrust
// (internal resistance times a current proportional to the thrust). With it, the logged rotor columns
// are the commands u in [0, 1] that the firmware computes from the speed the controller wants through
// the vehicle's command_to_speed map at its reference voltage (no battery compensation), and the
// motors turn at map(u (V / V_ref)^beta), beta = battery_exponent (INTERFACE.md).
struct BatteryOptions {
  bool enabled = false;
  double full_v = 4.2;
  double empty_v = 3.7;
  double hover_sag_v = 0.3;
};

struct SimulationOptions {
  // Logged flight length (s); the log holds round(duration_s * log_rate_hz) samples.
  double duration_s = 90.0;
  // Seed of every random choice (pilot, controller errors, noise, jitter): same seed, same flight.
  std::uint64_t seed = 1;
  // Log rate (Hz); the controller runs at this rate too, on the logged (jittered) instants.
  double log_rate_hz = 200.0;
  // Integration rate (Hz, >= 1000): RK4 steps per log interval = ceil(interval * physics_rate_hz).
  double physics_rate_hz = 2000.0;
  // g (m/s^2), written to the log as '# gravity: ...'.
  double gravity_mps2 = kStandardGravity;
  // The unmodelled effects, with INTERFACE.md's meanings.
  Effects effects;
  // Sensor noise.
  NoiseLevels noise;
  // Also log motion capture: pos_x,pos_y,pos_z and roll,pitch,yaw (yaw unwrapped).
  bool mocap = false;
  // Standard deviation (s) of the sampling instants around the nominal grid, clipped to 0.4 of
  // the nominal interval; samples are taken and logged at the jittered instants.
  double jitter_s = 0.0;
  // Scale of the pilot's references: 1 = the paper-like flight, 0 = hover.
  double excitation = 1.0;
  // Height of O_d above the ground (z = 0) the pilot hovers about (m): low for the ground effect.
  double hover_altitude_m = 1.5;
  // Logged hover at the start before the pilot's references fade in (over 2 s).
  double hover_lead_in_s = 1.0;
  // Unlogged flight before t = 0 so that the controller has settled when the log starts.
  double warmup_s = 1.0;
  // What the pilot flies; the circle's radius and speed.
  FlightProfile profile = FlightProfile::kPaper;
  double circle_radius_m = 2.0;
  double circle_speed_mps = 2.0;
  // The simulated battery (off: the log holds rotor speeds and no voltage).
  BatteryOptions battery;
  // A force rotorid does not model (tether, payload, wind); at most 0.3 m g (docs/simulator.md 1).
  ExternalForce external_force;
  // Relative error (5-10 % drawn per seed, random sign) of the controller's kt, kd and inertia.
  double controller_error_min = 0.05;
  double controller_error_max = 0.10;

  // Empty when valid, else a message naming the violated constraint.
  std::string Validate() const;
};

// The noise-free truth at each logged sample (rows), for checks of the IDIM equations.
struct TrueStates {
  Eigen::VectorXd t_s;
  Eigen::MatrixX3d position_w_m;
  Eigen::MatrixX3d velocity_w_mps;
  Eigen::MatrixXd attitude_wxyz;           // quaternion body to world, (w, x, y, z) per row
  Eigen::MatrixX3d bryant_rad;             // roll, pitch, yaw (yaw unwrapped)
  Eigen::MatrixX3d specific_force_b_mps2;  // s at O_d, body frame
  Eigen::MatrixX3d angular_velocity_b_radps;
  Eigen::MatrixX3d angular_acceleration_b_radps2;
  Eigen::MatrixXd rotor_speed_radps;    // actual rotor speeds (after delay and lag)
  Eigen::MatrixXd rotor_command_radps;  // the delayed log signal the motors follow
};

// A few numbers describing the flight (for the summary line and the tests).
struct FlightSummary {
  double duration_s = 0.0;
  int num_samples = 0;
  Eigen::Vector2d roll_range_deg = Eigen::Vector2d::Zero();
  Eigen::Vector2d pitch_range_deg = Eigen::Vector2d::Zero();
  Eigen::Vector2d yaw_rate_range_radps = Eigen::Vector2d::Zero();
  Eigen::Vector2d altitude_range_m = Eigen::Vector2d::Zero();
  double max_tilt_deg = 0.0;
  double max_horizontal_distance_m = 0.0;
  Eigen::Vector3d angular_acceleration_rms_radps2 = Eigen::Vector3d::Zero();
  double thrust_rms_variation_pct = 0.0;  // RMS of sum Omega^2 around its mean, in % of the mean
  Eigen::Vector2d rotor_speed_range_radps = Eigen::Vector2d::Zero();
  Eigen::Vector2d voltage_range_v = Eigen::Vector2d::Zero();  // the logged voltage (battery only)
};

// The controller's own (deliberately wrong) model of the vehicle.
struct ControllerModelSummary {
  double kt = 0.0;
  double kd = 0.0;
  Eigen::Vector3d inertia_diagonal = Eigen::Vector3d::Zero();
  double hover_speed_radps = 0.0;
};

struct SimulationResult {
  Vehicle vehicle;
  VehicleParameters truth;
  Effects effects;
  NoiseLevels noise;
  SimulationOptions options;
  std::string parameters_source;  // set by the caller (e.g. "preset A"); copied into the truth JSON
  FlightLog log;                  // what a real log would hold
  TrueStates states;
  FlightSummary summary;
  ControllerModelSummary controller;
};

// Flies the vehicle with these true parameters. Throws rotorid::Error when the options or the
// vehicle are invalid, when the vehicle cannot hover within its rotor speed range, or when the
// flight diverges (tilt > 80 deg or the vehicle leaves a 1 km box).
SimulationResult Simulate(const Vehicle& vehicle, const VehicleParameters& truth, const SimulationOptions& options);

// Rotor speeds (rad/s) that hold the vehicle level at rest (exact for any full-rank layout).
// Throws rotorid::Error when that needs a negative Omega^2.
Eigen::VectorXd HoverRotorSpeeds(const Vehicle& vehicle, const VehicleParameters& truth, double gravity_mps2);

// "simulated 90.0 s (18000 samples at 200 Hz) of A, seed 1, noise pixhawk: roll [...] deg, ..."
std::string SummaryLine(const SimulationResult& result);

}  // namespace rotorid

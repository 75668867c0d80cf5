#include "rotorid/sim/simulator.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <locale>
#include <optional>
#include <sstream>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/units.h"
#include "rotorid/model/rotation.h"
#include "rotorid/sim/dynamics.h"
#include "rotorid/sim/random.h"
#include "sim/battery_drive.h"
#include "sim/flight_controller.h"

namespace rotorid {
namespace {

// Independent random streams drawn from the one seed.
enum RandomStreamId : std::uint64_t { kPilotStream = 1, kControllerStream, kJitterStream, kImuStream, kMocapStream };

std::string FormatNumber(double value) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(10) << value;
  return out.str();
}

// The logged rotor signal as the motors see it: Omega_cmd(t) = Omega_log(t - delay), the delay of the rotor-signal
// effects, the log interpolated linearly between its samples and held before the first (INTERFACE.md, `delay`).
class DelayedRotorSignal {
 public:
  explicit DelayedRotorSignal(double command_latency_s) : command_latency_s_(command_latency_s) {}

  void Append(double t_s, const Eigen::VectorXd& omega_radps) {
    times_.push_back(t_s);
    values_.push_back(omega_radps);
  }
  const Eigen::VectorXd& Sample(int k) const { return values_[k]; }

  Eigen::VectorXd At(double t_s) const {
    const double t_log = t_s - command_latency_s_;
    if (t_log <= times_.front()) return values_.front();
    if (t_log >= times_.back()) return values_.back();
    const size_t upper = static_cast<size_t>(std::upper_bound(times_.begin(), times_.end(), t_log) - times_.begin());
    const size_t lower = upper - 1;
    const double fraction = (t_log - times_[lower]) / (times_[upper] - times_[lower]);
    return (1.0 - fraction) * values_[lower] + fraction * values_[upper];
  }

 private:
  double command_latency_s_;
  std::vector<double> times_;
  std::vector<Eigen::VectorXd> values_;
};

// Relative parameter error of the controller: a random sign times a magnitude in [min, max].
double ControllerError(RandomStream* random, const SimulationOptions& options) {
  const double sign = random->Uniform() < 0.5 ? -1.0 : 1.0;
  return sign * random->Uniform(options.controller_error_min, options.controller_error_max);
}

Eigen::Vector3d NoiseVector(RandomStream* random, double std) {
  const double x = random->Normal(), y = random->Normal(), z = random->Normal();
  return std * Eigen::Vector3d(x, y, z);
}

// Brings `angle` within pi of `previous` (keeps a logged yaw continuous).
double Unwrap(double angle, double previous) {
  return angle - 2.0 * kPi * std::round((angle - previous) / (2.0 * kPi));
}

// The result with its log (metadata set) and true states sized for `num_logged` samples.
SimulationResult PrepareResult(const Vehicle& vehicle, const VehicleParameters& truth, const SimulationOptions& options,
                               int num_logged) {
  SimulationResult result;
  result.vehicle = vehicle;
  result.truth = truth;
  result.effects = options.effects;
  result.noise = options.noise;
  result.options = options;
  const int num_rotors = vehicle.num_rotors();

  FlightLog& log = result.log;
  log.source = "rotorid simulate";
  log.gravity_mps2 = options.gravity_mps2;
  log.t_s.resize(num_logged);
  log.gyro_radps.resize(num_logged, 3);
  log.acc_mps2.resize(num_logged, 3);
  log.rotor_radps.resize(num_logged, num_rotors);
  if (options.mocap) log.mocap = MocapTrack{Eigen::MatrixX3d(num_logged, 3), Eigen::MatrixX3d(num_logged, 3)};
  if (options.battery.enabled) {
    log.voltage_v = Eigen::VectorXd(num_logged);
    log.metadata["rotor_signal"] = "command";  // the vehicle's command_to_speed maps it
  }
  // No effect parameters here: the log must not tell the diagnosis what to find.
  log.metadata["gravity"] = FormatNumber(options.gravity_mps2);
  log.metadata["simulator"] = "rotorid simulate";
  log.metadata["seed"] = std::to_string(options.seed);
  log.metadata["noise"] = options.noise.name;
  log.metadata["vehicle"] = vehicle.name;
  log.metadata["ground_z"] = "0";  // the world's z = 0 is the ground (ground_effect)
  log.metadata["rate_hz"] = FormatNumber(options.log_rate_hz);

  TrueStates& states = result.states;
  states.t_s.resize(num_logged);
  for (Eigen::MatrixX3d* m :
       {&states.position_w_m, &states.velocity_w_mps, &states.bryant_rad, &states.specific_force_b_mps2,
        &states.angular_velocity_b_radps, &states.angular_acceleration_b_radps2})
    m->resize(num_logged, 3);
  states.attitude_wxyz.resize(num_logged, 4);
  states.rotor_speed_radps.resize(num_logged, num_rotors);
  states.rotor_command_radps.resize(num_logged, num_rotors);
  return result;
}

FlightSummary Summarise(const TrueStates& states) {
  FlightSummary summary;
  const Eigen::Index n = states.t_s.size();
  summary.num_samples = static_cast<int>(n);
  summary.duration_s = n > 1 ? states.t_s[n - 1] - states.t_s[0] : 0.0;
  if (n == 0) return summary;
  auto range = [](const Eigen::VectorXd& v) { return Eigen::Vector2d(v.minCoeff(), v.maxCoeff()); };
  summary.roll_range_deg = range(states.bryant_rad.col(0)) * kRadToDeg;
  summary.pitch_range_deg = range(states.bryant_rad.col(1)) * kRadToDeg;
  summary.yaw_rate_range_radps = range(states.angular_velocity_b_radps.col(2));
  summary.altitude_range_m = range(states.position_w_m.col(2));
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Quaterniond q(states.attitude_wxyz(i, 0), states.attitude_wxyz(i, 1), states.attitude_wxyz(i, 2),
                               states.attitude_wxyz(i, 3));
    const double cos_tilt = std::clamp(q.toRotationMatrix()(2, 2), -1.0, 1.0);
    summary.max_tilt_deg = std::max(summary.max_tilt_deg, std::acos(cos_tilt) * kRadToDeg);
    summary.max_horizontal_distance_m =
        std::max(summary.max_horizontal_distance_m, states.position_w_m.row(i).head<2>().norm());
  }
  for (int a = 0; a < 3; ++a)
    summary.angular_acceleration_rms_radps2[a] =
        std::sqrt(states.angular_acceleration_b_radps2.col(a).squaredNorm() / n);
  const Eigen::VectorXd thrust = states.rotor_speed_radps.cwiseAbs2().rowwise().sum();
  const double mean = thrust.mean();
  summary.thrust_rms_variation_pct = 100.0 * std::sqrt((thrust.array() - mean).square().mean()) / mean;
  summary.rotor_speed_range_radps << states.rotor_speed_radps.minCoeff(), states.rotor_speed_radps.maxCoeff();
  return summary;
}

}  // namespace

NoiseLevels NoiseLevels::Preset(const std::string& name) {
  NoiseLevels noise;
  noise.name = name;
  if (name == "none") {
    noise.gyro_std_radps = noise.acc_std_mps2 = noise.mocap_position_std_m = noise.mocap_angle_std_rad = 0.0;
  } else if (name == "low") {
    noise.gyro_std_radps = 0.001;
    noise.acc_std_mps2 = 0.01;
    noise.mocap_position_std_m = 0.1e-3;
    noise.mocap_angle_std_rad = 0.0005;
  } else if (name == "pixhawk") {
    noise.gyro_std_radps = 0.01;
    noise.acc_std_mps2 = 0.15;
    noise.mocap_position_std_m = 0.5e-3;
    noise.mocap_angle_std_rad = 0.002;
  } else if (name == "bmi088") {
    // The broadband part (above ~55 Hz) of the IMRC Lab Crazyflies' logged gyro and accelerometer in
    // flight, 500 Hz: gyro 0.005-0.030 rad/s, acc 0.03-0.14 m/s^2 per axis (jana01/04/06); the
    // datasheet's densities times the firmware's bandwidths alone give 0.003 rad/s and 0.02 m/s^2.
    noise.gyro_std_radps = 0.015;
    noise.acc_std_mps2 = 0.06;
    noise.mocap_position_std_m = 0.5e-3;
    noise.mocap_angle_std_rad = 0.002;
  } else {
    throw Error("unknown noise preset '" + name + "'; known presets: none, low, pixhawk, bmi088");
  }
  return noise;
}

FlightProfile ParseFlightProfile(const std::string& name) {
  std::string known;
  for (FlightProfile profile :
       {FlightProfile::kPaper, FlightProfile::kYawSpin, FlightProfile::kCircle, FlightProfile::kTakeoffLanding}) {
    if (FlightProfileName(profile) == name) return profile;
    known += (known.empty() ? "" : ", ") + FlightProfileName(profile);
  }
  throw Error("unknown flight profile '" + name + "'; known profiles: " + known);
}

std::string FlightProfileName(FlightProfile profile) {
  switch (profile) {
    case FlightProfile::kPaper:
      return "paper";
    case FlightProfile::kYawSpin:
      return "yaw-spin";
    case FlightProfile::kCircle:
      return "circle";
    case FlightProfile::kTakeoffLanding:
      return "takeoff-landing";
  }
  return "paper";
}

std::string SimulationOptions::Validate() const {
  auto bad = [](double v) { return !std::isfinite(v); };
  if (bad(duration_s) || !(duration_s > 0.0) || duration_s > 36000.0)
    return "duration must be > 0 and <= 36000 s (got " + FormatNumber(duration_s) + ")";
  if (bad(log_rate_hz) || log_rate_hz < 50.0 || log_rate_hz > 10000.0)
    return "log rate must be within [50, 10000] Hz (got " + FormatNumber(log_rate_hz) + ")";
  if (duration_s * log_rate_hz < 19.5 || duration_s * log_rate_hz > 2e7)
    return "the flight must hold between 20 and 2e7 samples (duration * rate = " +
           FormatNumber(duration_s * log_rate_hz) + ")";
  if (bad(physics_rate_hz) || physics_rate_hz < 1000.0 || physics_rate_hz < log_rate_hz || physics_rate_hz > 1e6)
    return "physics rate must be >= 1000 Hz, >= the log rate and <= 1e6 Hz (got " + FormatNumber(physics_rate_hz) + ")";
  if (bad(gravity_mps2) || !(gravity_mps2 > 0.0) || gravity_mps2 > 100.0)
    return "gravity must be within (0, 100] m/s^2 (got " + FormatNumber(gravity_mps2) + ")";
  // Beyond these, the simulated controller can no longer fly the pilot's references safely.
  for (EffectKind kind : AllEffects())
    if (const std::string problem = kind->CheckSimulatable(effects.Get(kind)); !problem.empty()) return problem;
  for (double std : {noise.gyro_std_radps, noise.acc_std_mps2, noise.mocap_position_std_m, noise.mocap_angle_std_rad})
    if (bad(std) || std < 0.0) return "noise standard deviations must be finite and >= 0";
  if (bad(jitter_s) || jitter_s < 0.0 || jitter_s > 0.2 / log_rate_hz)
    return "jitter must be within [0, 0.2 / rate] s = [0, " + FormatNumber(0.2 / log_rate_hz) + "] s (got " +
           FormatNumber(jitter_s) + ")";
  if (bad(excitation) || excitation < 0.0 || excitation > 2.0)
    return "excitation must be within [0, 2] (got " + FormatNumber(excitation) + ")";
  if (bad(hover_lead_in_s) || hover_lead_in_s < 0.0) return "hover lead-in must be >= 0 s";
  if (bad(hover_altitude_m) || hover_altitude_m < 0.1 || hover_altitude_m > 1000.0)
    return "hover altitude must be within [0.1, 1000] m (got " + FormatNumber(hover_altitude_m) + ")";
  if (bad(warmup_s) || warmup_s < 0.0 || warmup_s > 60.0) return "warm-up must be within [0, 60] s";
  if (!external_force.world_n.allFinite()) return "the external force must be finite";
  if (bad(external_force.turn_period_s) || external_force.turn_period_s < 0.0)
    return "the external force's turn period must be >= 0 s (0: constant)";
  if (bad(circle_radius_m) || circle_radius_m < 0.2 || circle_radius_m > 100.0)
    return "circle radius must be within [0.2, 100] m (got " + FormatNumber(circle_radius_m) + ")";
  if (bad(circle_speed_mps) || circle_speed_mps < 0.0 || circle_speed_mps > 10.0 ||
      circle_speed_mps * circle_speed_mps / circle_radius_m > 5.0)
    return "circle speed must be within [0, 10] m/s with speed^2 / radius <= 5 m/s^2 (got " +
           FormatNumber(circle_speed_mps) + " m/s on " + FormatNumber(circle_radius_m) + " m)";
  if (battery.enabled &&
      (bad(battery.full_v) || bad(battery.empty_v) || bad(battery.hover_sag_v) || !(battery.empty_v > 0.0) ||
       battery.full_v < battery.empty_v || battery.hover_sag_v < 0.0 || battery.hover_sag_v >= 0.5 * battery.empty_v))
    return "battery voltages must satisfy 0 < empty <= full and 0 <= hover sag < empty / 2";
  if (!battery.enabled && !effects.IsZero(ParseEffectKind("battery")))
    return "battery_exponent needs the simulated battery (--battery): without it the log holds rotor speeds";
  if (bad(controller_error_min) || bad(controller_error_max) || controller_error_min < 0.0 ||
      controller_error_max < controller_error_min || controller_error_max > 0.3)
    return "controller errors must satisfy 0 <= min <= max <= 0.3";
  return {};
}

Eigen::VectorXd HoverRotorSpeeds(const Vehicle& vehicle, const VehicleParameters& truth, double gravity_mps2) {
  const int n = vehicle.num_rotors();
  Eigen::MatrixXd allocation(4, n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = vehicle.rotors[i].position_m;
    allocation.col(i) << truth.rotor.kt, truth.rotor.kt * p.y(), -truth.rotor.kt * p.x(),
        -vehicle.rotors[i].spin * truth.rotor.kd;
  }
  // At rest and level, s = [0 0 g]: the rotors carry m g and cancel the gravity torque -s x ms.
  const Eigen::Vector3d s(0.0, 0.0, gravity_mps2);
  const Eigen::Vector3d torque = -s.cross(truth.body.first_moment);
  const Eigen::Vector4d wrench(truth.mass_kg * gravity_mps2, torque.x(), torque.y(), 0.0);
  const Eigen::VectorXd speed_sq = allocation.completeOrthogonalDecomposition().solve(wrench);
  if (!((allocation * speed_sq - wrench).norm() <= 1e-9 * wrench.norm()) || !(speed_sq.minCoeff() > 0.0))
    throw Error("vehicle '" + vehicle.name + "' cannot hover: its centre of mass lies outside what its rotors can " +
                "balance (hover would need a negative or impossible rotor thrust)");
  return speed_sq.cwiseSqrt();
}

namespace {

// Adds the accelerometer signal of every sample k (at times[k], warm-up included) to the logged
// rows (from num_warmup on), read `delay_s` earlier: acc_log(t) = s(t - delay_s), linear between
// the samples (at 200 Hz its error is far below any accelerometer's noise), held beyond the ends.
void AddDelayedAccelerometer(const std::vector<double>& times, const std::vector<Eigen::Vector3d>& clean,
                             int num_warmup, double delay_s, Eigen::MatrixX3d* logged) {
  for (Eigen::Index row = 0; row < logged->rows(); ++row) {
    const size_t k = static_cast<size_t>(num_warmup + row);
    if (delay_s == 0.0) {
      logged->row(row) += clean[k].transpose();
      continue;
    }
    const double t = times[k] - delay_s;
    const size_t after = static_cast<size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin());
    if (after == 0 || after == times.size()) {
      logged->row(row) += clean[after == 0 ? 0 : times.size() - 1].transpose();
      continue;
    }
    const double a = (t - times[after - 1]) / (times[after] - times[after - 1]);
    logged->row(row) += ((1.0 - a) * clean[after - 1] + a * clean[after]).transpose();
  }
}

// Sampling instants: the unlogged warm-up, then the log; jitter clipped so time keeps increasing.
std::vector<double> SampleTimes(const SimulationOptions& options, int num_warmup, int num_logged) {
  std::vector<double> times(static_cast<size_t>(num_warmup + num_logged));
  RandomStream jitter_random(options.seed, kJitterStream);
  const double max_jitter_s = 0.4 / options.log_rate_hz;
  for (size_t k = 0; k < times.size(); ++k) {
    const double jitter = options.jitter_s > 0.0
                              ? std::clamp(jitter_random.Normal(0.0, options.jitter_s), -max_jitter_s, max_jitter_s)
                              : 0.0;
    times[k] = (static_cast<int>(k) - num_warmup) / options.log_rate_hz + jitter;
  }
  return times;
}

// The state at times[k + 1] from the state at times[k]: RK4 steps of at most 1 / physics_rate, cut
// where the motors' input has a kink (a logged sample arriving, t_j + delay), so that the
// piecewise-linear input is smooth within each step.
SimState IntegrateToNextSample(const MultirotorDynamics& dynamics, const MultirotorDynamics::RotorCommand& command,
                               const std::vector<double>& times, int k, double command_latency_s,
                               double physics_rate_hz, SimState state) {
  std::vector<double> segment_ends;
  for (auto it = std::upper_bound(times.begin(), times.begin() + k + 2, times[k] - command_latency_s);
       it != times.begin() + k + 2 && *it + command_latency_s < times[k + 1]; ++it)
    segment_ends.push_back(*it + command_latency_s);
  segment_ends.push_back(times[k + 1]);
  double segment_start = times[k];
  for (const double segment_end : segment_ends) {
    const double length = segment_end - segment_start;
    if (length <= 0.0) continue;
    const int num_steps = std::max(1, static_cast<int>(std::ceil(length * physics_rate_hz - 1e-9)));
    const double h = length / num_steps;
    for (int j = 0; j < num_steps; ++j) state = dynamics.Step(segment_start + j * h, state, h, command);
    segment_start = segment_end;
  }
  return state;
}

// Where the flight starts and the pilot hovers: the take-off profile starts in its low hover, a
// rotor radius above the ground (at least 2 cm), where the ground effect is largest.
double StartAltitude(const SimulationOptions& options, const Vehicle& vehicle) {
  if (options.profile != FlightProfile::kTakeoffLanding) return options.hover_altitude_m;
  return std::max(0.02, vehicle.rotor_radius_m.value_or(0.02));
}

// The pilot for this flight's profile. The yaw spin swings the yaw rate with a peak yaw
// acceleration of half what 30 % of the hover's rotor speed squared gives about z (the vehicle's
// yaw authority in the controller's model), at most one turn per second.
internal::PilotOptions PilotFor(const SimulationOptions& options, const Vehicle& vehicle,
                                const internal::ControllerModel& model, double hover_speed_radps) {
  internal::PilotOptions pilot;
  pilot.excitation = options.excitation;
  pilot.start_s = options.hover_lead_in_s;
  pilot.hover_altitude_m = StartAltitude(options, vehicle);
  pilot.profile = options.profile;
  const double yaw_authority_radps2 =
      0.3 * model.kd * vehicle.num_rotors() * hover_speed_radps * hover_speed_radps / model.inertia_diagonal.z();
  pilot.spin_rate_radps = std::min(2.0 * kPi, 0.5 * yaw_authority_radps2 * pilot.spin_period_s / (2.0 * kPi));
  pilot.circle_radius_m = options.circle_radius_m;
  pilot.circle_speed_mps = options.circle_speed_mps;
  return pilot;
}

// The vehicle as flown: with the battery, a map (the default one when the vehicle has none) and its voltage.
constexpr double kDefaultMapVoltage = 3.8;
Vehicle FlownVehicle(const Vehicle& vehicle, const SimulationOptions& options, const Eigen::VectorXd& hover_radps) {
  Vehicle flown = vehicle;
  if (!options.battery.enabled) return flown;
  // Without a map: one whose full command gives the mixer's ceiling.
  if (!flown.command_to_speed)
    flown.command_to_speed = internal::DefaultCommandToSpeed(internal::kMaxSpeedRatio * hover_radps.mean());
  if (!flown.command_to_speed_voltage_v) flown.command_to_speed_voltage_v = kDefaultMapVoltage;
  return flown;
}

// The most rotor speed the controller may ask for (0: its own 1.6 x hover). A vehicle with a command
// map cannot turn faster than the full command gives; a map that cannot carry the hover with 10 % to
// spare belongs to other parameters (derived ones): no ceiling then, and no battery, which needs it.
double MixerCeiling(const Vehicle& flown, const Eigen::VectorXd& hover, const SimulationOptions& options) {
  const double full_command_radps = flown.command_to_speed ? (*flown.command_to_speed)(1.0) : 0.0;
  const bool map_carries_hover = full_command_radps >= 1.1 * hover.maxCoeff();
  if (options.battery.enabled && !map_carries_hover)
    throw Error("vehicle '" + flown.name + "': its command_to_speed map gives " + FormatNumber(full_command_radps) +
                " rad/s at the full command, but hovering needs " + FormatNumber(hover.maxCoeff()) +
                " rad/s (plus 10 %); the simulated battery cannot fly it (give kt in its simulation: mapping)");
  return map_carries_hover ? full_command_radps : 0.0;
}

// The logged rotor commands and voltage of every sample (warm-up included) when the battery is simulated.
struct BatteryRecord {
  std::vector<Eigen::VectorXd> command;
  std::vector<double> voltage_v;
};

// The battery of this flight (none when off), with the first sample recorded: the commands that
// give the hover speeds at the starting voltage, so that the flight starts trimmed.
std::optional<internal::BatteryDrive> MakeBatteryDrive(const SimulationOptions& options, const Vehicle& flown,
                                                       const Eigen::VectorXd& hover, const std::vector<double>& times,
                                                       BatteryRecord* record) {
  if (!options.battery.enabled) return std::nullopt;
  const internal::BatteryDrive battery(options.battery, *flown.command_to_speed, *flown.command_to_speed_voltage_v,
                                       options.effects.Scalar(ParseEffectKind("battery")), hover.squaredNorm(),
                                       times.front(), times.back());
  const double voltage = battery.Voltage(times[0], hover.squaredNorm());
  Eigen::VectorXd trimmed(hover.size());
  for (Eigen::Index i = 0; i < hover.size(); ++i) trimmed[i] = battery.CommandFor(hover[i], voltage);
  record->command.push_back(trimmed);
  record->voltage_v.push_back(voltage);
  return battery;
}

// The speeds the motors get for the speeds the controller wants, through the firmware's command
// and the battery at this voltage; records both.
Eigen::VectorXd DriveMotors(const internal::BatteryDrive& battery, const Eigen::VectorXd& wanted_radps,
                            double voltage_v, BatteryRecord* record) {
  Eigen::VectorXd command(wanted_radps.size()), speed(wanted_radps.size());
  for (Eigen::Index i = 0; i < wanted_radps.size(); ++i) {
    command[i] = battery.Command(wanted_radps[i]);
    speed[i] = battery.Speed(command[i], voltage_v);
  }
  record->command.push_back(command);
  record->voltage_v.push_back(voltage_v);
  return speed;
}

// The inputs Simulate refuses: invalid options or vehicle, an effect of the wrong size, kt or kd not
// positive, an external force the controller's trim cannot fly against.
void ValidateSimulation(const Vehicle& vehicle, const VehicleParameters& truth, const SimulationOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error("simulation options: " + problem);
  if (const std::string problem = vehicle.Validate(); !problem.empty()) throw Error("simulated vehicle: " + problem);
  for (EffectKind kind : AllEffects())
    if (const Eigen::VectorXd v = options.effects.Get(kind); v.size() > 0 && v.size() != kind->Dimension(vehicle))
      throw Error("simulation options: " + kind->parameter_name() + " takes " +
                  std::to_string(kind->Dimension(vehicle)) + " value(s) for this vehicle, got " +
                  std::to_string(v.size()));
  if (!(truth.rotor.kt > 0.0) || !(truth.rotor.kd > 0.0) || !std::isfinite(truth.rotor.kt) ||
      !std::isfinite(truth.rotor.kd))
    throw Error("simulated vehicle: kt and kd must be positive");
  const double g = options.gravity_mps2;
  // Beyond this the controller's hover trim, made without it, is too far off to fly the references.
  if (options.external_force.world_n.norm() > 0.3 * truth.mass_kg * g)
    throw Error("simulation options: the external force (" + FormatNumber(options.external_force.world_n.norm()) +
                " N) must not exceed 0.3 m g = " + FormatNumber(0.3 * truth.mass_kg * g) + " N");
}

// The rotor-signal effects as the physics sees them: a delay of the command, a first-order lag and
// a slow share of the acting Omega^2.
struct RotorSignalTiming {
  double command_latency_s = 0.0;
  double motor_time_constant_s = 0.0;
  SlowActuation slow_actuation;
};
RotorSignalTiming RotorSignalTimingOf(const Effects& effects) {
  RotorSignalTiming timing;
  for (EffectKind kind : EffectsOfStage(EffectStage::kRotorSignal)) {
    timing.command_latency_s += kind->SimulatedCommandDelay(effects.Get(kind));
    timing.motor_time_constant_s += kind->SimulatedMotorTimeConstant(effects.Get(kind));
    if (const SlowActuation slow = kind->SimulatedSlowActuation(effects.Get(kind)); slow.active())
      timing.slow_actuation = slow;
  }
  return timing;
}

// The controller's slightly wrong model: right mass (weighed), CoM assumed at O_d.
internal::ControllerModel ControllerModelOf(const Vehicle& vehicle, const VehicleParameters& truth,
                                            const SimulationOptions& options) {
  RandomStream controller_random(options.seed, kControllerStream);
  internal::ControllerModel model;
  model.mass_kg = vehicle.mass_kg;
  model.kt = truth.rotor.kt * (1.0 + ControllerError(&controller_random, options));
  model.kd = truth.rotor.kd * (1.0 + ControllerError(&controller_random, options));
  for (int a = 0; a < 3; ++a)
    model.inertia_diagonal[a] = truth.body.inertia(a, a) * (1.0 + ControllerError(&controller_random, options));
  return model;
}

// What the IMU reads of one sample: the gyro with its noise, the accelerometer's noise (its signal is
// added after the flight, delayed: AddDelayedAccelerometer) and its clean specific force.
struct ImuReading {
  Eigen::Vector3d gyro;
  Eigen::Vector3d acc_noise;
  Eigen::Vector3d clean_specific_force;
};
// The body's motion at O_b through the sensor effects in chain order (INTERFACE.md's: rotate into the
// IMU frame, add the bias), then the noise.
ImuReading ReadImu(const EffectChain& sensor, const SimState& state, const BodyAcceleration& acc,
                   const SimulationOptions& options, RandomStream* imu_random) {
  ImuSample<double> imu{state.angular_velocity_b_radps, acc.angular_acceleration_b_radps2, acc.specific_force_b_mps2};
  for (size_t j = 0; j < sensor.kinds.size(); ++j) sensor.kinds[j]->ApplyToSensor(sensor.values[j].data(), &imu);
  ImuReading reading;
  reading.gyro = imu.angular_velocity + NoiseVector(imu_random, options.noise.gyro_std_radps);
  reading.acc_noise = NoiseVector(imu_random, options.noise.acc_std_mps2);
  reading.clean_specific_force = imu.specific_force;
  return reading;
}

// Motion capture of one logged sample, with its noise (yaw unwrapped against the previous noisy one).
void LogMotionCapture(int row, const SimState& state, const Eigen::Vector3d& bryant, const SimulationOptions& options,
                      RandomStream* mocap_random, double* previous_noisy_yaw, FlightLog* log) {
  log->mocap->position_w_m.row(row) =
      state.position_w_m + NoiseVector(mocap_random, options.noise.mocap_position_std_m);
  Eigen::Vector3d noisy = bryant + NoiseVector(mocap_random, options.noise.mocap_angle_std_rad);
  noisy.z() = *previous_noisy_yaw = Unwrap(noisy.z(), *previous_noisy_yaw);
  log->mocap->bryant_rad.row(row) = noisy;
}

// The true state of one logged sample.
void RecordTrueState(int row, double t, const SimState& state, const BodyAcceleration& acc,
                     const Eigen::Vector3d& bryant, const Eigen::VectorXd& acting, const Eigen::VectorXd& commanded,
                     TrueStates* states) {
  states->t_s[row] = t;
  states->position_w_m.row(row) = state.position_w_m;
  states->velocity_w_mps.row(row) = state.velocity_w_mps;
  states->attitude_wxyz.row(row) << state.attitude_wb.w(), state.attitude_wb.x(), state.attitude_wb.y(),
      state.attitude_wb.z();
  states->bryant_rad.row(row) = bryant;
  states->specific_force_b_mps2.row(row) = acc.specific_force_b_mps2;
  states->angular_velocity_b_radps.row(row) = state.angular_velocity_b_radps;
  states->angular_acceleration_b_radps2.row(row) = acc.angular_acceleration_b_radps2;
  states->rotor_speed_radps.row(row) = acting;
  states->rotor_command_radps.row(row) = commanded;
}

// Stops a flight that diverged (off to infinity, or tilted beyond 80 degrees).
void CheckNotDiverged(double t, const SimState& state, const Eigen::Matrix3d& r_wb) {
  if (!state.position_w_m.allFinite() || state.position_w_m.norm() > 1000.0 || r_wb(2, 2) < std::cos(80.0 / kRadToDeg))
    throw Error("the simulated flight diverged at t = " + FormatNumber(t) + " s (tilt " +
                FormatNumber(std::acos(std::clamp(r_wb(2, 2), -1.0, 1.0)) * kRadToDeg) +
                " deg); try a smaller excitation, delay or motor lag");
}

}  // namespace

SimulationResult Simulate(const Vehicle& vehicle, const VehicleParameters& truth, const SimulationOptions& options) {
  ValidateSimulation(vehicle, truth, options);
  const Effects& effects = options.effects;
  const RotorSignalTiming timing = RotorSignalTimingOf(effects);
  const double command_latency_s = timing.command_latency_s, motor_time_constant_s = timing.motor_time_constant_s;
  // The sensor effects in chain order, from the body towards the log, and the delay of the
  // accelerometer stream behind the gyro's (applied to the whole series after the flight).
  const EffectChain sensor = ActingEffects(effects, EffectStage::kImuSensor);
  double accelerometer_delay_s = 0.0;
  for (size_t j = 0; j < sensor.kinds.size(); ++j)
    accelerometer_delay_s += sensor.kinds[j]->SimulatedAccelerometerDelay(sensor.values[j]);
  const double g = options.gravity_mps2;
  const MultirotorDynamics dynamics(vehicle, truth, options.gravity_mps2, motor_time_constant_s,
                                    ActingEffects(effects, EffectStage::kRotorWrench), options.external_force,
                                    timing.slow_actuation);

  const internal::ControllerModel model = ControllerModelOf(vehicle, truth, options);
  const double loop_latency_s = command_latency_s + motor_time_constant_s + 1.0 / options.log_rate_hz;
  const Eigen::VectorXd hover = HoverRotorSpeeds(vehicle, truth, g);
  const Vehicle flown = FlownVehicle(vehicle, options, hover);
  const double max_speed_radps = MixerCeiling(flown, hover, options);
  // The circle needs a position loop that tracks it (the feed-forward tilt alone drifts outwards).
  const double horizontal_omega_radps = options.profile == FlightProfile::kCircle ? 2.0 : 0.6;
  internal::FlightController controller(vehicle, model, g, loop_latency_s, motor_time_constant_s, max_speed_radps,
                                        horizontal_omega_radps);

  RandomStream pilot_random(options.seed, kPilotStream);
  const internal::Pilot pilot(PilotFor(options, vehicle, model, controller.hover_speed_radps()), &pilot_random);

  const int num_warmup = static_cast<int>(std::lround(options.warmup_s * options.log_rate_hz));
  const int num_logged = static_cast<int>(std::lround(options.duration_s * options.log_rate_hz));
  const int num_total = num_warmup + num_logged;
  const std::vector<double> times = SampleTimes(options, num_warmup, num_logged);

  // Start trimmed in hover at rest: rotors at the exact hover speeds, controller integrators preset.
  SimState state;
  state.position_w_m = Eigen::Vector3d(0.0, 0.0, StartAltitude(options, vehicle));
  state.rotor_speed_radps = hover;
  DelayedRotorSignal rotor_signal(command_latency_s);
  BatteryRecord battery_record;
  const std::optional<internal::BatteryDrive> battery = MakeBatteryDrive(options, flown, hover, times, &battery_record);
  rotor_signal.Append(times[0], hover);
  controller.Trim(hover, pilot.At(times[0]));
  const MultirotorDynamics::RotorCommand command = [&rotor_signal](double t_s) { return rotor_signal.At(t_s); };

  SimulationResult result = PrepareResult(flown, truth, options, num_logged);
  result.controller = {model.kt, model.kd, model.inertia_diagonal, controller.hover_speed_radps()};
  FlightLog& log = result.log;

  RandomStream imu_random(options.seed, kImuStream);
  RandomStream mocap_random(options.seed, kMocapStream);
  double previous_yaw = 0.0, previous_noisy_yaw = 0.0;
  std::vector<Eigen::Vector3d> clean_accelerometer(num_total);

  for (int k = 0; k < num_total; ++k) {
    const double t = times[k];
    const Eigen::Matrix3d r_wb = state.attitude_wb.toRotationMatrix();
    const Eigen::VectorXd acting = dynamics.ActingRotorSpeeds(t, state, command);
    const BodyAcceleration acc = dynamics.Accelerations(t, state, acting, dynamics.ActingRotorRates(t, state, command));
    CheckNotDiverged(t, state, r_wb);
    const ImuReading imu = ReadImu(sensor, state, acc, options, &imu_random);
    clean_accelerometer[k] = imu.clean_specific_force;

    Eigen::Vector3d bryant = RotationToBryant(r_wb);
    bryant.z() = previous_yaw = Unwrap(bryant.z(), previous_yaw);
    if (k >= num_warmup) {
      const int row = k - num_warmup;
      log.t_s[row] = t;
      log.gyro_radps.row(row) = imu.gyro;
      log.acc_mps2.row(row) = imu.acc_noise;  // the signal is added after the flight
      log.rotor_radps.row(row) = battery ? battery_record.command[k] : rotor_signal.Sample(k);
      if (battery) (*log.voltage_v)[row] = battery_record.voltage_v[k];
      if (options.mocap) LogMotionCapture(row, state, bryant, options, &mocap_random, &previous_noisy_yaw, &log);
      RecordTrueState(row, t, state, acc, bryant, acting, command(t), &result.states);
    }
    if (k + 1 == num_total) break;

    // The controller acts on this sample; its output is the logged rotor signal of the next one
    // (one sample of latency), so the log interpolated between samples is exactly what the motors get.
    const double dt_control = k > 0 ? t - times[k - 1] : 1.0 / options.log_rate_hz;
    const internal::ControllerInput input{state.position_w_m, state.velocity_w_mps, state.attitude_wb, imu.gyro};
    const Eigen::VectorXd wanted = controller.Update(t, dt_control, input, pilot.At(t + loop_latency_s));
    // The voltage of the next sample sags with this sample's load.
    rotor_signal.Append(
        times[k + 1],
        battery ? DriveMotors(*battery, wanted, battery->Voltage(times[k + 1], acting.squaredNorm()), &battery_record)
                : wanted);

    state = IntegrateToNextSample(dynamics, command, times, k, command_latency_s, options.physics_rate_hz, state);
  }
  AddDelayedAccelerometer(times, clean_accelerometer, num_warmup, accelerometer_delay_s, &log.acc_mps2);
  result.summary = Summarise(result.states);
  if (battery) result.summary.voltage_range_v << log.voltage_v->minCoeff(), log.voltage_v->maxCoeff();
  return result;
}

std::string SummaryLine(const SimulationResult& result) {
  const FlightSummary& s = result.summary;
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::fixed << std::setprecision(1) << "simulated " << s.duration_s << " s (" << s.num_samples << " samples at "
      << std::setprecision(0) << result.options.log_rate_hz << " Hz) of vehicle " << result.vehicle.name << ", seed "
      << result.options.seed << ", noise " << result.noise.name << ": roll [" << std::setprecision(1)
      << s.roll_range_deg[0] << ", " << s.roll_range_deg[1] << "] deg, pitch [" << s.pitch_range_deg[0] << ", "
      << s.pitch_range_deg[1] << "] deg, yaw rate [" << std::setprecision(2) << s.yaw_rate_range_radps[0] << ", "
      << s.yaw_rate_range_radps[1] << "] rad/s, altitude [" << s.altitude_range_m[0] << ", " << s.altitude_range_m[1]
      << "] m, max tilt " << std::setprecision(1) << s.max_tilt_deg << " deg, angular acc RMS ["
      << s.angular_acceleration_rms_radps2[0] << ", " << s.angular_acceleration_rms_radps2[1] << ", "
      << s.angular_acceleration_rms_radps2[2] << "] rad/s^2, thrust variation " << s.thrust_rms_variation_pct
      << " % RMS, rotor speed [" << std::setprecision(0) << s.rotor_speed_range_radps[0] << ", "
      << s.rotor_speed_range_radps[1] << "] rad/s";
  if (result.options.profile != FlightProfile::kPaper) out << ", profile " << FlightProfileName(result.options.profile);
  if (result.options.battery.enabled)
    out << std::setprecision(2) << ", battery [" << s.voltage_range_v[0] << ", " << s.voltage_range_v[1] << "] V";
  return out.str();
}

}  // namespace rotorid

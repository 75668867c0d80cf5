#pragma once

// PX4 topics -> one rotorid flight (FlightLog) on one time base, and the rotor geometry suggested by
// the control-allocation parameters. docs/px4_ulog.md has the full mapping.
//
// Frames: PX4 body vectors are FRD and world vectors NED; rotorid's body frame is FLU and its world
// frame is z-up. Every vector v becomes (v.x, -v.y, -v.z), the world included, so the z-up world is
// north-west-up (x north, y west, z up) and a rotation R_ned_frd becomes F R_ned_frd F with
// F = diag(1, -1, -1). Yaw therefore changes sign: yaw = -(PX4 heading).

#include <string>
#include <vector>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"
#include "rotorid/io/ulog.h"

namespace rotorid {

// Where the gyro and accelerometer come from.
enum class Px4ImuSource {
  kAuto,             // the first with data of the three below, in this order
  kSensorCombined,   // sensor_combined: gyro_rad, accelerometer_m_s2 (+ accelerometer_timestamp_relative)
  kAngularVelocity,  // vehicle_angular_velocity.xyz + vehicle_acceleration.xyz (filtered, bias-corrected)
  kVehicleImu,       // vehicle_imu: delta_angle / delta_angle_dt, delta_velocity / delta_velocity_dt
};

// Where the rotor signal comes from.
enum class Px4RotorSource {
  kAuto,             // esc_status when it carries non-zero esc_rpm, else kCommand
  kEscRpm,           // esc_status esc[i].esc_rpm (measured), |rpm| * 2 pi / 60 -> rad/s; error if absent
  kCommand,          // actuator_motors when it has data, else actuator_outputs, through command_map
  kActuatorMotors,   // actuator_motors.control[i], normalised 0..1 (NaN = stopped -> 0 rad/s)
  kActuatorOutputs,  // actuator_outputs.output[i] (PWM in us, or the output driver's units)
};

// Motion-capture-like track (position and attitude).
enum class Px4PoseSource {
  kAuto,            // vehicle_visual_odometry when it has data (external vision / mocap), else kEstimate
  kEstimate,        // vehicle_attitude.q + vehicle_local_position x, y, z (the EKF's estimate)
  kVisualOdometry,  // vehicle_visual_odometry position + q (missing q: vehicle_attitude); error if absent
  kNone,            // no track
};

// Rotor command -> rotor speed, the same for every rotor: Omega = offset + gain * u (rad/s). A small
// struct so that richer maps (per rotor, polynomial) can replace it later. The default (0, 1) passes
// the command through unchanged: the rotor column then holds the command standing for the speed.
struct CommandToSpeedMap {
  double offset_radps = 0.0;         // Omega at u = 0
  double gain_radps_per_unit = 1.0;  // dOmega/du (rad/s per unit of u: per 1.0 normalised, or per us of PWM)

  double operator()(double u) const { return offset_radps + gain_radps_per_unit * u; }
  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

struct Px4FlightOptions {
  Px4ImuSource imu = Px4ImuSource::kAuto;
  // Multi id of the IMU topic (sensor_combined has one; vehicle_imu one per IMU). Default: 0.
  int imu_instance = 0;
  Px4RotorSource rotor = Px4RotorSource::kAuto;
  CommandToSpeedMap command_map;
  // actuator_outputs instance (multi id) for kActuatorOutputs. Default: 0.
  int outputs_instance = 0;
  // Channel (0-based) of rotor i in actuator_motors.control / actuator_outputs.output. Empty: rotor i
  // is channel i (PX4's motor order, the order of CA_ROTOR{i}). esc_status is matched through its
  // actuator_function (101 = motor 1) when set, else by index.
  std::vector<int> rotor_channels;
  Px4PoseSource pose = Px4PoseSource::kAuto;
  // Output time base: 0 keeps the IMU's own sample times; > 0 resamples everything onto a uniform grid
  // at this rate (Hz). Default: 0.
  double rate_hz = 0.0;

  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

// Maps a parsed ULog to a flight with `num_rotors` rotor columns (<= 0: CA_ROTOR_COUNT). All streams
// are interpolated onto the IMU time base (linear; commands zero-order hold), cropped to the span
// every used stream covers; t_s starts at 0 at the first kept sample (its absolute PX4 time is in
// metadata "px4_t0_us"). Throws rotorid::Error naming the file and the topics looked for when a
// needed topic is missing or empty.
FlightLog Px4FlightFromULog(const ULog& log, int num_rotors, const Px4FlightOptions& options = {});
// Reads only the topics the mapping can use, then maps them.
FlightLog ReadPx4Flight(const std::string& path, int num_rotors, const Px4FlightOptions& options = {});

// The rotor geometry PX4's control allocation was configured with: CA_ROTOR_COUNT rotors at
// (CA_ROTOR{i}_PX, -CA_ROTOR{i}_PY, -CA_ROTOR{i}_PZ) (FRD -> FLU; PX4 gives them relative to the centre
// of gravity) with spin = +1 when CA_ROTOR{i}_KM > 0 (PX4: positive KM for a counter-clockwise rotor,
// seen from above, which is rotorid's spin = +1). Mass is 0: unknown, the user must give it.
// Throws rotorid::Error when the log has no CA_ROTOR_COUNT (e.g. PX4 before v1.13).
Vehicle SuggestVehicleFromPx4Parameters(const ULog& log, const std::string& name = "A");

}  // namespace rotorid

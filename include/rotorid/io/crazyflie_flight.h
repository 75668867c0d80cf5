#pragma once

// A Crazyflie micro-SD log as one rotorid flight (INTERFACE.md conventions: FLU body, z-up
// world, SI units). The Crazyflie body frame is already FLU, so only units change:
//
//   IMU          fixedFrequency: gyro.x/y/z (deg/s -> rad/s), acc.x/y/z (g -> m/s^2, x 9.80665);
//                when that block does not log them, the estimator's events estGyroscope (gyro.x/y/z)
//                and estAcceleration (acc.x/y/z), one record per IMU sample (about 1 kHz): the
//                flight's times are then the gyro records inside the span every stream covers, and
//                the accelerometer and the fixed-frequency block (rotor signal, voltage) are
//                interpolated linearly onto them (never extrapolated)
//   rotor signal measured speed rpm.m1..m4 (rev/min -> rad/s), or the PWM command
//                pwm.m1_pwm..m4_pwm or motor.m1..m4 (0..65535 -> u = pwm/65535 in [0, 1],
//                metadata `rotor_signal: command`)
//   voltage      pm.vbatMV (mV -> V), else pm.vbat (V)
//   mocap        estPose: locSrv.x/y/z (m) and locSrv.qx/qy/qz/qw, resampled onto the IMU
//                times (linear for position, normalised linear for the quaternion), then as
//                Bryant angles with roll and yaw unwrapped (continuous, may leave [-pi, pi]);
//                without estPose records, the onboard estimate in the fixed-frequency block:
//                stateEstimateZ.x/y/z (mm), .vx/vy/vz (mm/s, the flight's velocity) and .quat (the
//                firmware's 32-bit compressed quaternion), resampled the same way
//
// Rotor columns follow the firmware's motor order M1..M4; the vehicle file lists its rotors in
// that order (data/vehicles/crazyflie21_*.yaml).

#include <string>

#include "rotorid/core/flight_log.h"
#include "rotorid/io/crazyflie_usd.h"

namespace rotorid {

struct CrazyflieFlightOptions {
  // "auto" (measured rpm when the log has rpm.m1..m4, else the command), "rpm" or "command".
  // Default: "auto".
  std::string rotor_signal = "auto";
  // Event holding the rotor variables, and the IMU when it logs gyro.x..z and acc.x..z.
  // Default: the firmware's "fixedFrequency".
  std::string imu_event = "fixedFrequency";
  // Events holding the IMU when `imu_event` does not. Defaults: "estGyroscope", "estAcceleration".
  std::string gyro_event = "estGyroscope";
  std::string acc_event = "estAcceleration";
  // Event holding the motion-capture pose; absent from a log means no mocap. Default "estPose".
  std::string pose_event = "estPose";
  // Refuse a file whose CRC32 disagrees. Default: true.
  bool verify_crc = true;

  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

// The flight in a decoded log. `num_rotors` is the vehicle's rotor count (a Crazyflie has 4;
// -1 accepts the log's 4). Throws rotorid::Error naming the file and, for missing variables,
// the names looked for and the event's variables.
FlightLog CrazyflieUsdToFlight(const CrazyflieUsdLog& log, int num_rotors = -1,
                               const CrazyflieFlightOptions& options = {});
// Reads and maps a uSD log file.
FlightLog LoadCrazyflieFlight(const std::string& path, int num_rotors = -1, const CrazyflieFlightOptions& options = {});

}  // namespace rotorid

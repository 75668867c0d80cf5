#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>

#include "rotorid/core/units.h"

namespace rotorid {

// Motion capture track, on the same time base as the flight log.
struct MocapTrack {
  Eigen::MatrixX3d position_w_m;  // position of O_d in the world frame (z up)
  Eigen::MatrixX3d bryant_rad;    // roll, pitch, yaw with R = Rz(yaw) Ry(pitch) Rx(roll)
  // Velocity of O_d in the world frame where the log gives it (an estimator's); without it the
  // velocity is the differentiated position.
  std::optional<Eigen::MatrixX3d> velocity_w_mps = std::nullopt;
};

// One flight on one time base (INTERFACE.md section 2). Rows are samples.
struct FlightLog {
  std::string source;           // where it came from, for messages
  Eigen::VectorXd t_s;          // strictly increasing; jitter allowed
  Eigen::MatrixX3d gyro_radps;  // IMU-frame angular velocity
  Eigen::MatrixX3d acc_mps2;    // IMU-frame specific force (about +g on z in hover)
  Eigen::MatrixXd rotor_radps;  // |Omega_i| per rotor (or the rotor signal standing for it)
  std::optional<MocapTrack> mocap;
  std::optional<Eigen::VectorXd> voltage_v;
  // The raw motor command when rotor_radps was mapped from it (the vehicle's command_to_speed).
  std::optional<Eigen::MatrixXd> rotor_command;
  double gravity_mps2 = kStandardGravity;
  std::map<std::string, std::string> metadata;

  int num_samples() const { return static_cast<int>(t_s.size()); }
  int num_rotors() const { return static_cast<int>(rotor_radps.cols()); }
  double duration_s() const { return t_s.size() > 1 ? t_s[t_s.size() - 1] - t_s[0] : 0.0; }
  // Median sample interval (s); robust to jitter and dropouts.
  double MedianDt() const;
  // The samples [begin, end) as a new log.
  FlightLog Slice(int begin, int end) const;
};

}  // namespace rotorid

#include "rotorid/io/crazyflie_flight.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/model/rotation.h"
#include "rotorid/signal/resample.h"

namespace rotorid {
namespace {

constexpr double kPwmFullScale = 65535.0;  // the firmware's 16-bit motor command range
constexpr int kCrazyflieRotors = 4;

// The columns of a set of variables; `missing` lists those the event does not log.
struct Lookup {
  std::vector<std::string> names;
  std::vector<const std::vector<double>*> columns;
  std::vector<std::string> missing;

  Lookup(const UsdEventTable& event, std::vector<std::string> wanted) : names(std::move(wanted)) {
    for (const std::string& name : names) {
      columns.push_back(event.FindColumn(name));
      if (!columns.back()) missing.push_back(name);
    }
  }
  bool complete() const { return missing.empty(); }
};

std::string LoggedVariables(const UsdEventTable& event) {
  std::vector<std::string> names;
  for (const UsdVariable& v : event.variables) names.push_back(v.name);
  if (names.empty()) return "no variables";
  if (names.size() > 40) {
    names.resize(40);
    names.push_back("...");
  }
  return Join(names);
}

[[noreturn]] void FailMissing(const CrazyflieUsdLog& log, const UsdEventTable& event, const std::string& what,
                              const std::string& looked_for) {
  throw Error(log.source + ": event '" + event.name + "' has no " + what + " (looked for " + looked_for +
              "; the event logs: " + LoggedVariables(event) + ")");
}

std::vector<std::string> Numbered(const std::string& prefix, const std::string& suffix) {
  std::vector<std::string> names;
  for (int m = 1; m <= kCrazyflieRotors; ++m) names.push_back(prefix + std::to_string(m) + suffix);
  return names;
}

// Whole seconds and the fraction apart: one rounding, the same as the column map's integer
// time path, so both readers of a flight give identical times.
double MicrosecondsToSeconds(uint64_t t_us) {
  return static_cast<double>(t_us / 1000000u) + static_cast<double>(t_us % 1000000u) * 1e-6;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// The rotor signal and whether it is the motor command.
struct RotorVariables {
  Lookup columns;
  bool is_command = false;
};

// `rotor_signal` (CrazyflieFlightOptions): measured speed rpm.m1..m4, the command (pwm.mN_pwm,
// else motor.mN), or "auto": the speed when logged, else the command.
RotorVariables ChooseRotorVariables(const CrazyflieUsdLog& usd, const UsdEventTable& imu,
                                    const std::string& rotor_signal) {
  const Lookup rpm(imu, Numbered("rpm.m", ""));
  const Lookup pwm(imu, Numbered("pwm.m", "_pwm"));
  const Lookup motor(imu, Numbered("motor.m", ""));
  const Lookup* command = pwm.complete() ? &pwm : motor.complete() ? &motor : nullptr;
  const std::string rpm_names = "rpm.m1..rpm.m4";
  const std::string command_names = "pwm.m1_pwm..pwm.m4_pwm or motor.m1..motor.m4";
  const Lookup* rotor = nullptr;
  if (rotor_signal == "rpm") {
    if (!rpm.complete()) FailMissing(usd, imu, "measured rotor speed " + Join(rpm.missing), rpm_names);
    rotor = &rpm;
  } else if (rotor_signal == "command") {
    if (!command) FailMissing(usd, imu, "motor command", command_names);
    rotor = command;
  } else {
    rotor = rpm.complete() ? &rpm : command;
    if (!rotor) FailMissing(usd, imu, "rotor signal", rpm_names + " or " + command_names);
  }
  return {*rotor, rotor != &rpm};
}

// The battery voltage from pm.vbatMV, else pm.vbat, where every record holds a finite value.
void AddVoltage(const UsdEventTable& imu, FlightLog* log) {
  const int n = log->num_samples();
  const auto all_finite = [n](const std::vector<double>* v) {
    return std::all_of(v->begin(), v->begin() + n, [](double x) { return std::isfinite(x); });
  };
  if (const auto* mv = imu.FindColumn("pm.vbatMV"); mv && all_finite(mv)) {
    log->voltage_v = Eigen::Map<const Eigen::VectorXd>(mv->data(), n) * 1e-3;
    log->metadata["voltage_source"] = "pm.vbatMV";
  } else if (const auto* v = imu.FindColumn("pm.vbat"); v && all_finite(v)) {
    log->voltage_v = Eigen::Map<const Eigen::VectorXd>(v->data(), n);
    log->metadata["voltage_source"] = "pm.vbat";
  }
}

// Motion capture from the pose event, on the IMU time base. Leaves `log->mocap` empty (and says
// why in the metadata) when the event holds no usable pose.
void AddMocap(const UsdEventTable& pose, FlightLog* log) {
  const Lookup found(pose, {"locSrv.x", "locSrv.y", "locSrv.z", "locSrv.qw", "locSrv.qx", "locSrv.qy", "locSrv.qz"});
  if (!found.complete()) {
    log->metadata["mocap"] = "none: event '" + pose.name + "' lacks " + Join(found.missing);
    return;
  }
  // Usable samples: finite, a rotation, strictly later than the previous one. The quaternion
  // keeps one hemisphere so that interpolating its components never passes through zero.
  const int m = pose.num_records();
  std::vector<double> t;
  std::vector<double> rows;  // x, y, z, qw, qx, qy, qz per sample
  t.reserve(m);
  rows.reserve(static_cast<size_t>(m) * 7);
  int dropped = 0;
  Eigen::Vector4d previous_q = Eigen::Vector4d::Zero();
  for (int i = 0; i < m; ++i) {
    double v[7];
    bool finite = true;
    for (int k = 0; k < 7; ++k) {
      v[k] = (*found.columns[k])[i];
      finite = finite && std::isfinite(v[k]);
    }
    Eigen::Vector4d q(v[3], v[4], v[5], v[6]);
    const double ti = MicrosecondsToSeconds(pose.timestamp_us[i]);
    if (!finite || !(q.norm() > 0.5 && q.norm() < 2.0) || (!t.empty() && !(ti > t.back()))) {
      ++dropped;
      continue;
    }
    q.normalize();
    if (!t.empty() && q.dot(previous_q) < 0.0) q = -q;
    previous_q = q;
    t.push_back(ti);
    rows.insert(rows.end(), {v[0], v[1], v[2], q[0], q[1], q[2], q[3]});
  }
  if (t.size() < 2) {
    log->metadata["mocap"] = "none: event '" + pose.name + "' has " + std::to_string(t.size()) + " usable samples";
    return;
  }
  const Eigen::Map<const Eigen::VectorXd> t_pose(t.data(), static_cast<Eigen::Index>(t.size()));
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor>> x_pose(
      rows.data(), static_cast<Eigen::Index>(t.size()), 7);
  const Eigen::MatrixXd x = InterpolateLinear(t_pose, Eigen::MatrixXd(x_pose), log->t_s);

  const int n = log->num_samples();
  MocapTrack mocap;
  mocap.position_w_m = x.leftCols(3);
  mocap.bryant_rad.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Quaterniond q(x(i, 3), x(i, 4), x(i, 5), x(i, 6));
    mocap.bryant_rad.row(i) = RotationToBryant(q.normalized().toRotationMatrix()).transpose();
  }
  // Continuous roll and yaw: a flip or a full turn must not jump by 2 pi between samples.
  mocap.bryant_rad.col(0) = UnwrapAngle(mocap.bryant_rad.col(0));
  mocap.bryant_rad.col(2) = UnwrapAngle(mocap.bryant_rad.col(2));
  log->mocap = std::move(mocap);

  double max_gap = 0.0;
  for (size_t i = 1; i < t.size(); ++i) max_gap = std::max(max_gap, t[i] - t[i - 1]);
  int held = 0;
  for (int i = 0; i < n; ++i) held += (log->t_s[i] < t.front() || log->t_s[i] > t.back()) ? 1 : 0;
  log->metadata["mocap"] = "event '" + pose.name + "' (locSrv.x/y/z, locSrv.q*), " + std::to_string(t.size()) +
                           " samples interpolated onto the IMU times";
  log->metadata["mocap_coverage_s"] = Format("%.6f", t.front()) + " .. " + Format("%.6f", t.back());
  log->metadata["mocap_max_gap_s"] = Format("%.4f", max_gap);
  if (held > 0) log->metadata["mocap_held_samples"] = std::to_string(held);  // outside coverage: end values
  if (dropped > 0) log->metadata["mocap_dropped_samples"] = std::to_string(dropped);
}

}  // namespace

std::string CrazyflieFlightOptions::Validate() const {
  if (rotor_signal != "auto" && rotor_signal != "rpm" && rotor_signal != "command")
    return "rotor signal must be auto, rpm or command, got '" + rotor_signal + "'";
  if (imu_event.empty()) return "the IMU event name must not be empty";
  return {};
}

FlightLog CrazyflieUsdToFlight(const CrazyflieUsdLog& usd, int num_rotors, const CrazyflieFlightOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(usd.source + ": " + problem);
  if (num_rotors >= 0 && num_rotors != kCrazyflieRotors) {
    throw Error(usd.source + ": a Crazyflie log has " + std::to_string(kCrazyflieRotors) +
                " motors, the vehicle file has " + std::to_string(num_rotors) + " rotors");
  }
  const UsdEventTable* imu = usd.FindEvent(options.imu_event);
  if (!imu) {
    throw Error(usd.source + ": no event '" + options.imu_event + "' with the IMU; the log has " +
                usd.DescribeEvents());
  }
  const Lookup gyro(*imu, {"gyro.x", "gyro.y", "gyro.z"});
  if (!gyro.complete()) FailMissing(usd, *imu, Join(gyro.missing), Join(gyro.names));
  const Lookup acc(*imu, {"acc.x", "acc.y", "acc.z"});
  if (!acc.complete()) FailMissing(usd, *imu, Join(acc.missing), Join(acc.names));

  const RotorVariables signal = ChooseRotorVariables(usd, *imu, options.rotor_signal);
  const Lookup* rotor = &signal.columns;
  const bool is_command = signal.is_command;
  const int n = imu->num_records();
  if (n < kMinFlightSamples) {
    throw Error(usd.source + ": event '" + imu->name + "' has " + std::to_string(n) + " records; at least " +
                std::to_string(kMinFlightSamples) + " are needed");
  }

  FlightLog log;
  log.source = usd.source;
  log.t_s.resize(n);
  for (int i = 0; i < n; ++i) {
    log.t_s[i] = MicrosecondsToSeconds(imu->timestamp_us[i]);
    if (i > 0 && !(imu->timestamp_us[i] > imu->timestamp_us[i - 1])) {
      throw Error(usd.source + ": event '" + imu->name + "' record " + std::to_string(i) + ": time goes backwards or " +
                  "repeats (" + std::to_string(imu->timestamp_us[i]) + " us after " +
                  std::to_string(imu->timestamp_us[i - 1]) + " us)");
    }
  }
  // The flight takes finite numbers only (a float variable can hold NaN or infinity).
  for (const Lookup* used : {&gyro, &acc, rotor}) {
    for (size_t k = 0; k < used->columns.size(); ++k) {
      const std::vector<double>& column = *used->columns[k];
      for (int i = 0; i < n; ++i) {
        if (!std::isfinite(column[i])) {
          throw Error(usd.source + ": event '" + imu->name + "' record " + std::to_string(i) + ": " + used->names[k] +
                      " is " + std::to_string(column[i]) + ", not a finite number");
        }
      }
    }
  }
  log.gyro_radps.resize(n, 3);
  log.acc_mps2.resize(n, 3);
  for (int a = 0; a < 3; ++a) {
    for (int i = 0; i < n; ++i) {
      log.gyro_radps(i, a) = (*gyro.columns[a])[i] * kDegToRad;
      // The firmware reports acceleration in units of standard gravity.
      log.acc_mps2(i, a) = (*acc.columns[a])[i] * kStandardGravity;
    }
  }
  log.rotor_radps.resize(n, kCrazyflieRotors);
  for (int r = 0; r < kCrazyflieRotors; ++r) {
    const std::vector<double>& column = *rotor->columns[r];
    for (int i = 0; i < n; ++i) {
      // Rotor columns hold |Omega|; the turning direction comes from the vehicle file.
      log.rotor_radps(i, r) = is_command ? column[i] / kPwmFullScale : std::abs(column[i]) * kRpmToRadps;
    }
  }
  AddVoltage(*imu, &log);

  log.metadata["source_format"] = "crazyflie_usd v" + std::to_string(usd.version);
  log.metadata["imu_event"] = imu->name + " (" + std::to_string(n) + " records)";
  log.metadata["rotor_signal"] = is_command ? "command" : "speed";
  log.metadata["rotor_signal_source"] =
      rotor->names.front() + ".." + rotor->names.back() + (is_command ? " (pwm / 65535)" : " (rpm -> rad/s)");
  if (const UsdEventTable* pose = usd.FindEvent(options.pose_event); pose && pose->num_records() > 0) {
    AddMocap(*pose, &log);
  }
  return log;
}

FlightLog LoadCrazyflieFlight(const std::string& path, int num_rotors, const CrazyflieFlightOptions& options) {
  CrazyflieUsdOptions read_options;
  read_options.verify_crc = options.verify_crc;
  return CrazyflieUsdToFlight(ReadCrazyflieUsd(path, read_options), num_rotors, options);
}

}  // namespace rotorid

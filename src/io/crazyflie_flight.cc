#include "rotorid/io/crazyflie_flight.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/io/rotor_signal.h"
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
                              const std::string& looked_for, const std::string& also = "") {
  throw Error(log.source + ": event '" + event.name + "' has no " + what + " (looked for " + looked_for +
              "; the event logs: " + LoggedVariables(event) + ")" + also);
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

// The times of an event's records (s); throws when they do not increase.
Eigen::VectorXd EventTimes(const CrazyflieUsdLog& usd, const UsdEventTable& event) {
  Eigen::VectorXd t(event.num_records());
  for (int i = 0; i < event.num_records(); ++i) {
    t[i] = MicrosecondsToSeconds(event.timestamp_us[i]);
    if (i > 0 && !(event.timestamp_us[i] > event.timestamp_us[i - 1])) {
      throw Error(usd.source + ": event '" + event.name + "' record " + std::to_string(i) +
                  ": time goes backwards or repeats (" + std::to_string(event.timestamp_us[i]) + " us after " +
                  std::to_string(event.timestamp_us[i - 1]) + " us)");
    }
  }
  return t;
}

double EventRateHz(const UsdEventTable& event) {
  const int n = event.num_records();
  if (n < 2) return 0.0;
  return (n - 1) / (static_cast<double>(event.timestamp_us.back() - event.timestamp_us.front()) * 1e-6);
}

// "estGyroscope (3029 records, 1009.2 Hz)".
std::string StreamDescription(const UsdEventTable& event) {
  return event.name + " (" + std::to_string(event.num_records()) + " records, " +
         FormatValue("%.1f Hz", EventRateHz(event)) + ")";
}

// Where the gyro, the accelerometer and the rotor signal come from: the fixed-frequency block
// when it logs the IMU, else the firmware's estimator events (one record per IMU sample).
struct ImuStreams {
  const UsdEventTable* gyro_event;
  const UsdEventTable* acc_event;
  Lookup gyro, acc;
};

ImuStreams FindImu(const CrazyflieUsdLog& usd, const UsdEventTable& block, const CrazyflieFlightOptions& options) {
  const std::vector<std::string> gyro_names = {"gyro.x", "gyro.y", "gyro.z"}, acc_names = {"acc.x", "acc.y", "acc.z"};
  const Lookup gyro(block, gyro_names), acc(block, acc_names);
  if (gyro.complete() && acc.complete()) return {&block, &block, gyro, acc};
  const UsdEventTable* gyro_event = usd.FindEvent(options.gyro_event);
  const UsdEventTable* acc_event = usd.FindEvent(options.acc_event);
  if (gyro_event && acc_event && gyro_event->num_records() > 0 && acc_event->num_records() > 0) {
    const Lookup event_gyro(*gyro_event, gyro_names), event_acc(*acc_event, acc_names);
    if (!event_gyro.complete()) FailMissing(usd, *gyro_event, Join(event_gyro.missing), Join(gyro_names));
    if (!event_acc.complete()) FailMissing(usd, *acc_event, Join(event_acc.missing), Join(acc_names));
    return {gyro_event, acc_event, event_gyro, event_acc};
  }
  const Lookup& missing = gyro.complete() ? acc : gyro;
  FailMissing(
      usd, block, Join(missing.missing), Join(missing.names),
      ", and the log has no records of the IMU events '" + options.gyro_event + "' and '" + options.acc_event + "'");
}

// The flight's time base: the gyro's records, cut to the span every stream covers when the
// streams differ (the slower ones are interpolated onto it, never extrapolated).
struct TimeBase {
  Eigen::VectorXd t_s;
  std::map<const UsdEventTable*, Eigen::VectorXd> event_t_s;  // each stream's own record times
  std::string description;
};

TimeBase MakeTimeBase(const CrazyflieUsdLog& usd, const ImuStreams& imu, const UsdEventTable& block) {
  const UsdEventTable& gyro = *imu.gyro_event;
  if (gyro.num_records() < kMinFlightSamples) {
    throw Error(usd.source + ": event '" + gyro.name + "' has " + std::to_string(gyro.num_records()) +
                " records; at least " + std::to_string(kMinFlightSamples) + " are needed");
  }
  TimeBase base;
  double begin = -std::numeric_limits<double>::infinity(), end = std::numeric_limits<double>::infinity();
  for (const UsdEventTable* stream : {&gyro, imu.acc_event, &block}) {
    if (base.event_t_s.count(stream)) continue;
    const Eigen::VectorXd t = EventTimes(usd, *stream);
    if (t.size() < 2) {
      throw Error(usd.source + ": event '" + stream->name + "' has " + std::to_string(t.size()) +
                  " records: too few to interpolate onto the IMU times");
    }
    begin = std::max(begin, t[0]);
    end = std::min(end, t[t.size() - 1]);
    base.event_t_s[stream] = t;
  }
  const Eigen::VectorXd& t_gyro = base.event_t_s.at(&gyro);
  std::vector<double> kept;
  for (Eigen::Index i = 0; i < t_gyro.size(); ++i)
    if (t_gyro[i] >= begin && t_gyro[i] <= end) kept.push_back(t_gyro[i]);
  base.t_s = Eigen::Map<const Eigen::VectorXd>(kept.data(), static_cast<Eigen::Index>(kept.size()));
  if (base.event_t_s.size() > 1) {
    base.description = "the " + gyro.name + " records from " + FormatValue("%.4f", begin) + " to " +
                       FormatValue("%.4f", end) + " s, where every stream has records: " + std::to_string(kept.size()) +
                       " of " + std::to_string(t_gyro.size());
  }
  if (static_cast<int>(kept.size()) < kMinFlightSamples) {
    throw Error(usd.source + ": the IMU events and '" + block.name + "' overlap in " + std::to_string(kept.size()) +
                " IMU records; at least " + std::to_string(kMinFlightSamples) + " are needed");
  }
  return base;
}

// The variables of `found` (logged by `event`) on the flight's time base; refuses values that
// are not finite (a float variable can hold NaN or infinity).
Eigen::MatrixXd ColumnsAt(const CrazyflieUsdLog& usd, const UsdEventTable& event, const Lookup& found,
                          const TimeBase& base) {
  const int records = event.num_records();
  Eigen::MatrixXd values(records, static_cast<Eigen::Index>(found.columns.size()));
  for (size_t k = 0; k < found.columns.size(); ++k) {
    const std::vector<double>& column = *found.columns[k];
    for (int i = 0; i < records; ++i) {
      if (!std::isfinite(column[i])) {
        throw Error(usd.source + ": event '" + event.name + "' record " + std::to_string(i) + ": " + found.names[k] +
                    " is " + std::to_string(column[i]) + ", not a finite number");
      }
      values(i, static_cast<Eigen::Index>(k)) = column[i];
    }
  }
  return InterpolateLinear(base.event_t_s.at(&event), values, base.t_s);
}

// The battery voltage from pm.vbatMV, else pm.vbat, where every record holds a finite value.
void AddVoltage(const UsdEventTable& block, const TimeBase& base, FlightLog* log) {
  const auto all_finite = [](const std::vector<double>* v) {
    return std::all_of(v->begin(), v->end(), [](double x) { return std::isfinite(x); });
  };
  const auto at_base = [&](const std::vector<double>& v) -> Eigen::VectorXd {
    const Eigen::Map<const Eigen::VectorXd> values(v.data(), static_cast<Eigen::Index>(v.size()));
    return InterpolateLinear(base.event_t_s.at(&block), values, base.t_s).col(0);
  };
  if (const auto* mv = block.FindColumn("pm.vbatMV"); mv && all_finite(mv)) {
    log->voltage_v = at_base(*mv) * 1e-3;
    log->metadata["voltage_source"] = "pm.vbatMV";
  } else if (const auto* v = block.FindColumn("pm.vbat"); v && all_finite(v)) {
    log->voltage_v = at_base(*v);
    log->metadata["voltage_source"] = "pm.vbat";
  }
}

// A pose source's records: position (m), quaternion (w, x, y, z), and the velocity (m/s, world)
// when the source has it. Rows are the event's records.
struct PoseRecords {
  const UsdEventTable* event = nullptr;
  Eigen::MatrixXd values;  // x, y, z, qw, qx, qy, qz[, vx, vy, vz]
  std::string description;
};

// The firmware's 32-bit compressed unit quaternion (quatcompress.h): the index of the largest
// component of (x, y, z, w) in the top 2 bits, then the other three, each a sign bit and 9 bits of
// |q_i| / (1/sqrt(2)); the largest is the positive rest of the unit norm. Returns (w, x, y, z).
Eigen::Vector4d DecompressQuaternion(uint32_t packed) {
  constexpr uint32_t kMask = (1u << 9) - 1;
  const int largest = static_cast<int>(packed >> 30);
  double xyzw[4];
  double sum_squares = 0.0;
  for (int i = 3; i >= 0; --i) {
    if (i == largest) continue;
    const double magnitude = M_SQRT1_2 * static_cast<double>(packed & kMask) / kMask;
    xyzw[i] = ((packed >> 9) & 1u) ? -magnitude : magnitude;
    sum_squares += xyzw[i] * xyzw[i];
    packed >>= 10;
  }
  xyzw[largest] = std::sqrt(std::max(0.0, 1.0 - sum_squares));
  return {xyzw[3], xyzw[0], xyzw[1], xyzw[2]};
}

// Motion capture as the radio delivered it: the estPose event's locSrv.x/y/z (m) and locSrv.q*.
std::optional<PoseRecords> LocSrvPose(const UsdEventTable& pose, FlightLog* log) {
  const Lookup found(pose, {"locSrv.x", "locSrv.y", "locSrv.z", "locSrv.qw", "locSrv.qx", "locSrv.qy", "locSrv.qz"});
  if (!found.complete()) {
    log->metadata["mocap"] = "none: event '" + pose.name + "' lacks " + Join(found.missing);
    return std::nullopt;
  }
  PoseRecords records{&pose, Eigen::MatrixXd(pose.num_records(), 7), "(locSrv.x/y/z, locSrv.q*)"};
  for (int k = 0; k < 7; ++k)
    records.values.col(k) = Eigen::Map<const Eigen::VectorXd>(found.columns[k]->data(), pose.num_records());
  return records;
}

// The onboard estimator's compressed state in the fixed-frequency block (stateEstimateZ: x/y/z in
// mm, vx/vy/vz in mm/s, world frame, and the compressed attitude quaternion), for logs without
// estPose records.
std::optional<PoseRecords> EstimatorPose(const UsdEventTable& block) {
  const std::string z = "stateEstimateZ.";
  const Lookup found(block, {z + "x", z + "y", z + "z", z + "quat", z + "vx", z + "vy", z + "vz"});
  if (!found.complete()) return std::nullopt;
  PoseRecords records{&block, Eigen::MatrixXd(block.num_records(), 10),
                      "(onboard estimate stateEstimateZ.x/y/z, .vx/vy/vz in mm and mm/s, .quat compressed)"};
  for (int i = 0; i < block.num_records(); ++i) {
    for (int a = 0; a < 3; ++a) {
      records.values(i, a) = (*found.columns[a])[i] * 1e-3;
      records.values(i, 7 + a) = (*found.columns[4 + a])[i] * 1e-3;
    }
    // The variable is a uint32 (type I); anything else cannot be a packed quaternion: dropped.
    const double packed = (*found.columns[3])[i];
    const bool valid = std::isfinite(packed) && packed >= 0.0 && packed <= 4294967295.0;
    const Eigen::Vector4d q = valid ? DecompressQuaternion(static_cast<uint32_t>(packed))
                                    : Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
    records.values.block<1, 4>(i, 3) = q.transpose();
  }
  return records;
}

// A pose on the IMU time base. Leaves `log->mocap` empty (and says why in the metadata) when the
// records hold no usable pose.
void AddPose(const PoseRecords& pose, FlightLog* log) {
  // Usable samples: finite, a rotation, strictly later than the previous one. The quaternion
  // keeps one hemisphere so that interpolating its components never passes through zero.
  const UsdEventTable& event = *pose.event;
  const int m = static_cast<int>(pose.values.rows()), columns = static_cast<int>(pose.values.cols());
  std::vector<double> t;
  std::vector<double> rows;  // the columns of `pose.values`, the quaternion normalised
  int dropped = 0;
  Eigen::Vector4d previous_q = Eigen::Vector4d::Zero();
  for (int i = 0; i < m; ++i) {
    Eigen::VectorXd v = pose.values.row(i).transpose();
    Eigen::Vector4d q = v.segment<4>(3);
    const double ti = MicrosecondsToSeconds(event.timestamp_us[i]);
    if (!v.allFinite() || !(q.norm() > 0.5 && q.norm() < 2.0) || (!t.empty() && !(ti > t.back()))) {
      ++dropped;
      continue;
    }
    q.normalize();
    if (!t.empty() && q.dot(previous_q) < 0.0) q = -q;
    previous_q = q;
    v.segment<4>(3) = q;
    t.push_back(ti);
    rows.insert(rows.end(), v.data(), v.data() + columns);
  }
  if (t.size() < 2) {
    log->metadata["mocap"] = "none: event '" + event.name + "' has " + std::to_string(t.size()) + " usable samples";
    return;
  }
  const Eigen::Map<const Eigen::VectorXd> t_pose(t.data(), static_cast<Eigen::Index>(t.size()));
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> x_pose(
      rows.data(), static_cast<Eigen::Index>(t.size()), columns);
  const Eigen::MatrixXd x = InterpolateLinear(t_pose, Eigen::MatrixXd(x_pose), log->t_s);

  const int n = log->num_samples();
  MocapTrack& mocap = log->mocap.emplace();
  mocap.position_w_m = x.leftCols(3);
  if (columns == 10) mocap.velocity_w_mps = x.rightCols(3);
  mocap.bryant_rad.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Quaterniond q(x(i, 3), x(i, 4), x(i, 5), x(i, 6));
    mocap.bryant_rad.row(i) = RotationToBryant(q.normalized().toRotationMatrix()).transpose();
  }
  // Continuous roll and yaw: a flip or a full turn must not jump by 2 pi between samples.
  mocap.bryant_rad.col(0) = UnwrapAngle(mocap.bryant_rad.col(0));
  mocap.bryant_rad.col(2) = UnwrapAngle(mocap.bryant_rad.col(2));

  double max_gap = 0.0;
  for (size_t i = 1; i < t.size(); ++i) max_gap = std::max(max_gap, t[i] - t[i - 1]);
  int held = 0;
  for (int i = 0; i < n; ++i) held += (log->t_s[i] < t.front() || log->t_s[i] > t.back()) ? 1 : 0;
  log->metadata["mocap"] = "event '" + event.name + "' " + pose.description + ", " + std::to_string(t.size()) +
                           " samples interpolated onto the IMU times";
  log->metadata["mocap_coverage_s"] = FormatValue("%.6f", t.front()) + " .. " + FormatValue("%.6f", t.back());
  log->metadata["mocap_max_gap_s"] = FormatValue("%.4f", max_gap);
  if (held > 0) log->metadata["mocap_held_samples"] = std::to_string(held);  // outside coverage: end values
  if (dropped > 0) log->metadata["mocap_dropped_samples"] = std::to_string(dropped);
}

}  // namespace

std::string CrazyflieFlightOptions::Validate() const {
  if (std::string problem = RotorSignalProblem(rotor_signal); !problem.empty()) return problem;
  if (imu_event.empty() || gyro_event.empty() || acc_event.empty()) return "the IMU event names must not be empty";
  return {};
}

FlightLog CrazyflieUsdToFlight(const CrazyflieUsdLog& usd, int num_rotors, const CrazyflieFlightOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(usd.source + ": " + problem);
  if (num_rotors >= 0 && num_rotors != kCrazyflieRotors) {
    throw Error(usd.source + ": a Crazyflie log has " + std::to_string(kCrazyflieRotors) +
                " motors, the vehicle file has " + std::to_string(num_rotors) + " rotors");
  }
  const UsdEventTable* block = usd.FindEvent(options.imu_event);
  if (!block) {
    throw Error(usd.source + ": no event '" + options.imu_event + "' with the IMU; the log has " +
                usd.DescribeEvents());
  }
  const ImuStreams imu = FindImu(usd, *block, options);
  const RotorVariables signal = ChooseRotorVariables(usd, *block, options.rotor_signal);
  const Lookup& rotor = signal.columns;
  const bool is_command = signal.is_command;
  const TimeBase base = MakeTimeBase(usd, imu, *block);
  const int n = static_cast<int>(base.t_s.size());

  FlightLog log;
  log.source = usd.source;
  log.t_s = base.t_s;
  // The firmware reports the gyro in deg/s and the acceleration in units of standard gravity.
  log.gyro_radps = ColumnsAt(usd, *imu.gyro_event, imu.gyro, base) * kDegToRad;
  log.acc_mps2 = ColumnsAt(usd, *imu.acc_event, imu.acc, base) * kStandardGravity;
  // Rotor columns hold |Omega|; the turning direction comes from the vehicle file.
  const Eigen::MatrixXd rotor_values = ColumnsAt(usd, *block, rotor, base);
  log.rotor_radps = is_command ? Eigen::MatrixXd(rotor_values / kPwmFullScale)
                               : Eigen::MatrixXd(rotor_values.cwiseAbs() * kRpmToRadps);
  AddVoltage(*block, base, &log);

  const bool merged = imu.gyro_event != block;
  log.metadata["source_format"] = "crazyflie_usd v" + std::to_string(usd.version);
  log.metadata["imu_event"] = merged ? StreamDescription(*imu.gyro_event) + " + " + StreamDescription(*imu.acc_event)
                                     : imu.gyro_event->name + " (" + std::to_string(n) + " records)";
  log.metadata["rotor_signal"] = is_command ? "command" : "speed";
  log.metadata["rotor_signal_source"] =
      (merged ? block->name + " " : std::string()) + rotor.names.front() + ".." + rotor.names.back() +
      (is_command ? " (pwm / 65535)" : " (rpm -> rad/s)") +
      (merged ? ", " + FormatValue("%.1f Hz", EventRateHz(*block)) + " interpolated linearly onto the IMU times" : "");
  if (merged) {
    log.metadata["time_base"] = base.description;
    log.metadata["rotor_event"] = StreamDescription(*block);
  }
  const UsdEventTable* pose = usd.FindEvent(options.pose_event);
  if (pose && pose->num_records() > 0) {
    if (const std::optional<PoseRecords> records = LocSrvPose(*pose, &log)) AddPose(*records, &log);
  } else if (const std::optional<PoseRecords> records = EstimatorPose(*block)) {
    AddPose(*records, &log);
  }
  return log;
}

FlightLog LoadCrazyflieFlight(const std::string& path, int num_rotors, const CrazyflieFlightOptions& options) {
  CrazyflieUsdOptions read_options;
  read_options.verify_crc = options.verify_crc;
  return CrazyflieUsdToFlight(ReadCrazyflieUsd(path, read_options), num_rotors, options);
}

}  // namespace rotorid

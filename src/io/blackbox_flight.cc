#include "rotorid/io/blackbox_flight.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"
#include "rotorid/io/rotor_signal.h"
#include "rotorid/model/rotation.h"
#include "rotorid/signal/resample.h"

namespace rotorid {
namespace internal {
namespace {

// Field columns of an indexed group name[0..count), or empty when any is missing.
std::vector<int> Columns(const BlackboxFrames& frames, const std::string& name, int count) {
  std::vector<int> columns;
  for (int i = 0; i < count; ++i) {
    const int c = frames.Find(name + "[" + std::to_string(i) + "]");
    if (c < 0) return {};
    columns.push_back(c);
  }
  return columns;
}

int CountIndexed(const BlackboxFrames& frames, const std::string& name) {
  int n = 0;
  while (frames.Find(name + "[" + std::to_string(n) + "]") >= 0) ++n;
  return n;
}

// The header's gyro_scale: a float written as its bit pattern in hex (0x3f800000 = 1.0).
double HeaderFloatBits(const BlackboxLog& log, const std::string& name, double fallback) {
  const std::string text = log.Header(name);
  if (text.empty()) return fallback;
  const auto bits = static_cast<std::uint32_t>(std::strtoul(text.c_str(), nullptr, 0));
  float value = 0.0f;
  std::memcpy(&value, &bits, sizeof(value));
  return std::isfinite(value) && value > 0.0f ? value : fallback;
}

// Major version from "Betaflight 4.2.8 (101738d8e) STM32F7X2", or -1.
int FirmwareMajor(const std::string& revision, const std::string& firmware) {
  if (revision.rfind(firmware + " ", 0) != 0) return -1;
  return std::atoi(revision.c_str() + firmware.size() + 1);
}

// Gyro in rad/s per logged count.
double GyroRadpsPerCount(const BlackboxLog& log, std::string* description) {
  const double scale = HeaderFloatBits(log, "gyro_scale", 1.0);
  const bool high_resolution = log.HeaderInt("blackbox_high_resolution", 0) == 1;
  if (scale < 1e-3) {  // old Cleanflight: rad/us per count
    *description = "gyroADC x gyro_scale (rad/us) x 1e6";
    return scale * 1e6;
  }
  *description = std::string("gyroADC (deg/s") + (high_resolution ? " x 10, blackbox_high_resolution" : "") + ")";
  return scale * kDegToRad / (high_resolution ? 10.0 : 1.0);
}

struct RotorSource {
  std::vector<int> columns;
  double offset = 0.0, scale = 1.0;  // value = (raw - offset) * scale
  bool is_command = false;
  std::string description;
};

RotorSource PickRotorSource(const BlackboxLog& log, int num_rotors, const std::string& wanted,
                            const std::string& where) {
  RotorSource source;
  if (wanted != "command") {
    if (auto c = Columns(log.main, "omega", num_rotors); !c.empty()) {
      source.columns = c;
      source.description = "omega[] (rad/s)";
      return source;
    }
    const long poles = log.HeaderInt("motor_poles", 14);
    if (auto c = Columns(log.main, "eRPM", num_rotors); !c.empty() && poles > 0) {
      source.columns = c;
      source.scale = 100.0 * 2.0 / static_cast<double>(poles) * kRpmToRadps;
      source.description = "eRPM[] x 100 / (motor_poles " + std::to_string(poles) + " / 2) (rev/min)";
      return source;
    }
    if (wanted == "rpm")
      throw Error(where + ": --rotor-signal rpm needs omega[0.." + std::to_string(num_rotors - 1) + "] or eRPM[0.." +
                  std::to_string(num_rotors - 1) + "] fields (Betaflight logs eRPM from 4.3 with bidirectional DShot)");
  }
  source.columns = Columns(log.main, "motor", num_rotors);
  if (source.columns.empty())
    throw Error(where + ": no motor[0.." + std::to_string(num_rotors - 1) + "] fields for " +
                std::to_string(num_rotors) + " rotors (the log has " + std::to_string(CountIndexed(log.main, "motor")) +
                ")");
  const std::string output = log.Header("motorOutput", "1000,2000");
  const std::size_t comma = output.find(',');
  const double high = comma == std::string::npos ? 2000.0 : std::atof(output.c_str() + comma + 1);
  const long protocol = log.HeaderInt("motor_pwm_protocol", 0);
  const bool dshot = protocol >= 5 && protocol <= 8;
  source.offset = dshot ? 48.0 : 1000.0;
  if (!(high > source.offset)) throw Error(where + ": header motorOutput '" + output + "' has no usable upper end");
  source.scale = 1.0 / (high - source.offset);
  source.is_command = true;
  source.description = std::string("motor[] ") + (dshot ? "DShot" : "PWM") + " (m - " +
                       std::to_string(static_cast<int>(source.offset)) + ") / " +
                       std::to_string(static_cast<int>(high - source.offset));
  return source;
}

// vbatLatest in V per count, or 0 when the firmware's unit is not known.
double VoltsPerCount(const BlackboxLog& log) {
  const std::string revision = log.Header("Firmware revision");
  if (FirmwareMajor(revision, "Betaflight") >= 4 || FirmwareMajor(revision, "INAV") >= 1 ||
      FirmwareMajor(revision, "Indiflight") >= 1)
    return 0.01;
  return 0.0;
}

// Motion capture uplinked to the flight controller and its onboard attitude (Indiflight):
// extPos[0..2] (mm), extVel[0..2] (cm/s), extAtt[0..2] (mrad roll, pitch, yaw), all NED with an
// FRD body, refreshed only when a new mocap sample arrives (24 Hz on the TU Delft logs), and
// quat[0..3] (w, x, y, z of FRD body -> NED, every frame). Converted to INTERFACE.md 1: world
// (x, -y, -z) (north, west, up), body FLU: R_flu = F R_frd F with F = diag(1, -1, -1).
struct MocapColumns {
  std::vector<int> position, velocity, euler, quaternion;
};

const Eigen::Matrix3d kFrdToFlu = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();

// The kept frames at which the uplinked mocap changes (a new sample): the first frame, then every
// frame where any of extPos, extVel, extAtt differs from the frame before.
std::vector<int> MocapUpdateRows(const BlackboxFrames& frames, const std::vector<int>& kept, const MocapColumns& c) {
  std::vector<int> fields = c.position;
  fields.insert(fields.end(), c.velocity.begin(), c.velocity.end());
  fields.insert(fields.end(), c.euler.begin(), c.euler.end());
  std::vector<int> rows = {0};
  for (int r = 1; r < static_cast<int>(kept.size()); ++r)
    for (int f : fields)
      if (frames.at(kept[r], f) != frames.at(kept[r - 1], f)) {
        rows.push_back(r);
        break;
      }
  return rows;
}

// A NED vector field (x, y, z columns) in `unit` per metre, at the given rows, as z-up world values.
Eigen::MatrixXd NedToWorld(const BlackboxFrames& frames, const std::vector<int>& kept, const std::vector<int>& rows,
                           const std::vector<int>& columns, double counts_per_unit) {
  Eigen::MatrixXd out(rows.size(), 3);
  for (size_t k = 0; k < rows.size(); ++k)
    for (int a = 0; a < 3; ++a)
      out(k, a) = (a == 0 ? 1.0 : -1.0) * static_cast<double>(frames.at(kept[rows[k]], columns[a])) / counts_per_unit;
  return out;
}

// FLU body -> z-up world rotation at the given kept rows: from quat when logged, else extAtt.
std::vector<Eigen::Matrix3d> Attitudes(const BlackboxFrames& frames, const std::vector<int>& kept,
                                       const std::vector<int>& rows, const MocapColumns& c) {
  std::vector<Eigen::Matrix3d> r(rows.size());
  for (size_t k = 0; k < rows.size(); ++k) {
    const auto v = [&](const std::vector<int>& columns, int i) {
      return static_cast<double>(frames.at(kept[rows[k]], columns[i]));
    };
    const Eigen::Matrix3d r_ned_frd =
        c.quaternion.empty()
            ? BryantToRotation(Eigen::Vector3d(v(c.euler, 0), v(c.euler, 1), v(c.euler, 2)) * 1e-3)
            : Eigen::Quaterniond(v(c.quaternion, 0), v(c.quaternion, 1), v(c.quaternion, 2), v(c.quaternion, 3))
                  .normalized()
                  .toRotationMatrix();
    r[k] = kFrdToFlu * r_ned_frd * kFrdToFlu;
  }
  return r;
}

// Median angle (deg) between the onboard attitude and extAtt at the mocap updates.
double MedianAttitudeOffsetDeg(const BlackboxFrames& frames, const std::vector<int>& kept, const std::vector<int>& rows,
                               const MocapColumns& c, const std::vector<Eigen::Matrix3d>& attitude) {
  std::vector<double> angles;
  for (int r : rows) {
    Eigen::Vector3d euler;
    for (int a = 0; a < 3; ++a) euler[a] = static_cast<double>(frames.at(kept[r], c.euler[a])) * 1e-3;
    const Eigen::Matrix3d ext = kFrdToFlu * BryantToRotation(euler) * kFrdToFlu;
    angles.push_back(Eigen::AngleAxisd(attitude[r].transpose() * ext).angle() * kRadToDeg);
  }
  std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
  return angles[angles.size() / 2];
}

void AddMotionCapture(const BlackboxFrames& frames, const std::vector<int>& kept, FlightLog* flight) {
  MocapColumns c{Columns(frames, "extPos", 3), Columns(frames, "extVel", 3), Columns(frames, "extAtt", 3),
                 Columns(frames, "quat", 4)};
  if (c.position.empty() || (c.quaternion.empty() && c.euler.empty())) {
    flight->metadata["blackbox_pose"] = "none (no extPos[0..2] with quat[0..3] or extAtt[0..2])";
    return;
  }
  const std::vector<int> rows = MocapUpdateRows(frames, kept, c);
  if (rows.size() < 2) {
    flight->metadata["blackbox_pose"] = "none (extPos, extVel and extAtt never change: no mocap uplinked)";
    return;
  }
  Eigen::VectorXd t_update(rows.size());
  for (size_t k = 0; k < rows.size(); ++k) t_update[k] = flight->t_s[rows[k]];
  MocapTrack mocap;
  mocap.position_w_m = InterpolateLinear(t_update, NedToWorld(frames, kept, rows, c.position, 1000.0), flight->t_s);
  if (!c.velocity.empty())
    mocap.velocity_w_mps = InterpolateLinear(t_update, NedToWorld(frames, kept, rows, c.velocity, 100.0), flight->t_s);
  // The onboard attitude is logged every frame; extAtt only at the mocap samples.
  const bool onboard = !c.quaternion.empty();
  std::vector<int> every_row(kept.size());
  std::iota(every_row.begin(), every_row.end(), 0);
  const std::vector<int>& attitude_rows = onboard ? every_row : rows;
  const std::vector<Eigen::Matrix3d> attitude = Attitudes(frames, kept, attitude_rows, c);
  Eigen::MatrixXd bryant(attitude.size(), 3);
  for (size_t k = 0; k < attitude.size(); ++k) bryant.row(k) = RotationToBryant(attitude[k]).transpose();
  bryant.col(0) = UnwrapAngle(bryant.col(0));
  bryant.col(2) = UnwrapAngle(bryant.col(2));
  mocap.bryant_rad = onboard ? bryant : InterpolateLinear(t_update, bryant, flight->t_s);
  flight->mocap = std::move(mocap);

  // The mocap's rate: the median interval between samples (some are dropped on the radio link).
  std::vector<double> intervals(rows.size() - 1);
  for (size_t k = 1; k < rows.size(); ++k) intervals[k - 1] = t_update[k] - t_update[k - 1];
  std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
  const double rate_hz = 1.0 / intervals[intervals.size() / 2];
  std::string pose = "extPos[0..2] (mm, NED -> z up)" +
                     std::string(c.velocity.empty() ? "" : ", extVel[0..2] (cm/s, NED -> z up)") + ": " +
                     std::to_string(rows.size()) + " mocap samples (" + FormatValue("%.1f Hz", rate_hz) +
                     ") interpolated linearly between the frames where they change; attitude ";
  if (!onboard) {
    pose += "extAtt[0..2] (mrad roll, pitch, yaw, FRD -> FLU), interpolated the same way";
  } else {
    pose += "quat[0..3] (onboard estimate of every frame, FRD -> FLU)";
    if (!c.euler.empty())
      pose += "; extAtt differs from it by " +
              FormatValue("%.1f deg", MedianAttitudeOffsetDeg(frames, kept, rows, c, attitude)) + " (median)";
  }
  flight->metadata["blackbox_pose"] = pose;
  flight->metadata["blackbox_mocap_rate_hz"] = FormatValue("%.2f", rate_hz);
}

}  // namespace
}  // namespace internal

std::string BlackboxFlightOptions::Validate() const {
  if (log_index < 0) return "blackbox log index must be >= 0 (0: the longest), got " + std::to_string(log_index);
  return RotorSignalProblem(rotor_signal);
}

const BlackboxLog& SelectBlackboxLog(const std::vector<BlackboxLog>& logs, const std::string& source, int log_index) {
  if (logs.empty()) throw Error(source + ": no blackbox log in the file");
  if (log_index > static_cast<int>(logs.size()))
    throw Error(source + ": blackbox log " + std::to_string(log_index) + " asked for, the file has " +
                std::to_string(logs.size()));
  const BlackboxLog* pick = log_index > 0 ? &logs[log_index - 1] : &logs[0];
  if (log_index == 0)
    for (const BlackboxLog& log : logs)
      if (log.main.num_frames() > pick->main.num_frames()) pick = &log;
  if (!pick->header_error.empty())
    throw Error(source + ": blackbox log " + std::to_string(pick->index) + ": " + pick->header_error);
  return *pick;
}

FlightLog BlackboxToFlight(const BlackboxLog& log, const std::string& source, int num_rotors,
                           const BlackboxFlightOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  const std::string where = source + " (blackbox log " + std::to_string(log.index) + ")";
  const BlackboxFrames& frames = log.main;
  if (num_rotors <= 0) num_rotors = internal::CountIndexed(frames, "motor");
  if (num_rotors <= 0) throw Error(where + ": no motor[] fields");
  const int time = frames.Find("time");
  const std::vector<int> gyro = internal::Columns(frames, "gyroADC", 3);
  const std::vector<int> acc = internal::Columns(frames, "accSmooth", 3);
  if (time < 0 || gyro.empty() || acc.empty())
    throw Error(where + ": needs the fields time, gyroADC[0..2] and accSmooth[0..2]" +
                (acc.empty() ? " (accSmooth is absent: was the accelerometer disabled?)" : ""));
  const internal::RotorSource rotor = internal::PickRotorSource(log, num_rotors, options.rotor_signal, where);
  const double acc_1g = static_cast<double>(log.HeaderInt("acc_1G", 0));
  if (!(acc_1g > 0)) throw Error(where + ": header acc_1G is missing or not positive");
  std::string gyro_description;
  const double gyro_scale = internal::GyroRadpsPerCount(log, &gyro_description);
  const int vbat = frames.Find("vbatLatest");
  const double volts = vbat >= 0 ? internal::VoltsPerCount(log) : 0.0;

  // Keep frames whose time increases.
  std::vector<int> kept;
  for (int k = 0; k < frames.num_frames(); ++k)
    if (kept.empty() || frames.at(k, time) > frames.at(kept.back(), time)) kept.push_back(k);
  if (kept.size() < 2) throw Error(where + ": fewer than 2 main frames with increasing time");
  const int n = static_cast<int>(kept.size());
  FlightLog flight;
  flight.source = source;
  flight.t_s.resize(n);
  flight.gyro_radps.resize(n, 3);
  flight.acc_mps2.resize(n, 3);
  flight.rotor_radps.resize(n, num_rotors);
  if (volts > 0) flight.voltage_v = Eigen::VectorXd(n);
  const std::int64_t t0 = frames.at(kept[0], time);
  for (int r = 0; r < n; ++r) {
    const int k = kept[r];
    flight.t_s[r] = static_cast<double>(frames.at(k, time) - t0) * 1e-6;
    for (int a = 0; a < 3; ++a) {
      flight.gyro_radps(r, a) = static_cast<double>(frames.at(k, gyro[a])) * gyro_scale;
      flight.acc_mps2(r, a) = static_cast<double>(frames.at(k, acc[a])) / acc_1g * kStandardGravity;
    }
    for (int i = 0; i < num_rotors; ++i) {
      const double value = (static_cast<double>(frames.at(k, rotor.columns[i])) - rotor.offset) * rotor.scale;
      flight.rotor_radps(r, i) = rotor.is_command ? std::max(0.0, value) : std::abs(value);
    }
    if (flight.voltage_v) (*flight.voltage_v)[r] = static_cast<double>(frames.at(k, vbat)) * volts;
  }
  internal::AddMotionCapture(frames, kept, &flight);
  auto& meta = flight.metadata;
  meta["format"] = "blackbox";
  meta["blackbox_log"] = log.Summary();
  meta["blackbox_firmware"] = log.Header("Firmware revision", "unknown");
  if (!log.Header("Craft name").empty()) meta["blackbox_craft"] = log.Header("Craft name");
  meta["blackbox_t0_us"] = std::to_string(t0);
  meta["blackbox_gyro"] = gyro_description;
  meta["blackbox_acc"] = "accSmooth / acc_1G " + std::to_string(static_cast<long>(acc_1g));
  meta["blackbox_rotor"] = rotor.description;
  meta["rotor_signal"] = rotor.is_command ? "command" : "speed";
  meta["blackbox_voltage"] = vbat < 0    ? "none (no vbatLatest field)"
                             : volts > 0 ? "vbatLatest x 0.01 V"
                                         : "none (vbatLatest unit unknown for this firmware)";
  if (n < frames.num_frames())
    meta["blackbox_dropped_frames"] = std::to_string(frames.num_frames() - n) + " (time not increasing)";
  return flight;
}

FlightLog LoadBlackboxFlight(const std::string& path, int num_rotors, const BlackboxFlightOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  const std::vector<BlackboxLog> logs = ReadBlackboxFile(path);
  return BlackboxToFlight(SelectBlackboxLog(logs, path, options.log_index), path, num_rotors, options);
}

Vehicle SuggestVehicleFromBlackboxHeader(const BlackboxLog& log, const QuadXGeometry& geometry,
                                         const std::string& name) {
  const std::string where = "blackbox log " + std::to_string(log.index);
  const int motors = internal::CountIndexed(log.main, "motor");
  if (motors != 4)
    throw Error(where + ": " + std::to_string(motors) +
                " motor[] fields: only a Quad-X (4 motors) can be suggested from the header; write the vehicle file "
                "by hand (INTERFACE.md section 3)");
  for (const char* key : {"mixer", "mixer_type", "mixerMode"}) {
    const std::string mixer = log.Header(key);
    if (!mixer.empty() && mixer != "QUADX" && mixer != "3")
      throw Error(where + ": header " + key + ":" + mixer + " is not QUADX; write the vehicle file by hand");
  }
  if (!(geometry.arm_length_m > 0))
    throw Error(where +
                ": the blackbox header records no geometry: give the arm length (hub to centre, m) and the "
                "mass (kg) of this Quad-X");
  if (geometry.mass_kg < 0) throw Error(where + ": mass must be >= 0 kg (0: unknown)");
  const double d = geometry.arm_length_m / std::sqrt(2.0);
  const bool reversed = geometry.props_out || log.HeaderInt("yaw_motors_reversed", 0) == 1;
  const double xy[4][2] = {{-d, -d}, {d, -d}, {-d, d}, {d, d}};
  const int spin[4] = {-1, 1, 1, -1};
  Vehicle vehicle;
  vehicle.name = name;
  vehicle.mass_kg = geometry.mass_kg;
  for (int i = 0; i < 4; ++i) {
    Rotor rotor;
    rotor.position_m = Eigen::Vector3d(xy[i][0], xy[i][1], 0.0);
    rotor.spin = reversed ? -spin[i] : spin[i];
    vehicle.rotors.push_back(rotor);
  }
  return vehicle;
}

}  // namespace rotorid

#include "rotorid/io/px4_flight.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/model/rotation.h"
#include "rotorid/signal/resample.h"

namespace rotorid {
namespace {

// sensor_combined marks an accelerometer sample that is not valid with this relative timestamp.
constexpr double kRelativeTimestampInvalid = 2147483647.0;
// PX4 actuator functions: Motor1 = 101 .. Motor12 = 112.
constexpr int kActuatorFunctionMotor1 = 101;
constexpr int kMaxMotors = 12;

// One topic's samples on its own (strictly increasing) time stamps, rows = samples.
struct Stream {
  std::vector<uint64_t> t_us;
  Eigen::MatrixXd x;
  std::string label;  // "topic[multi id].field", for metadata and messages
};

bool HasData(const ULogTopic* topic) { return topic != nullptr && topic->num_messages() > 0; }

// The time a message's content refers to: timestamp_sample when the topic has it (newer PX4), else
// the publication timestamp.
std::vector<uint64_t> SampleTimes(const ULogTopic& topic) {
  const ULogField* sample = topic.FindField("timestamp_sample");
  if (!sample || sample->type != ULogBaseType::kUInt64) return topic.timestamps_us();
  std::vector<uint64_t> t(topic.num_messages());
  for (size_t i = 0; i < t.size(); ++i) {
    uint64_t value;
    std::memcpy(&value, topic.MessageData(i) + sample->offset_bytes, sizeof(value));
    t[i] = value != 0 ? value : topic.timestamps_us()[i];
  }
  return t;
}

// Columns of fields, as a matrix (rows = messages).
Eigen::MatrixXd Columns(const ULogTopic& topic, const std::vector<std::string>& fields) {
  Eigen::MatrixXd x(static_cast<Eigen::Index>(topic.num_messages()), static_cast<Eigen::Index>(fields.size()));
  for (size_t c = 0; c < fields.size(); ++c) {
    const std::vector<double> column = topic.Column(fields[c]);
    x.col(static_cast<Eigen::Index>(c)) = Eigen::Map<const Eigen::VectorXd>(column.data(), x.rows());
  }
  return x;
}

std::vector<std::string> Vec3Fields(const std::string& base) { return {base + "[0]", base + "[1]", base + "[2]"}; }

// FRD/NED -> FLU/z-up: (x, y, z) -> (x, -y, -z) on every row of 3 columns starting at `col`.
void FlipYZ(Eigen::MatrixXd* x, Eigen::Index col = 0) {
  x->col(col + 1) *= -1.0;
  x->col(col + 2) *= -1.0;
}

// Keeps the samples whose time is strictly later than every earlier one (logs can repeat a stamp or
// step back after a time reset); returns how many were dropped.
int MakeStrictlyIncreasing(Stream* s) {
  std::vector<Eigen::Index> keep;
  keep.reserve(s->t_us.size());
  uint64_t last = 0;
  for (size_t i = 0; i < s->t_us.size(); ++i) {
    if (!keep.empty() && s->t_us[i] <= last) continue;
    keep.push_back(static_cast<Eigen::Index>(i));
    last = s->t_us[i];
  }
  const int dropped = static_cast<int>(s->t_us.size() - keep.size());
  if (dropped == 0) return 0;
  std::vector<uint64_t> t(keep.size());
  Eigen::MatrixXd x(static_cast<Eigen::Index>(keep.size()), s->x.cols());
  for (size_t k = 0; k < keep.size(); ++k) {
    t[k] = s->t_us[static_cast<size_t>(keep[k])];
    x.row(static_cast<Eigen::Index>(k)) = s->x.row(keep[k]);
  }
  s->t_us = std::move(t);
  s->x = std::move(x);
  return dropped;
}

Eigen::VectorXd SecondsSince(const std::vector<uint64_t>& t_us, uint64_t t0_us) {
  Eigen::VectorXd t(static_cast<Eigen::Index>(t_us.size()));
  for (size_t i = 0; i < t_us.size(); ++i)
    t[static_cast<Eigen::Index>(i)] = static_cast<double>(static_cast<int64_t>(t_us[i] - t0_us)) * 1e-6;
  return t;
}

const char* ImuSourceName(Px4ImuSource source) {
  switch (source) {
    case Px4ImuSource::kSensorCombined:
      return "sensor_combined";
    case Px4ImuSource::kAngularVelocity:
      return "vehicle_angular_velocity + vehicle_acceleration";
    case Px4ImuSource::kVehicleImu:
      return "vehicle_imu";
    case Px4ImuSource::kAuto:
      break;
  }
  return "sensor_combined, vehicle_angular_velocity + vehicle_acceleration, vehicle_imu";
}

class Px4Mapper {
 public:
  Px4Mapper(const ULog& log, int num_rotors, const Px4FlightOptions& options)
      : log_(log), num_rotors_(num_rotors), options_(options) {}

  FlightLog Map() {
    if (const std::string problem = options_.Validate(); !problem.empty()) throw Error(log_.source + ": " + problem);
    if (num_rotors_ <= 0) num_rotors_ = SuggestVehicleFromPx4Parameters(log_).num_rotors();
    if (num_rotors_ > kMaxMotors && options_.rotor_channels.empty())
      throw Error(log_.source + ": " + std::to_string(num_rotors_) + " rotors; PX4 logs at most 12 motors");
    if (!options_.rotor_channels.empty() && static_cast<int>(options_.rotor_channels.size()) != num_rotors_)
      throw Error(log_.source + ": " + std::to_string(options_.rotor_channels.size()) + " rotor channels given for " +
                  std::to_string(num_rotors_) + " rotors");

    Stream gyro, acc;
    LoadImu(&gyro, &acc);
    bool rotor_is_command = false;
    Stream rotor = LoadRotor(&rotor_is_command);
    std::optional<Stream> position, attitude;
    LoadPose(&position, &attitude);
    std::optional<Stream> voltage = LoadBattery();

    // Time window: what the IMU, the rotor signal and the pose all cover (never extrapolate them).
    uint64_t begin_us = std::max(gyro.t_us.front(), rotor.t_us.front());
    uint64_t end_us = std::min(gyro.t_us.back(), rotor.t_us.back());
    for (const auto* s : {&position, &attitude}) {
      if (!*s) continue;
      begin_us = std::max(begin_us, (*s)->t_us.front());
      end_us = std::min(end_us, (*s)->t_us.back());
    }
    if (end_us <= begin_us)
      throw Error(log_.source + ": the IMU (" + gyro.label + "), rotor (" + rotor.label +
                  ") and pose streams do not overlap in time");

    // The output time base: the IMU's own samples inside the window, or a uniform grid.
    const uint64_t t0_us = begin_us;
    Eigen::VectorXd t_s;
    if (options_.rate_hz > 0.0) {
      t_s = UniformTimeBase(0.0, static_cast<double>(end_us - begin_us) * 1e-6, options_.rate_hz);
    } else {
      const auto first = std::lower_bound(gyro.t_us.begin(), gyro.t_us.end(), begin_us);
      const auto last = std::upper_bound(gyro.t_us.begin(), gyro.t_us.end(), end_us);
      t_s = SecondsSince(std::vector<uint64_t>(first, last), t0_us);
    }
    if (t_s.size() < kMinFlightSamples)
      throw Error(log_.source + ": only " + std::to_string(t_s.size()) +
                  " samples where IMU, rotor and pose data overlap; " + "need at least " +
                  std::to_string(kMinFlightSamples));

    FlightLog flight;
    flight.source = log_.source;
    flight.t_s = t_s;
    flight.gyro_radps = InterpolateLinear(SecondsSince(gyro.t_us, t0_us), gyro.x, t_s);
    flight.acc_mps2 = InterpolateLinear(SecondsSince(acc.t_us, t0_us), acc.x, t_s);
    const Eigen::VectorXd rotor_t = SecondsSince(rotor.t_us, t0_us);
    // Commands are piecewise constant between publications; measured speeds are samples of a smooth signal.
    flight.rotor_radps =
        rotor_is_command ? InterpolateHold(rotor_t, rotor.x, t_s) : InterpolateLinear(rotor_t, rotor.x, t_s);
    if (position && attitude) flight.mocap = MakeMocap(*position, *attitude, t0_us, t_s);
    if (voltage) flight.voltage_v = InterpolateLinear(SecondsSince(voltage->t_us, t0_us), voltage->x, t_s).col(0);
    flight.gravity_mps2 = kStandardGravity;

    flight.metadata["format"] = "px4_ulog";
    flight.metadata["px4_t0_us"] = std::to_string(t0_us);
    flight.metadata["px4_imu"] = gyro.label + (acc.label != gyro.label ? " + " + acc.label : "");
    flight.metadata["px4_rotor"] = rotor.label;
    flight.metadata["px4_rotor_signal"] = rotor_is_command ? "command" : "measured";
    if (rotor_is_command)
      flight.metadata["px4_command_map"] = "Omega = " + std::to_string(options_.command_map.offset_radps) + " + " +
                                           std::to_string(options_.command_map.gain_radps_per_unit) + " * u";
    flight.metadata["px4_pose"] = position && attitude ? position->label + " + " + attitude->label : "none";
    if (voltage) flight.metadata["px4_battery"] = voltage->label;
    flight.metadata["px4_time_base"] =
        options_.rate_hz > 0.0 ? "uniform " + std::to_string(options_.rate_hz) + " Hz" : "IMU samples";
    flight.metadata["px4_dropouts"] =
        std::to_string(log_.dropouts.size()) + " (" + std::to_string(log_.DropoutTotalMs()) + " ms)";
    if (dropped_samples_ > 0) flight.metadata["px4_dropped_samples"] = std::to_string(dropped_samples_);
    if (!log_.warnings.empty()) flight.metadata["ulog_warnings"] = std::to_string(log_.warnings.size());
    for (const char* key : {"sys_name", "ver_hw", "ver_sw"})
      if (const auto it = log_.info.find(key); it != log_.info.end())
        flight.metadata[std::string("px4_") + key] = it->second.ToString();
    return flight;
  }

 private:
  const ULogTopic* Find(const char* name, int multi_id = 0) const {
    const ULogTopic* topic = log_.FindTopic(name, multi_id);
    return HasData(topic) ? topic : nullptr;
  }

  [[noreturn]] void Missing(const std::string& what, const std::string& looked_for) const {
    throw Error(log_.source + ": no " + what + " in this PX4 log; looked for " + looked_for);
  }

  // A few repeated or early stamps are dropped (counted in px4_dropped_samples); a step back (a time
  // reset) would drop everything up to the old time again: an error, not a silent loss.
  void Finalize(Stream* s) {
    const size_t before = s->t_us.size();
    size_t step = 1;  // the first sample stamped before the one preceding it
    while (step < before && s->t_us[step] >= s->t_us[step - 1]) ++step;
    const double back_s = step < before ? 1e-6 * static_cast<double>(s->t_us[step - 1] - s->t_us[step]) : 0.0;
    const double at_s = step < before ? 1e-6 * static_cast<double>(s->t_us[step - 1]) : 0.0;
    const int dropped = MakeStrictlyIncreasing(s);
    if (static_cast<size_t>(dropped) > std::max<size_t>(10, before / 100))
      throw Error(log_.source + ": the time stamps of " + s->label + " step back by " + ShortNumber(back_s) +
                  " s after " + ShortNumber(at_s) + " s (a time reset): " + std::to_string(dropped) + " of " +
                  std::to_string(before) + " samples would be lost; split the log at the reset");
    dropped_samples_ += dropped;
  }

  void LoadImu(Stream* gyro, Stream* acc) {
    Px4ImuSource source = options_.imu;
    const int instance = options_.imu_instance;
    if (source == Px4ImuSource::kAuto) {
      if (Find("sensor_combined", instance))
        source = Px4ImuSource::kSensorCombined;
      else if (Find("vehicle_angular_velocity", instance) && Find("vehicle_acceleration", instance))
        source = Px4ImuSource::kAngularVelocity;
      else if (Find("vehicle_imu", instance))
        source = Px4ImuSource::kVehicleImu;
      else
        Missing("IMU data",
                std::string(ImuSourceName(Px4ImuSource::kAuto)) + " (multi id " + std::to_string(instance) + ")");
    }
    const std::string suffix = "[" + std::to_string(instance) + "]";
    switch (source) {
      case Px4ImuSource::kSensorCombined: {
        const ULogTopic* topic = Find("sensor_combined", instance);
        if (!topic) Missing("IMU data", "sensor_combined" + suffix);
        gyro->t_us = topic->timestamps_us();
        gyro->x = Columns(*topic, Vec3Fields("gyro_rad"));
        gyro->label = "sensor_combined" + suffix + ".gyro_rad";
        // The accelerometer sample time is timestamp + accelerometer_timestamp_relative (us).
        acc->x = Columns(*topic, Vec3Fields("accelerometer_m_s2"));
        acc->t_us = topic->timestamps_us();
        acc->label = "sensor_combined" + suffix + ".accelerometer_m_s2";
        if (topic->HasField("accelerometer_timestamp_relative")) {
          const std::vector<double> relative = topic->Column("accelerometer_timestamp_relative");
          for (size_t i = 0; i < relative.size(); ++i)
            if (relative[i] != kRelativeTimestampInvalid)
              acc->t_us[i] =
                  static_cast<uint64_t>(static_cast<int64_t>(acc->t_us[i]) + static_cast<int64_t>(relative[i]));
        }
        break;
      }
      case Px4ImuSource::kAngularVelocity: {
        const ULogTopic* rates = Find("vehicle_angular_velocity", instance);
        const ULogTopic* accel = Find("vehicle_acceleration", instance);
        if (!rates || !accel)
          Missing("IMU data", "vehicle_angular_velocity" + suffix + " and vehicle_acceleration" + suffix);
        gyro->t_us = SampleTimes(*rates);
        gyro->x = Columns(*rates, Vec3Fields("xyz"));
        gyro->label = "vehicle_angular_velocity" + suffix + ".xyz";
        acc->t_us = SampleTimes(*accel);
        acc->x = Columns(*accel, Vec3Fields("xyz"));
        acc->label = "vehicle_acceleration" + suffix + ".xyz";
        break;
      }
      case Px4ImuSource::kVehicleImu: {
        const ULogTopic* topic = Find("vehicle_imu", instance);
        if (!topic) Missing("IMU data", "vehicle_imu" + suffix);
        // Integrated increments over their own intervals (us): rate = delta / dt.
        const std::vector<double> angle_dt = topic->Column("delta_angle_dt");
        const std::vector<double> velocity_dt = topic->Column("delta_velocity_dt");
        const Eigen::MatrixXd angle = Columns(*topic, Vec3Fields("delta_angle"));
        const Eigen::MatrixXd velocity = Columns(*topic, Vec3Fields("delta_velocity"));
        const std::vector<uint64_t> t = SampleTimes(*topic);
        std::vector<Eigen::Index> rows;
        for (size_t i = 0; i < t.size(); ++i)
          if (angle_dt[i] > 0.0 && velocity_dt[i] > 0.0) rows.push_back(static_cast<Eigen::Index>(i));
        dropped_samples_ += static_cast<int>(t.size() - rows.size());
        gyro->x.resize(static_cast<Eigen::Index>(rows.size()), 3);
        acc->x.resize(static_cast<Eigen::Index>(rows.size()), 3);
        for (size_t k = 0; k < rows.size(); ++k) {
          const Eigen::Index i = rows[k], r = static_cast<Eigen::Index>(k);
          gyro->x.row(r) = angle.row(i) / (angle_dt[static_cast<size_t>(i)] * 1e-6);
          acc->x.row(r) = velocity.row(i) / (velocity_dt[static_cast<size_t>(i)] * 1e-6);
          gyro->t_us.push_back(t[static_cast<size_t>(i)]);
        }
        acc->t_us = gyro->t_us;
        gyro->label = "vehicle_imu" + suffix + ".delta_angle/dt";
        acc->label = "vehicle_imu" + suffix + ".delta_velocity/dt";
        break;
      }
      case Px4ImuSource::kAuto:
        break;
    }
    FlipYZ(&gyro->x);
    FlipYZ(&acc->x);
    Finalize(gyro);
    Finalize(acc);
    if (gyro->t_us.size() < 2 || acc->t_us.size() < 2) Missing("usable IMU samples", gyro->label);
  }

  int Channel(int rotor) const {
    return options_.rotor_channels.empty() ? rotor : options_.rotor_channels[static_cast<size_t>(rotor)];
  }

  // Measured rotor speed from esc_status, or nullopt when it has no data or only zero rpm.
  std::optional<Stream> EscRpm() const {
    const ULogTopic* topic = Find("esc_status");
    if (!topic) return std::nullopt;
    // ESC k drives motor (actuator_function - 100) when that field is set (PX4 >= 1.14), else motor k+1.
    std::vector<int> esc_of_rotor(static_cast<size_t>(num_rotors_), -1);
    for (int k = 0; topic->HasField("esc[" + std::to_string(k) + "].esc_rpm"); ++k) {
      const std::string function_field = "esc[" + std::to_string(k) + "].actuator_function";
      if (!topic->HasField(function_field)) continue;
      const std::vector<double> function = topic->Column(function_field);
      const int motor = static_cast<int>(*std::max_element(function.begin(), function.end())) - kActuatorFunctionMotor1;
      for (int i = 0; i < num_rotors_; ++i)
        if (motor == Channel(i) && esc_of_rotor[static_cast<size_t>(i)] < 0) esc_of_rotor[static_cast<size_t>(i)] = k;
    }
    Stream s;
    s.t_us = topic->timestamps_us();
    s.x.resize(static_cast<Eigen::Index>(topic->num_messages()), num_rotors_);
    bool any_nonzero = false;
    for (int i = 0; i < num_rotors_; ++i) {
      const int k = esc_of_rotor[static_cast<size_t>(i)] >= 0 ? esc_of_rotor[static_cast<size_t>(i)] : Channel(i);
      const std::string field = "esc[" + std::to_string(k) + "].esc_rpm";
      if (!topic->HasField(field)) return std::nullopt;
      const std::vector<double> rpm = topic->Column(field);
      for (size_t j = 0; j < rpm.size(); ++j) {
        s.x(static_cast<Eigen::Index>(j), i) = std::abs(rpm[j]) * kRpmToRadps;
        any_nonzero = any_nonzero || rpm[j] != 0.0;
      }
    }
    if (!any_nonzero) return std::nullopt;
    s.label = "esc_status[0].esc[].esc_rpm";
    return s;
  }

  // A command topic through the command-to-speed map.
  std::optional<Stream> Command(const char* topic_name, int instance, const char* field_base) const {
    const ULogTopic* topic = Find(topic_name, instance);
    if (!topic) return std::nullopt;
    Stream s;
    s.t_us = topic->timestamps_us();
    s.x.resize(static_cast<Eigen::Index>(topic->num_messages()), num_rotors_);
    for (int i = 0; i < num_rotors_; ++i) {
      const std::string field = std::string(field_base) + "[" + std::to_string(Channel(i)) + "]";
      if (!topic->HasField(field))
        throw Error(log_.source + ": " + topic_name + " has no field " + field + " for rotor " + std::to_string(i + 1));
      const std::vector<double> u = topic->Column(field);
      for (size_t j = 0; j < u.size(); ++j) {
        // NaN is PX4's "motor stopped" (disarmed); the map never makes a negative speed.
        const double omega = std::isnan(u[j]) ? 0.0 : std::max(0.0, options_.command_map(u[j]));
        s.x(static_cast<Eigen::Index>(j), i) = omega;
      }
    }
    s.label = std::string(topic_name) + "[" + std::to_string(instance) + "]." + field_base;
    return s;
  }

  Stream LoadRotor(bool* is_command) {
    const std::string outputs = "actuator_outputs[" + std::to_string(options_.outputs_instance) + "].output";
    std::optional<Stream> s;
    *is_command = true;
    switch (options_.rotor) {
      case Px4RotorSource::kAuto:
        s = EscRpm();
        if (s) {
          *is_command = false;
          break;
        }
        [[fallthrough]];
      case Px4RotorSource::kCommand:
        s = Command("actuator_motors", 0, "control");
        if (!s) s = Command("actuator_outputs", options_.outputs_instance, "output");
        if (!s)
          Missing("rotor signal",
                  std::string(options_.rotor == Px4RotorSource::kAuto ? "esc_status (non-zero esc_rpm), " : "") +
                      "actuator_motors, " + outputs);
        break;
      case Px4RotorSource::kEscRpm:
        s = EscRpm();
        if (!s) Missing("measured rotor speed", "esc_status with non-zero esc[i].esc_rpm");
        *is_command = false;
        break;
      case Px4RotorSource::kActuatorMotors:
        s = Command("actuator_motors", 0, "control");
        if (!s) Missing("rotor command", "actuator_motors");
        break;
      case Px4RotorSource::kActuatorOutputs:
        s = Command("actuator_outputs", options_.outputs_instance, "output");
        if (!s) Missing("rotor command", outputs);
        break;
    }
    Finalize(&*s);
    if (s->t_us.size() < 2) Missing("usable rotor samples", s->label);
    return std::move(*s);
  }

  void LoadPose(std::optional<Stream>* position, std::optional<Stream>* attitude) {
    if (options_.pose == Px4PoseSource::kNone) return;
    const ULogTopic* odometry = Find("vehicle_visual_odometry");
    if (options_.pose == Px4PoseSource::kVisualOdometry && !odometry) Missing("pose", "vehicle_visual_odometry");
    if (odometry && options_.pose != Px4PoseSource::kEstimate) {
      // Position and orientation of the body in a z-down world (NED, or FRD with arbitrary heading).
      const std::string position_base = odometry->HasField("position[0]") ? "position" : "";
      const std::vector<std::string> position_fields =
          position_base.empty() ? std::vector<std::string>{"x", "y", "z"} : Vec3Fields(position_base);
      Stream p;
      p.t_us = SampleTimes(*odometry);
      p.x = Columns(*odometry, position_fields);
      p.label = "vehicle_visual_odometry[0]." + (position_base.empty() ? std::string("x,y,z") : position_base);
      if (!p.x.col(0).array().isNaN().all()) *position = std::move(p);
      if (odometry->HasField("q[0]")) {
        Stream q;
        q.t_us = SampleTimes(*odometry);
        q.x = Columns(*odometry, {"q[0]", "q[1]", "q[2]", "q[3]"});
        q.label = "vehicle_visual_odometry[0].q";
        if (!q.x.col(0).array().isNaN().all()) *attitude = std::move(q);
      }
    }
    if (!*position) {
      if (const ULogTopic* local = Find("vehicle_local_position")) {
        Stream p;
        p.t_us = SampleTimes(*local);
        p.x = Columns(*local, {"x", "y", "z"});
        p.label = "vehicle_local_position[0].x,y,z";
        *position = std::move(p);
      }
    }
    if (!*attitude) {
      if (const ULogTopic* estimate = Find("vehicle_attitude")) {
        Stream q;
        q.t_us = SampleTimes(*estimate);
        q.x = Columns(*estimate, {"q[0]", "q[1]", "q[2]", "q[3]"});
        q.label = "vehicle_attitude[0].q";
        *attitude = std::move(q);
      }
    }
    for (auto* s : {position, attitude}) {
      if (!*s) continue;
      DropNanRows(&**s);
      Finalize(&**s);
      if ((*s)->t_us.size() < 2) s->reset();
    }
    if (!*position || !*attitude) {
      if (options_.pose != Px4PoseSource::kAuto)
        Missing("pose", "vehicle_visual_odometry or vehicle_attitude + vehicle_local_position");
      position->reset();  // a track needs both
      attitude->reset();
      return;
    }
    FlipYZ(&(*position)->x);
  }

  void DropNanRows(Stream* s) {
    std::vector<Eigen::Index> keep;
    for (Eigen::Index r = 0; r < s->x.rows(); ++r)
      if (!s->x.row(r).array().isNaN().any()) keep.push_back(r);
    if (keep.size() == static_cast<size_t>(s->x.rows())) return;
    dropped_samples_ += static_cast<int>(s->x.rows()) - static_cast<int>(keep.size());
    Stream out;
    out.label = s->label;
    out.x.resize(static_cast<Eigen::Index>(keep.size()), s->x.cols());
    for (size_t k = 0; k < keep.size(); ++k) {
      out.x.row(static_cast<Eigen::Index>(k)) = s->x.row(keep[k]);
      out.t_us.push_back(s->t_us[static_cast<size_t>(keep[k])]);
    }
    *s = std::move(out);
  }

  // Interpolates the quaternion (sign-aligned, renormalised) and converts R_ned_frd to the z-up world
  // and FLU body: R = F R_ned_frd F, F = diag(1, -1, -1); then Bryant angles, unwrapped over time.
  MocapTrack MakeMocap(const Stream& position, const Stream& attitude, uint64_t t0_us,
                       const Eigen::VectorXd& t_s) const {
    MocapTrack track;
    track.position_w_m = InterpolateLinear(SecondsSince(position.t_us, t0_us), position.x, t_s);
    Eigen::MatrixXd q = attitude.x;
    for (Eigen::Index r = 1; r < q.rows(); ++r)
      if (q.row(r).dot(q.row(r - 1)) < 0.0) q.row(r) *= -1.0;
    const Eigen::MatrixXd q_t = InterpolateLinear(SecondsSince(attitude.t_us, t0_us), q, t_s);
    const Eigen::Matrix3d flip = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
    track.bryant_rad.resize(t_s.size(), 3);
    for (Eigen::Index r = 0; r < t_s.size(); ++r) {
      Eigen::Quaterniond q_ned_frd(q_t(r, 0), q_t(r, 1), q_t(r, 2), q_t(r, 3));
      q_ned_frd.normalize();
      const Eigen::Matrix3d r_w_b = flip * q_ned_frd.toRotationMatrix() * flip;
      track.bryant_rad.row(r) = RotationToBryant(r_w_b).transpose();
    }
    track.bryant_rad.col(0) = UnwrapAngle(track.bryant_rad.col(0));
    track.bryant_rad.col(2) = UnwrapAngle(track.bryant_rad.col(2));
    return track;
  }

  std::optional<Stream> LoadBattery() {
    const ULogTopic* battery = Find("battery_status");
    if (!battery || !battery->HasField("voltage_v")) return std::nullopt;
    Stream s;
    s.t_us = battery->timestamps_us();
    s.x = Columns(*battery, {"voltage_v"});
    s.label = "battery_status[0].voltage_v";
    DropNanRows(&s);
    Finalize(&s);
    if (s.t_us.empty()) return std::nullopt;
    return s;
  }

  const ULog& log_;
  int num_rotors_;
  const Px4FlightOptions& options_;
  int dropped_samples_ = 0;
};

double ParameterOr(const ULog& log, const std::string& name, double fallback) {
  const ULogParameter* p = log.FindParameter(name);
  return p ? p->value() : fallback;
}

}  // namespace

std::string CommandToSpeedMap::Validate() const {
  if (!std::isfinite(offset_radps) || !std::isfinite(gain_radps_per_unit))
    return "command-to-speed map must have finite offset and gain";
  if (gain_radps_per_unit <= 0.0) return "command-to-speed gain must be positive";
  return {};
}

std::string Px4FlightOptions::Validate() const {
  if (const std::string problem = command_map.Validate(); !problem.empty()) return problem;
  if (imu_instance < 0 || imu_instance > 255) return "IMU instance must be a multi id 0..255";
  if (outputs_instance < 0 || outputs_instance > 255) return "actuator_outputs instance must be a multi id 0..255";
  for (const int channel : rotor_channels)
    if (channel < 0 || channel > 255) return "rotor channels must be 0..255, got " + std::to_string(channel);
  if (!std::isfinite(rate_hz) || rate_hz < 0.0) return "rate must be 0 (IMU time base) or a positive rate in Hz";
  return {};
}

FlightLog Px4FlightFromULog(const ULog& log, int num_rotors, const Px4FlightOptions& options) {
  return Px4Mapper(log, num_rotors, options).Map();
}

FlightLog ReadPx4Flight(const std::string& path, int num_rotors, const Px4FlightOptions& options) {
  ULogReadOptions read_options;
  read_options.topics = {"sensor_combined",
                         "vehicle_angular_velocity",
                         "vehicle_acceleration",
                         "vehicle_imu",
                         "esc_status",
                         "actuator_motors",
                         "actuator_outputs",
                         "vehicle_attitude",
                         "vehicle_local_position",
                         "vehicle_visual_odometry",
                         "battery_status"};
  return Px4FlightFromULog(ReadULog(path, read_options), num_rotors, options);
}

Vehicle SuggestVehicleFromPx4Parameters(const ULog& log, const std::string& name) {
  const ULogParameter* count = log.FindParameter("CA_ROTOR_COUNT");
  if (!count)
    throw Error(log.source +
                ": no CA_ROTOR_COUNT parameter (control allocation, PX4 >= 1.13); give the rotor "
                "geometry in the vehicle file");
  const int n = static_cast<int>(count->value());
  if (n <= 0 || n > kMaxMotors)
    throw Error(log.source + ": CA_ROTOR_COUNT is " + std::to_string(n) + "; expected 1.." +
                std::to_string(kMaxMotors));
  Vehicle vehicle;
  vehicle.name = name;
  vehicle.mass_kg = 0.0;  // unknown: PX4 does not log the mass
  for (int i = 0; i < n; ++i) {
    const std::string prefix = "CA_ROTOR" + std::to_string(i) + "_";
    Rotor rotor;
    // FRD -> FLU.
    rotor.position_m = Eigen::Vector3d(ParameterOr(log, prefix + "PX", 0.0), -ParameterOr(log, prefix + "PY", 0.0),
                                       -ParameterOr(log, prefix + "PZ", 0.0));
    // PX4: KM > 0 for a rotor turning counter-clockwise seen from above (its reaction torque yaws the body
    // clockwise, +z in FRD); that is rotorid's spin = +1 (angular velocity along +z up). PX4's default is 0.05.
    const double km = ParameterOr(log, prefix + "KM", 0.05);
    if (km == 0.0)
      throw Error(log.source + ": " + prefix + "KM is 0, so the turning direction of rotor " + std::to_string(i + 1) +
                  " is unknown");
    rotor.spin = km > 0.0 ? 1 : -1;
    vehicle.rotors.push_back(rotor);
  }
  return vehicle;
}

}  // namespace rotorid

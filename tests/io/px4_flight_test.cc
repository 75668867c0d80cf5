#include "rotorid/io/px4_flight.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/model/rotation.h"
#include "rotorid/signal/resample.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::optional<std::string> SamplePath(const std::string& name) {
  return testing::SharedDataPath("ulog-samples/" + name);
}

void ExpectErrorContaining(const std::function<void()>& f, const std::vector<std::string>& fragments) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one containing '" << fragments.front() << "'";
  } catch (const Error& e) {
    for (const std::string& fragment : fragments)
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what() << "\n  lacks: " << fragment;
  }
}

// A small ULog writer: formats, parameters, subscriptions and data.
class ULogWriter {
 public:
  ULogWriter() {
    const uint8_t magic[8] = {0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01};
    bytes_.append(reinterpret_cast<const char*>(magic), 8);
    Put(uint64_t{0});
  }
  template <typename T>
  static std::string Pod(T value) {
    return std::string(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  template <typename T>
  void Put(T value) {
    bytes_ += Pod(value);
  }
  void Message(char type, const std::string& body) {
    Put(static_cast<uint16_t>(body.size()));
    bytes_ += type;
    bytes_ += body;
  }
  void ParameterFloat(const std::string& name, float value) {
    const std::string key = "float " + name;
    Message('P', std::string(1, static_cast<char>(key.size())) + key + Pod(value));
  }
  void ParameterInt(const std::string& name, int32_t value) {
    const std::string key = "int32_t " + name;
    Message('P', std::string(1, static_cast<char>(key.size())) + key + Pod(value));
  }
  // Topic with a uint64 timestamp followed by float fields (names as in the format).
  void Topic(uint16_t msg_id, const std::string& name, const std::string& float_fields) {
    Message('F', name + ":uint64_t timestamp;" + float_fields);
    pending_.push_back({msg_id, name});
  }
  void Subscribe() {
    for (const auto& [id, name] : pending_) Message('A', std::string(1, '\0') + Pod(id) + name);
    pending_.clear();
  }
  void Data(uint16_t msg_id, uint64_t t_us, const std::vector<float>& values) {
    std::string body = Pod(msg_id) + Pod(t_us);
    for (float v : values) body += Pod(v);
    Message('D', body);
  }
  void RawData(uint16_t msg_id, const std::string& payload) { Message('D', Pod(msg_id) + payload); }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
  std::vector<std::pair<uint16_t, std::string>> pending_;
};

ULog ParseBytes(const std::string& bytes) { return ParseULog(bytes.data(), bytes.size(), "synthetic.ulg"); }

// A synthetic hover-like log with known values in FRD/NED.
struct SyntheticLog {
  Eigen::Vector3d gyro_frd{0.1, 0.2, 0.3};
  Eigen::Vector3d acc_frd{0.5, -0.4, -9.7};
  Eigen::Vector3d position_ned{1.0, 2.0, -3.0};
  Eigen::Vector3d roll_pitch_yaw_ned{0.1, 0.2, 0.5};  // PX4's Euler angles (ZYX) of R_ned_frd
  bool with_imu = true, with_motors = true, with_esc = false;
  uint64_t imu_step_back_us = 0;  // the IMU's clock steps back by this much half way (a time reset)

  std::string Build() const {
    ULogWriter w;
    w.ParameterInt("CA_ROTOR_COUNT", 4);
    const float px[4] = {0.15f, -0.15f, 0.15f, -0.15f}, py[4] = {0.25f, -0.2f, -0.25f, 0.2f},
                km[4] = {0.05f, 0.05f, -0.05f, -0.05f};
    for (int i = 0; i < 4; ++i) {
      const std::string p = "CA_ROTOR" + std::to_string(i) + "_";
      w.ParameterFloat(p + "PX", px[i]);
      w.ParameterFloat(p + "PY", py[i]);
      w.ParameterFloat(p + "PZ", 0.02f);
      w.ParameterFloat(p + "KM", km[i]);
    }
    if (with_imu) w.Topic(1, "sensor_combined", "float[3] gyro_rad;float[3] accelerometer_m_s2;");
    if (with_motors) w.Topic(2, "actuator_motors", "float[12] control;");
    w.Topic(3, "vehicle_attitude", "float[4] q;");
    w.Topic(4, "vehicle_local_position", "float x;float y;float z;");
    w.Topic(5, "battery_status", "float voltage_v;");
    if (with_esc) {
      w.Message('F', "esc_report:uint64_t timestamp;int32_t esc_rpm;uint8_t actuator_function;uint8_t[3] _padding0;");
      w.Message('F', "esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[4] esc;");
      w.Message('A', std::string(1, '\0') + ULogWriter::Pod<uint16_t>(6) + "esc_status");
    }
    w.Subscribe();
    const Eigen::Quaterniond q(Eigen::AngleAxisd(roll_pitch_yaw_ned.z(), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(roll_pitch_yaw_ned.y(), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(roll_pitch_yaw_ned.x(), Eigen::Vector3d::UnitX()));
    for (int k = 0; k < 400; ++k) {  // 2 s at 200 Hz
      const uint64_t t = 1000000 + 5000 * static_cast<uint64_t>(k);
      if (with_imu)
        w.Data(1, k >= 200 ? t - imu_step_back_us : t,
               {float(gyro_frd.x()), float(gyro_frd.y()), float(gyro_frd.z()), float(acc_frd.x()), float(acc_frd.y()),
                float(acc_frd.z())});
      if (k % 10 == 0) {  // 20 Hz
        std::vector<float> control(12, std::nanf(""));
        for (int i = 0; i < 4; ++i) control[static_cast<size_t>(i)] = 0.1f * float(i + 1) + (k >= 200 ? 0.5f : 0.0f);
        if (with_motors) w.Data(2, t + 1000, control);
        w.Data(3, t, {float(q.w()), float(q.x()), float(q.y()), float(q.z())});
        w.Data(4, t, {float(position_ned.x()), float(position_ned.y()), float(position_ned.z())});
        w.Data(5, t, {15.5f});
        if (with_esc) {
          std::string payload = ULogWriter::Pod(t) + std::string(1, '\4') + std::string(7, '\0');
          // ESC k drives motor function 101 + (3 - k): reversed order.
          for (int e = 0; e < 4; ++e)
            payload += ULogWriter::Pod(t) + ULogWriter::Pod<int32_t>(-1000 * (e + 1)) +
                       std::string(1, static_cast<char>(101 + 3 - e)) + std::string(3, '\0');
          w.RawData(6, payload);
        }
      }
    }
    return w.bytes();
  }
};

// ---------------------------------------------------------------------------------------------
// Synthetic: the conversions, exactly

TEST(Px4FlightSynthetic, FrdNedToFluZUpAndCommandMap) {
  const SyntheticLog synthetic;
  const ULog log = ParseBytes(synthetic.Build());
  Px4FlightOptions options;
  options.command_map = {50.0, 1000.0};
  const FlightLog flight = Px4FlightFromULog(log, 4, options);

  // Window: IMU from 1.000 s, motors from 1.001 s, pose to 2.950 s.
  EXPECT_EQ(flight.metadata.at("px4_t0_us"), "1001000");
  EXPECT_DOUBLE_EQ(flight.t_s[0], 0.004);  // first IMU sample at or after the motors' first
  EXPECT_EQ(flight.metadata.at("px4_rotor_signal"), "command");
  for (int r = 0; r < flight.num_samples(); ++r) {
    EXPECT_NEAR(flight.gyro_radps(r, 0), 0.1, 1e-6);
    EXPECT_NEAR(flight.gyro_radps(r, 1), -0.2, 1e-6);
    EXPECT_NEAR(flight.gyro_radps(r, 2), -0.3, 1e-6);
    EXPECT_NEAR(flight.acc_mps2(r, 0), 0.5, 1e-6);
    EXPECT_NEAR(flight.acc_mps2(r, 1), 0.4, 1e-6);
    EXPECT_NEAR(flight.acc_mps2(r, 2), 9.7, 1e-5);
  }
  // Command map Omega = 50 + 1000 u, held between publications (motors published at +1 ms).
  const int before = 100, after = 250;  // rows at t = 1.405 s and 2.005 s
  EXPECT_NEAR(flight.rotor_radps(before, 0), 150.0, 1e-3);
  EXPECT_NEAR(flight.rotor_radps(before, 3), 450.0, 1e-3);
  EXPECT_NEAR(flight.rotor_radps(after, 1), 50.0 + 1000.0 * 0.7, 1e-3);

  ASSERT_TRUE(flight.mocap.has_value());
  EXPECT_TRUE(flight.mocap->position_w_m.row(0).isApprox(Eigen::RowVector3d(1.0, -2.0, 3.0), 1e-6));
  // F R_ned_frd F with F = diag(1, -1, -1): roll kept, pitch and yaw change sign.
  EXPECT_NEAR(flight.mocap->bryant_rad(0, 0), 0.1, 1e-6);
  EXPECT_NEAR(flight.mocap->bryant_rad(0, 1), -0.2, 1e-6);
  EXPECT_NEAR(flight.mocap->bryant_rad(0, 2), -0.5, 1e-6);
  // The specific force of a vehicle at rest is R^T [0, 0, g] in both conventions.
  const Eigen::Matrix3d r_w_b = BryantToRotation(flight.mocap->bryant_rad.row(0).transpose());
  const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Vector3d acc_ned_static(0, 0, -9.81);
  const Eigen::Matrix3d r_ned_frd = flip * r_w_b * flip;
  EXPECT_TRUE((flip * (r_ned_frd.transpose() * acc_ned_static))
                  .isApprox(r_w_b.transpose() * Eigen::Vector3d(0, 0, 9.81), 1e-9));

  ASSERT_TRUE(flight.voltage_v.has_value());
  EXPECT_NEAR((*flight.voltage_v)[0], 15.5, 1e-6);
  EXPECT_GE(flight.t_s[flight.num_samples() - 1], 0.9);
  for (int r = 1; r < flight.num_samples(); ++r) ASSERT_GT(flight.t_s[r], flight.t_s[r - 1]);
}

// A time reset of the IMU half way would drop every later sample up to the old time: an error naming
// the topic and the step, not a flight silently cut (issue 42, item 8). A repeated stamp still passes.
TEST(Px4FlightSynthetic, ImuTimeResetIsAnErrorNotASilentLoss) {
  SyntheticLog synthetic;
  synthetic.imu_step_back_us = 600000;
  ExpectErrorContaining([&] { Px4FlightFromULog(ParseBytes(synthetic.Build()), 4, {}); },
                        {"synthetic.ulg", "sensor_combined", "step back by 0.595 s", "120 of 400 samples"});
  synthetic.imu_step_back_us = 5000;  // one repeated stamp
  const FlightLog flight = Px4FlightFromULog(ParseBytes(synthetic.Build()), 4, {});
  EXPECT_EQ(flight.metadata.at("px4_dropped_samples"), "2");  // in the gyro and the accelerometer stream
}

TEST(Px4FlightSynthetic, EscRpmMatchedByActuatorFunction) {
  SyntheticLog synthetic;
  synthetic.with_esc = true;
  const ULog log = ParseBytes(synthetic.Build());
  const FlightLog flight = Px4FlightFromULog(log, 4);
  EXPECT_EQ(flight.metadata.at("px4_rotor_signal"), "measured");
  // Rotor 1 (motor function 101) is driven by ESC 3, which reports -4000 rpm.
  EXPECT_NEAR(flight.rotor_radps(10, 0), 4000.0 * 2.0 * kPi / 60.0, 1e-9);
  EXPECT_NEAR(flight.rotor_radps(10, 3), 1000.0 * 2.0 * kPi / 60.0, 1e-9);

  Px4FlightOptions command;
  command.rotor = Px4RotorSource::kCommand;
  EXPECT_EQ(Px4FlightFromULog(log, 4, command).metadata.at("px4_rotor_signal"), "command");
}

TEST(Px4FlightSynthetic, UniformRateAndChannels) {
  const ULog log = ParseBytes(SyntheticLog().Build());
  Px4FlightOptions options;
  options.rate_hz = 100.0;
  options.rotor_channels = {3, 2, 1, 0};
  options.pose = Px4PoseSource::kNone;
  const FlightLog flight = Px4FlightFromULog(log, 4, options);
  // The grid is the signal module's uniform time base over the common span.
  const Eigen::VectorXd grid = UniformTimeBase(0.0, flight.t_s[flight.num_samples() - 1], 100.0);
  ASSERT_EQ(grid.size(), flight.t_s.size());
  EXPECT_TRUE(grid.isApprox(flight.t_s));
  EXPECT_NEAR(flight.MedianDt(), 0.01, 1e-12);
  EXPECT_DOUBLE_EQ(flight.t_s[0], 0.0);
  EXPECT_FALSE(flight.mocap.has_value());
  EXPECT_NEAR(flight.rotor_radps(10, 0), 0.4, 1e-6);  // channel 3, identity map
  EXPECT_NEAR(flight.rotor_radps(10, 3), 0.1, 1e-6);
}

TEST(Px4FlightSynthetic, MissingTopicsNameTheFileAndWhatWasLookedFor) {
  SyntheticLog no_imu;
  no_imu.with_imu = false;
  const ULog log_no_imu = ParseBytes(no_imu.Build());
  ExpectErrorContaining([&] { Px4FlightFromULog(log_no_imu, 4); },
                        {"synthetic.ulg", "no IMU data", "sensor_combined", "vehicle_angular_velocity",
                         "vehicle_acceleration", "vehicle_imu"});
  SyntheticLog no_rotor;
  no_rotor.with_motors = false;
  const ULog log_no_rotor = ParseBytes(no_rotor.Build());
  ExpectErrorContaining([&] { Px4FlightFromULog(log_no_rotor, 4); },
                        {"synthetic.ulg", "no rotor signal", "esc_status", "actuator_motors", "actuator_outputs"});
  Px4FlightOptions rpm;
  rpm.rotor = Px4RotorSource::kEscRpm;
  ExpectErrorContaining([&] { Px4FlightFromULog(ParseBytes(SyntheticLog().Build()), 4, rpm); },
                        {"synthetic.ulg", "measured rotor speed", "esc_status"});
  Px4FlightOptions odometry;
  odometry.pose = Px4PoseSource::kVisualOdometry;
  ExpectErrorContaining([&] { Px4FlightFromULog(ParseBytes(SyntheticLog().Build()), 4, odometry); },
                        {"synthetic.ulg", "vehicle_visual_odometry"});
  Px4FlightOptions bad;
  bad.command_map.gain_radps_per_unit = 0.0;
  ExpectErrorContaining([&] { Px4FlightFromULog(ParseBytes(SyntheticLog().Build()), 4, bad); }, {"gain"});
  ExpectErrorContaining([&] { Px4FlightFromULog(ParseBytes(SyntheticLog().Build()), 13); }, {"13 rotors"});
}

TEST(Px4FlightSynthetic, VehicleFromControlAllocationParameters) {
  const ULog log = ParseBytes(SyntheticLog().Build());
  const Vehicle vehicle = SuggestVehicleFromPx4Parameters(log, "quad");
  EXPECT_EQ(vehicle.name, "quad");
  EXPECT_EQ(vehicle.mass_kg, 0.0);
  ASSERT_EQ(vehicle.num_rotors(), 4);
  EXPECT_TRUE(vehicle.rotors[0].position_m.isApprox(Eigen::Vector3d(0.15, -0.25, -0.02), 1e-6));  // front right
  EXPECT_EQ(vehicle.rotors[0].spin, 1);   // KM > 0: counter-clockwise seen from above
  EXPECT_EQ(vehicle.rotors[2].spin, -1);  // KM < 0: clockwise
  // num_rotors <= 0 takes CA_ROTOR_COUNT.
  EXPECT_EQ(Px4FlightFromULog(log, 0).num_rotors(), 4);
}

// ---------------------------------------------------------------------------------------------
// The sample logs

TEST(Px4FlightSamples, SitlFlightWithMeasuredRpm) {
  const auto path = SamplePath("sample_px4_events.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const FlightLog flight = ReadPx4Flight(*path, 4);
  EXPECT_EQ(flight.metadata.at("px4_rotor_signal"), "measured");
  EXPECT_EQ(flight.metadata.at("px4_imu"), "sensor_combined[0].gyro_rad + sensor_combined[0].accelerometer_m_s2");
  EXPECT_GT(flight.num_samples(), 7000);
  EXPECT_NEAR(flight.MedianDt(), 0.004, 1e-4);
  EXPECT_NEAR(flight.acc_mps2.col(2).mean(), 9.8, 0.2);  // FLU: +g on z
  EXPECT_GE(flight.rotor_radps.minCoeff(), 0.0);
  EXPECT_GT(flight.rotor_radps.maxCoeff(), 100.0);
  ASSERT_TRUE(flight.mocap && flight.voltage_v);
  EXPECT_GT(flight.mocap->position_w_m.col(2).maxCoeff(), 1.5);  // took off to about 2.5 m: z up

  const Vehicle vehicle = SuggestVehicleFromPx4Parameters(ReadULog(*path));
  ASSERT_EQ(vehicle.num_rotors(), 4);
  EXPECT_TRUE(vehicle.rotors[0].position_m.isApprox(Eigen::Vector3d(0.1515, -0.245, 0.0), 1e-6));
  EXPECT_EQ((std::vector<int>{vehicle.rotors[0].spin, vehicle.rotors[1].spin, vehicle.rotors[2].spin,
                              vehicle.rotors[3].spin}),
            (std::vector<int>{1, 1, -1, -1}));
}

// sample.ulg was waved around by hand (up to several rad/s on every axis): a good frame check.
TEST(Px4FlightSamples, GyroAccAndAttitudeAgreeOnAHandHeldLog) {
  const auto path = SamplePath("sample.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const FlightLog flight = ReadPx4Flight(*path, 4);
  EXPECT_EQ(flight.metadata.at("px4_rotor"), "actuator_outputs[0].output");
  ASSERT_TRUE(flight.mocap.has_value());
  // Specific force ~ R^T [0, 0, g] when the motion is slow: checks acc and attitude frames together.
  std::vector<double> residual;
  for (int r = 0; r < flight.num_samples(); r += 10) {
    const Eigen::Matrix3d r_w_b = BryantToRotation(flight.mocap->bryant_rad.row(r).transpose());
    const Eigen::Vector3d expected = r_w_b.transpose() * Eigen::Vector3d(0, 0, kStandardGravity);
    residual.push_back((flight.acc_mps2.row(r).transpose() - expected).norm());
  }
  std::nth_element(residual.begin(), residual.begin() + residual.size() / 2, residual.end());
  EXPECT_LT(residual[residual.size() / 2], 0.6);
  EXPECT_NEAR(flight.acc_mps2.col(0).mean(), 1.1, 0.3);  // tilted nose-up: +x in FLU

  // The gyro agrees with the attitude's rate of change: LogSO3(R_k^T R_k+n) / dt ~ mean gyro.
  const int n = 25;
  std::vector<Eigen::Vector3d> from_attitude, from_gyro;
  for (int k = 0; k + n < flight.num_samples(); k += n) {
    const Eigen::Matrix3d r0 = BryantToRotation(flight.mocap->bryant_rad.row(k).transpose());
    const Eigen::Matrix3d r1 = BryantToRotation(flight.mocap->bryant_rad.row(k + n).transpose());
    from_attitude.push_back(LogSO3(r0.transpose() * r1) / (flight.t_s[k + n] - flight.t_s[k]));
    from_gyro.push_back(flight.gyro_radps.middleRows(k, n).colwise().mean().transpose());
  }
  for (int axis = 0; axis < 3; ++axis) {
    double sxy = 0, sxx = 0, syy = 0;
    for (size_t i = 0; i < from_gyro.size(); ++i) {
      sxy += from_gyro[i][axis] * from_attitude[i][axis];
      sxx += from_gyro[i][axis] * from_gyro[i][axis];
      syy += from_attitude[i][axis] * from_attitude[i][axis];
    }
    EXPECT_GT(sxy / std::sqrt(sxx * syy), 0.95) << "axis " << axis;  // same sign and shape
  }
  ExpectErrorContaining([&] { SuggestVehicleFromPx4Parameters(ReadULog(*path)); }, {"sample.ulg", "CA_ROTOR_COUNT"});
  Px4FlightOptions rpm;
  rpm.rotor = Px4RotorSource::kEscRpm;
  ExpectErrorContaining([&] { ReadPx4Flight(*path, 4, rpm); }, {"sample.ulg", "esc_status"});
}

TEST(Px4FlightSamples, AlternativeImuTopics) {
  const auto path = SamplePath("sample_px4_events.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  const ULog log = ReadULog(*path);
  const FlightLog combined = Px4FlightFromULog(log, 4);
  for (const Px4ImuSource source : {Px4ImuSource::kAngularVelocity, Px4ImuSource::kVehicleImu}) {
    Px4FlightOptions options;
    options.imu = source;
    const FlightLog flight = Px4FlightFromULog(log, 4, options);
    EXPECT_NEAR(flight.acc_mps2.col(2).mean(), combined.acc_mps2.col(2).mean(), 0.1);
    EXPECT_LT((flight.gyro_radps.colwise().mean() - combined.gyro_radps.colwise().mean()).norm(), 0.01);
  }
}

TEST(Px4FlightSamples, DispatcherReadsULog) {
  const auto path = SamplePath("sample_px4_events.ulg");
  if (!path) GTEST_SKIP() << "ulog-samples absent";
  Vehicle vehicle;
  vehicle.rotors.resize(4);
  EXPECT_EQ(DetectLogFormat(*path), LogFormat::kULog);
  EXPECT_EQ(LoadFlightLog(*path, vehicle).metadata.at("px4_rotor_signal"), "measured");
  FlightSourceOptions command;
  command.rotor_signal = "command";
  EXPECT_EQ(LoadFlightLog(*path, vehicle, command).metadata.at("px4_rotor_signal"), "command");
}

}  // namespace
}  // namespace rotorid

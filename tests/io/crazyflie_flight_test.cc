#include "rotorid/io/crazyflie_flight.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/column_map.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/model/rotation.h"
#include "rotorid/signal/resample.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A uSD log written as the firmware writes it (version 2).
class LogWriter {
 public:
  LogWriter() { bytes_ = std::string("\xBC\x02\x00", 3); }
  template <typename T>
  LogWriter& Put(T v) {
    bytes_.append(reinterpret_cast<const char*>(&v), sizeof(v));
    return *this;
  }
  LogWriter& Str(const std::string& s) {
    bytes_ += s;
    bytes_.push_back('\0');
    return *this;
  }
  LogWriter& Event(uint16_t id, const std::string& name, const std::vector<std::string>& variables) {
    Put(id).Str(name).Put(static_cast<uint16_t>(variables.size()));
    for (const auto& v : variables) Str(v);
    return *this;
  }
  std::string Finish() const {
    std::string out = bytes_;
    const uint32_t crc = Crc32(out.data(), out.size());
    out.append(reinterpret_cast<const char*>(&crc), 4);
    return out;
  }

 private:
  std::string bytes_;
};

struct SyntheticOptions {
  bool rpm = true;
  bool pwm = true;
  bool pose = true;
  int records = 100;
};

// 500 Hz IMU with rpm, pwm and battery, and a 100 Hz pose that yaws through +-pi with
// quaternions of alternating sign.
std::string SyntheticLog(const SyntheticOptions& o = {}) {
  LogWriter w;
  w.Put(static_cast<uint16_t>(o.pose ? 2 : 1));
  std::vector<std::string> vars = {"gyro.x(f)", "gyro.y(f)", "gyro.z(f)", "acc.x(f)", "acc.y(f)", "acc.z(f)"};
  for (int m = 1; m <= 4 && o.rpm; ++m) vars.push_back("rpm.m" + std::to_string(m) + "(H)");
  for (int m = 1; m <= 4 && o.pwm; ++m)
    vars.push_back("pwm.m" + std::to_string(m) + "_pwm(" + (m == 4 ? "I" : "H") + ")");
  vars.push_back("pm.vbatMV(H)");
  w.Event(0xFFFF, "fixedFrequency", vars);
  if (o.pose) {
    w.Event(
        8, "estPose",
        {"locSrv.x(f)", "locSrv.y(f)", "locSrv.z(f)", "locSrv.qx(f)", "locSrv.qy(f)", "locSrv.qz(f)", "locSrv.qw(f)"});
  }
  const uint64_t t0 = 5000000;
  for (int i = 0; i < o.records; ++i) {
    w.Put(static_cast<uint16_t>(0xFFFF)).Put(static_cast<uint64_t>(t0 + 2000 * i));
    w.Put(90.0f).Put(-45.0f).Put(static_cast<float>(i)).Put(0.0f).Put(0.0f).Put(1.0f);
    for (int m = 1; m <= 4 && o.rpm; ++m) w.Put(static_cast<uint16_t>(18000 + 100 * m));
    for (int m = 1; m <= 4 && o.pwm; ++m) {
      if (m == 4) {
        w.Put(static_cast<uint32_t>(65535));
      } else {
        w.Put(static_cast<uint16_t>(13107 * m));
      }
    }
    w.Put(static_cast<uint16_t>(3700));
    if (o.pose && i % 5 == 1) {
      // Yaw runs from 170 deg up by 2 deg per pose sample: it crosses +180 -> -180.
      const double yaw = (170.0 + 2.0 * (i / 5)) * kPi / 180.0;
      const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
      const double sign = (i / 5) % 2 ? -1.0 : 1.0;
      w.Put(static_cast<uint16_t>(8)).Put(static_cast<uint64_t>(t0 + 2000 * i + 300));
      w.Put(0.1f * (i / 5)).Put(0.0f).Put(0.7f);
      w.Put(static_cast<float>(sign * q.x()))
          .Put(static_cast<float>(sign * q.y()))
          .Put(static_cast<float>(sign * q.z()))
          .Put(static_cast<float>(sign * q.w()));
    }
  }
  return w.Finish();
}

FlightLog FromBytes(const std::string& bytes, const CrazyflieFlightOptions& options = {}, int num_rotors = 4) {
  return CrazyflieUsdToFlight(ParseCrazyflieUsd(bytes, "cf.bin"), num_rotors, options);
}

TEST(CrazyflieFlight, ConvertsUnitsAndPrefersMeasuredRpm) {
  const FlightLog log = FromBytes(SyntheticLog());
  ASSERT_EQ(log.num_samples(), 100);
  EXPECT_DOUBLE_EQ(log.t_s[0], 5.0);
  EXPECT_DOUBLE_EQ(log.t_s[1], 5.002);
  EXPECT_DOUBLE_EQ(log.gyro_radps(0, 0), kPi / 2);
  EXPECT_DOUBLE_EQ(log.gyro_radps(0, 1), -kPi / 4);
  EXPECT_DOUBLE_EQ(log.acc_mps2(0, 2), kStandardGravity);
  EXPECT_DOUBLE_EQ(log.rotor_radps(0, 0), 18100 * 2 * kPi / 60);
  EXPECT_DOUBLE_EQ(log.rotor_radps(0, 3), 18400 * 2 * kPi / 60);
  ASSERT_TRUE(log.voltage_v.has_value());
  EXPECT_DOUBLE_EQ((*log.voltage_v)[7], 3.7);
  EXPECT_EQ(log.metadata.at("rotor_signal"), "speed");
  EXPECT_EQ(log.metadata.at("rotor_signal_source"), "rpm.m1..rpm.m4 (rpm -> rad/s)");
  EXPECT_EQ(log.metadata.at("source_format"), "crazyflie_usd v2");
}

TEST(CrazyflieFlight, CommandIsNormalisedPwm) {
  CrazyflieFlightOptions options;
  options.rotor_signal = "command";
  const FlightLog log = FromBytes(SyntheticLog(), options);
  EXPECT_DOUBLE_EQ(log.rotor_radps(0, 0), 0.2);
  EXPECT_DOUBLE_EQ(log.rotor_radps(0, 2), 0.6);
  EXPECT_DOUBLE_EQ(log.rotor_radps(0, 3), 1.0);
  EXPECT_EQ(log.metadata.at("rotor_signal"), "command");
  // Without rpm, auto falls back on the command.
  SyntheticOptions no_rpm;
  no_rpm.rpm = false;
  EXPECT_EQ(FromBytes(SyntheticLog(no_rpm)).metadata.at("rotor_signal"), "command");
}

void ExpectError(const std::string& bytes, const std::string& fragment, const CrazyflieFlightOptions& options = {},
                 int num_rotors = 4) {
  try {
    FromBytes(bytes, options, num_rotors);
    ADD_FAILURE() << "no error; expected " << fragment;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(CrazyflieFlight, MissingVariablesNameWhatWasLookedFor) {
  SyntheticOptions no_rpm;
  no_rpm.rpm = false;
  CrazyflieFlightOptions rpm;
  rpm.rotor_signal = "rpm";
  ExpectError(SyntheticLog(no_rpm),
              "cf.bin: event 'fixedFrequency' has no measured rotor speed rpm.m1, rpm.m2, rpm.m3, "
              "rpm.m4 (looked for rpm.m1..rpm.m4; the event logs: gyro.x, gyro.y",
              rpm);
  SyntheticOptions neither = no_rpm;
  neither.pwm = false;
  ExpectError(SyntheticLog(neither),
              "has no rotor signal (looked for rpm.m1..rpm.m4 or pwm.m1_pwm..pwm.m4_pwm or motor.m1..motor.m4");
  ExpectError(SyntheticLog(), "cf.bin: a Crazyflie log has 4 motors, the vehicle file has 6 rotors", {}, 6);
  CrazyflieFlightOptions other;
  other.imu_event = "imu";
  ExpectError(SyntheticLog(), "cf.bin: no event 'imu' with the IMU; the log has fixedFrequency (100 records), estPose",
              other);
  SyntheticOptions few;
  few.records = 10;
  ExpectError(SyntheticLog(few), "event 'fixedFrequency' has 10 records; at least 20 are needed");

  LogWriter w;
  w.Put(static_cast<uint16_t>(1)).Event(0xFFFF, "fixedFrequency", {"gyro.x(f)", "gyro.y(f)", "acc.x(f)"});
  ExpectError(w.Finish(), "has no gyro.z (looked for gyro.x, gyro.y, gyro.z; the event logs: gyro.x, gyro.y, acc.x)");
}

TEST(CrazyflieFlight, TimeMustIncrease) {
  LogWriter w;
  w.Put(static_cast<uint16_t>(1))
      .Event(0xFFFF, "fixedFrequency",
             {"gyro.x(f)", "gyro.y(f)", "gyro.z(f)", "acc.x(f)", "acc.y(f)", "acc.z(f)", "motor.m1(I)", "motor.m2(I)",
              "motor.m3(I)", "motor.m4(I)"});
  for (int i = 0; i < 30; ++i) {
    w.Put(static_cast<uint16_t>(0xFFFF)).Put(static_cast<uint64_t>(i == 20 ? 1000 : 1000 + i));
    for (int k = 0; k < 6; ++k) w.Put(0.0f);
    for (int k = 0; k < 4; ++k) w.Put(static_cast<uint32_t>(30000));
  }
  ExpectError(w.Finish(),
              "cf.bin: event 'fixedFrequency' record 20: time goes backwards or repeats (1000 us after 1019 us)");
}

TEST(CrazyflieFlight, NonFiniteValuesAreRefused) {
  LogWriter w;
  w.Put(static_cast<uint16_t>(1))
      .Event(0xFFFF, "fixedFrequency",
             {"gyro.x(f)", "gyro.y(f)", "gyro.z(f)", "acc.x(f)", "acc.y(f)", "acc.z(f)", "motor.m1(I)", "motor.m2(I)",
              "motor.m3(I)", "motor.m4(I)"});
  for (int i = 0; i < 30; ++i) {
    w.Put(static_cast<uint16_t>(0xFFFF)).Put(static_cast<uint64_t>(1000 + i));
    for (int k = 0; k < 6; ++k) w.Put(i == 7 && k == 4 ? std::numeric_limits<float>::quiet_NaN() : 0.0f);
    for (int k = 0; k < 4; ++k) w.Put(static_cast<uint32_t>(30000));
  }
  ExpectError(w.Finish(), "cf.bin: event 'fixedFrequency' record 7: acc.y is nan, not a finite number");
}

TEST(CrazyflieFlight, MocapIsResampledOntoImuTimesWithContinuousYaw) {
  const FlightLog log = FromBytes(SyntheticLog());
  ASSERT_TRUE(log.mocap.has_value());
  const MocapTrack& mocap = *log.mocap;
  ASSERT_EQ(mocap.position_w_m.rows(), 100);
  // Pose k is stamped at 5.0023 + 0.01 k s with x = 0.1 k; IMU sample 6 (5.012 s) lies 0.0097 s
  // after pose 0: x = 0.1 * 0.97.
  EXPECT_NEAR(mocap.position_w_m(6, 0), 0.097, 1e-6);
  EXPECT_NEAR(mocap.position_w_m(6, 2), 0.7, 1e-6);
  // Before the first pose the first one is held.
  EXPECT_NEAR(mocap.position_w_m(0, 0), 0.0, 1e-9);
  // Yaw is continuous through 180 deg although the quaternion's sign alternates.
  double max_step = 0.0;
  for (int i = 1; i < 100; ++i)
    max_step = std::max(max_step, std::abs(mocap.bryant_rad(i, 2) - mocap.bryant_rad(i - 1, 2)));
  EXPECT_LT(max_step, 2.1 * kPi / 180.0 / 5.0 + 1e-6);
  const double yaw_last = mocap.bryant_rad(99, 2);
  EXPECT_NEAR(std::remainder(yaw_last - (170.0 + 2.0 * 19) * kPi / 180.0, 2 * kPi), 0.0, 1e-5);
  EXPECT_GT(yaw_last, kPi);  // unwrapped
  // The same as unwrapping the wrapped angles with the signal module.
  Eigen::VectorXd wrapped = mocap.bryant_rad.col(2);
  for (int i = 0; i < wrapped.size(); ++i) wrapped[i] = std::remainder(wrapped[i], 2 * kPi);
  EXPECT_LT((UnwrapAngle(wrapped) - mocap.bryant_rad.col(2)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(mocap.bryant_rad(50, 0), 0.0, 1e-6);
  EXPECT_NEAR(mocap.bryant_rad(50, 1), 0.0, 1e-6);
  EXPECT_EQ(log.metadata.at("mocap_max_gap_s"), "0.0100");
  EXPECT_EQ(log.metadata.at("mocap_held_samples"), "5");  // 2 before the first pose, 3 after the last
}

// The firmware's IMU events (estGyroscope, estAcceleration at 1 kHz) beside a 100 Hz
// fixed-frequency block with the rotor signal: every value is linear in time, so the merge onto
// the gyro's times is exact, and gyro records outside the block's span are left out.
std::string EventImuLog(bool with_events) {
  LogWriter w;
  w.Put(static_cast<uint16_t>(3));
  w.Event(10, "estGyroscope", {"gyro.x(f)", "gyro.y(f)", "gyro.z(f)"});
  w.Event(11, "estAcceleration", {"acc.x(f)", "acc.y(f)", "acc.z(f)"});
  w.Event(0xFFFF, "fixedFrequency", {"rpm.m1(H)", "rpm.m2(H)", "rpm.m3(H)", "rpm.m4(H)", "pm.vbatMV(H)"});
  const uint64_t t0 = 2000000;
  for (int i = 0; i < 300; ++i) {
    const uint64_t t_us = t0 + 1000 * i;  // gyro at 1 kHz; acc 15 us later (as the firmware's)
    if (with_events) {
      w.Put(static_cast<uint16_t>(10)).Put(t_us).Put(static_cast<float>(i)).Put(0.0f).Put(0.0f);
      w.Put(static_cast<uint16_t>(11)).Put(t_us + 15).Put(0.0f).Put(0.0f).Put(static_cast<float>(1.0 + 1e-4 * i));
    }
    if (i % 10 == 3 && i < 290) {  // the block from 2.003 s to 2.283 s, every 10 ms
      w.Put(static_cast<uint16_t>(0xFFFF)).Put(t_us);
      for (int m = 1; m <= 4; ++m) w.Put(static_cast<uint16_t>(10000 + 10 * i + m));
      w.Put(static_cast<uint16_t>(4000 - i));
    }
  }
  return w.Finish();
}

TEST(CrazyflieFlight, ImuEventsMergeWithTheFixedFrequencyBlock) {
  const FlightLog log = FromBytes(EventImuLog(true));
  // Gyro records 3..283 lie inside the block's span: 281 samples at the gyro's own times.
  ASSERT_EQ(log.num_samples(), 281);
  EXPECT_DOUBLE_EQ(log.t_s[0], 2.003);
  EXPECT_DOUBLE_EQ(log.t_s[280], 2.283);
  for (int k = 0; k < log.num_samples(); ++k) {
    const int i = k + 3;  // the gyro record
    EXPECT_NEAR(log.gyro_radps(k, 0), i * kDegToRad, 1e-9);
    // The accelerometer at the gyro's time, 15 us before its own record: 1 + 1e-4 (i - 0.015).
    EXPECT_NEAR(log.acc_mps2(k, 2), (1.0 + 1e-4 * (i - 0.015)) * kStandardGravity, 2e-6);
    // The 100 Hz rpm between its records: 10000 + 10 i + m rev/min.
    EXPECT_NEAR(log.rotor_radps(k, 1), (10000.0 + 10.0 * i + 2.0) * kRpmToRadps, 1e-6);
    EXPECT_NEAR((*log.voltage_v)[k], (4000.0 - i) * 1e-3, 1e-9);
  }
  EXPECT_EQ(log.metadata.at("imu_event"),
            "estGyroscope (300 records, 1000.0 Hz) + estAcceleration (300 records, 1000.0 Hz)");
  EXPECT_EQ(log.metadata.at("rotor_signal_source"),
            "fixedFrequency rpm.m1..rpm.m4 (rpm -> rad/s), 100.0 Hz interpolated linearly onto the IMU times");
  EXPECT_NE(log.metadata.at("time_base").find("from 2.0030 to 2.2830 s, where every stream has records: 281 of 300"),
            std::string::npos)
      << log.metadata.at("time_base");
  // Without the events the block's missing gyro is named, and the events looked for.
  ExpectError(EventImuLog(false),
              "event 'fixedFrequency' has no gyro.x, gyro.y, gyro.z (looked for gyro.x, gyro.y, gyro.z; the event "
              "logs: rpm.m1, rpm.m2, rpm.m3, rpm.m4, pm.vbatMV), and the log has no records of the IMU events "
              "'estGyroscope' and 'estAcceleration'");
}

// Without estPose records the pose comes from the fixed-frequency block's compressed estimator
// state: mm, mm/s and the firmware's 32-bit quaternion (largest of x, y, z, w in the top 2 bits,
// then 3 x (sign, 9 bits)). Identity: 3 << 30; yaw +90 deg (z = w = 1/sqrt 2): 2 << 30 | 511.
TEST(CrazyflieFlight, EstimatorPoseFromTheCompressedState) {
  LogWriter w;
  w.Put(static_cast<uint16_t>(1));
  w.Event(0xFFFF, "fixedFrequency",
          {"gyro.x(f)", "gyro.y(f)", "gyro.z(f)", "acc.x(f)", "acc.y(f)", "acc.z(f)", "rpm.m1(H)", "rpm.m2(H)",
           "rpm.m3(H)", "rpm.m4(H)", "stateEstimateZ.x(h)", "stateEstimateZ.y(h)", "stateEstimateZ.z(h)",
           "stateEstimateZ.vx(h)", "stateEstimateZ.vy(h)", "stateEstimateZ.vz(h)", "stateEstimateZ.quat(I)"});
  for (int i = 0; i < 40; ++i) {
    w.Put(static_cast<uint16_t>(0xFFFF)).Put(static_cast<uint64_t>(1000000 + 2000 * i));
    for (int k = 0; k < 6; ++k) w.Put(k == 5 ? 1.0f : 0.0f);
    for (int m = 0; m < 4; ++m) w.Put(static_cast<uint16_t>(20000));
    w.Put(static_cast<int16_t>(10 * i)).Put(static_cast<int16_t>(-500)).Put(static_cast<int16_t>(470));
    w.Put(static_cast<int16_t>(5000)).Put(static_cast<int16_t>(0)).Put(static_cast<int16_t>(-250));
    w.Put(static_cast<uint32_t>(i < 20 ? 3u << 30 : (2u << 30) | 511u));
  }
  const FlightLog log = FromBytes(w.Finish());
  ASSERT_TRUE(log.mocap.has_value());
  ASSERT_TRUE(log.mocap->velocity_w_mps.has_value());
  EXPECT_TRUE(log.mocap->position_w_m.row(3).isApprox(Eigen::RowVector3d(0.03, -0.5, 0.47), 1e-12));
  EXPECT_TRUE(log.mocap->velocity_w_mps->row(3).isApprox(Eigen::RowVector3d(5.0, 0.0, -0.25), 1e-12));
  EXPECT_NEAR(log.mocap->bryant_rad(10, 2), 0.0, 1e-9);
  EXPECT_NEAR(log.mocap->bryant_rad(30, 2), kPi / 2, 1e-9);
  EXPECT_NEAR(log.mocap->bryant_rad(30, 0), 0.0, 1e-9);
  EXPECT_NE(log.metadata.at("mocap").find("stateEstimateZ"), std::string::npos) << log.metadata.at("mocap");
}

TEST(CrazyflieFlight, VehicleFilesDescribeTheCrazyflies) {
  const std::string dir = testing::SourceDir() + "/data/vehicles/";
  for (const auto& [file, name, mass] : std::vector<std::tuple<std::string, std::string, double>>{
           {"crazyflie21_brushed.yaml", "cf21_brushed", 0.0347},
           {"crazyflie21_brushless.yaml", "cf21_brushless", 0.037}}) {
    SCOPED_TRACE(file);
    const Vehicle v = ReadVehicleYaml(dir + file);
    EXPECT_EQ(v.name, name);
    EXPECT_DOUBLE_EQ(v.mass_kg, mass);
    ASSERT_EQ(v.num_rotors(), 4);
    const double a = 0.0325;
    const Eigen::Vector3d expected[4] = {{a, -a, 0}, {-a, -a, 0}, {-a, a, 0}, {a, a, 0}};
    const int spin[4] = {+1, -1, +1, -1};
    for (int r = 0; r < 4; ++r) {
      EXPECT_TRUE(v.rotors[r].position_m.isApprox(expected[r])) << r;
      EXPECT_EQ(v.rotors[r].spin, spin[r]) << r;
    }
  }
}

TEST(CrazyflieFlight, DispatcherReadsUsdLogsAndMappedCsv) {
  const std::string dir = testing::MakeTempDir("cf-flight");
  WriteFileAtomically(dir + "/log00", SyntheticLog());
  Vehicle quad;
  quad.mass_kg = 0.03;
  quad.rotors.resize(4);
  EXPECT_EQ(DetectLogFormat(dir + "/log00"), LogFormat::kCrazyflieUsd);
  FlightSourceOptions options;
  EXPECT_EQ(LoadFlightLog(dir + "/log00", quad, options).metadata.at("rotor_signal"), "speed");
  options.rotor_signal = "command";
  EXPECT_EQ(LoadFlightLog(dir + "/log00", quad, options).metadata.at("rotor_signal"), "command");

  std::string csv = "time_ms,gx,gy,gz,ax,ay,az,u1,u2,u3,u4\n";
  for (int i = 0; i < 30; ++i) csv += std::to_string(10 * i) + ",0,0,0,0,0,1,32767.5,32767.5,32767.5,65535\n";
  WriteFileAtomically(dir + "/export.csv", csv);
  WriteFileAtomically(dir + "/map.yaml", R"(time: {column: time_ms, unit: ms}
gyro: {columns: [gx, gy, gz], unit: deg/s}
acc: {columns: [ax, ay, az], unit: g}
rotors: {columns: [u1, u2, u3, u4], unit: pwm}
)");
  options.rotor_signal = "auto";
  options.column_map_path = dir + "/map.yaml";
  const FlightLog mapped = LoadFlightLog(dir + "/export.csv", quad, options);
  EXPECT_EQ(mapped.num_samples(), 30);
  EXPECT_DOUBLE_EQ(mapped.rotor_radps(3, 3), 1.0);
  EXPECT_DOUBLE_EQ(mapped.acc_mps2(0, 2), kStandardGravity);
  options.column_map_path = dir + "/absent.yaml";
  EXPECT_THROW(LoadFlightLog(dir + "/export.csv", quad, options), Error);
  std::filesystem::remove_all(dir);
}

// ---- Real flights ----

// The decoded CSV of a flight read through a column map, for comparison with the uSD reader.
ColumnMap ImrcMap(const std::string& rotors) {
  return ParseColumnMap(R"(time: {column: t_us, unit: us}
gyro: {columns: [gyro.x, gyro.y, gyro.z], unit: deg/s}
acc: {columns: [acc.x, acc.y, acc.z], unit: g}
voltage: {column: pm.vbatMV, unit: mV}
)" + rotors,
                        "imrc_map.yaml");
}

// Largest |a - b| / max(|a|, 1e-3 scale) over two matrices (the CSV prints 7 digits).
double MaxRelDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const double scale = std::max(1e-12, a.cwiseAbs().maxCoeff());
  double worst = 0.0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      const double denominator = std::max(std::abs(a(i, j)), 1e-6 * scale);
      worst = std::max(worst, std::abs(a(i, j) - b(i, j)) / denominator);
    }
  }
  return worst;
}

// Correlation of two series after a centred moving average over `window` samples.
double SmoothedCorrelation(const Eigen::VectorXd& a, const Eigen::VectorXd& b, int window) {
  const Eigen::Index n = a.size() - window;
  Eigen::VectorXd sa(n), sb(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    sa[i] = a.segment(i, window).mean();
    sb[i] = b.segment(i, window).mean();
  }
  sa.array() -= sa.mean();
  sb.array() -= sb.mean();
  return sa.dot(sb) / std::sqrt(sa.squaredNorm() * sb.squaredNorm());
}

TEST(CrazyflieFlightRealData, ImrcFlightsMatchTheirCsvAndVehicleFiles) {
  const auto root = testing::SharedDataPath("real/crazyflie-imrc-rpm");
  if (!root) GTEST_SKIP() << "shared IMRC Crazyflie data not present";
  int flights = 0;
  for (const std::string kind : {"brushed", "brushless"}) {
    const Vehicle vehicle = ReadVehicleYaml(testing::SourceDir() + "/data/vehicles/crazyflie21_" + kind + ".yaml");
    std::vector<std::string> raws;
    for (const auto& e : std::filesystem::directory_iterator(*root + "/" + kind + "/raw"))
      raws.push_back(e.path().string());
    std::sort(raws.begin(), raws.end());
    for (const std::string& raw : raws) {
      SCOPED_TRACE(raw);
      const std::string name = std::filesystem::path(raw).filename().string();
      const FlightLog log = LoadCrazyflieFlight(raw, vehicle.num_rotors());
      const std::string csv = *root + "/" + kind + "/csv/" + name + ".csv";
      const FlightLog speed =
          ReadMappedCsv(csv, ImrcMap("rotors: {columns: [rpm.m1, rpm.m2, rpm.m3, rpm.m4], unit: rpm}\n"), 4);
      const FlightLog command = ReadMappedCsv(
          csv, ImrcMap("rotors: {columns: [pwm.m1_pwm, pwm.m2_pwm, pwm.m3_pwm, pwm.m4_pwm], unit: pwm}\n"), 4);
      ++flights;
      ASSERT_EQ(log.num_samples(), speed.num_samples());
      EXPECT_EQ(log.metadata.at("rotor_signal"), "speed");
      // The same micro-second stamps, read as split seconds by the CSV reader: equal to the last bits.
      EXPECT_LE((log.t_s - speed.t_s).cwiseAbs().maxCoeff(), 1e-9);
      EXPECT_LE(MaxRelDiff(log.gyro_radps, speed.gyro_radps), 5e-7);
      EXPECT_LE(MaxRelDiff(log.acc_mps2, speed.acc_mps2), 5e-7);
      EXPECT_EQ(log.rotor_radps, speed.rotor_radps);
      EXPECT_EQ(*log.voltage_v, *speed.voltage_v);
      CrazyflieFlightOptions pwm;
      pwm.rotor_signal = "command";
      EXPECT_EQ(LoadCrazyflieFlight(raw, 4, pwm).rotor_radps, command.rotor_radps);

      // Mocap: present, and its attitude close to the onboard estimate's (the EKF fuses it).
      ASSERT_TRUE(log.mocap.has_value());
      const CrazyflieUsdLog usd = ReadCrazyflieUsd(raw);
      const UsdEventTable& imu = *usd.FindEvent("fixedFrequency");
      double sum_sq[3] = {0, 0, 0};
      for (int i = 0; i < log.num_samples(); ++i) {
        const Eigen::Quaterniond q_ekf(
            (*imu.FindColumn("stateEstimate.qw"))[i], (*imu.FindColumn("stateEstimate.qx"))[i],
            (*imu.FindColumn("stateEstimate.qy"))[i], (*imu.FindColumn("stateEstimate.qz"))[i]);
        const Eigen::Vector3d ekf = RotationToBryant(q_ekf.normalized().toRotationMatrix());
        for (int k = 0; k < 3; ++k) {
          const double d = std::remainder(log.mocap->bryant_rad(i, k) - ekf[k], 2 * kPi);
          sum_sq[k] += d * d;
        }
      }
      const double n = log.num_samples();
      const double rms_deg[3] = {std::sqrt(sum_sq[0] / n) * 180 / kPi, std::sqrt(sum_sq[1] / n) * 180 / kPi,
                                 std::sqrt(sum_sq[2] / n) * 180 / kPi};
      EXPECT_LT(rms_deg[0], 3.0);
      EXPECT_LT(rms_deg[1], 3.0);
      EXPECT_LT(rms_deg[2], 8.0);  // yaw: radio latency during fast yaw turns (jana06: 383 deg/s)

      // The vehicle file's geometry and spins: modelled torques from Omega^2 rise and fall with
      // the angular acceleration, on every axis.
      const int m = log.num_samples();
      Eigen::MatrixXd torque(m, 3);
      for (int i = 0; i < m; ++i) {
        Eigen::Vector3d tau = Eigen::Vector3d::Zero();
        for (int r = 0; r < 4; ++r) {
          const double w2 = log.rotor_radps(i, r) * log.rotor_radps(i, r);
          const Eigen::Vector3d& p = vehicle.rotors[r].position_m;
          tau += Eigen::Vector3d(p.y() * w2, -p.x() * w2, -vehicle.rotors[r].spin * 0.01 * w2);
        }
        torque.row(i) = tau.transpose();
      }
      Eigen::MatrixXd alpha = Eigen::MatrixXd::Zero(m, 3);
      for (int i = 1; i + 1 < m; ++i) {
        alpha.row(i) = (log.gyro_radps.row(i + 1) - log.gyro_radps.row(i - 1)) / (log.t_s[i + 1] - log.t_s[i - 1]);
      }
      double correlation[3];
      for (int k = 0; k < 3; ++k) correlation[k] = SmoothedCorrelation(torque.col(k), alpha.col(k), 25);
      std::cout << "  " << kind << "/" << name << ": " << m << " samples, mocap attitude vs EKF RMS " << rms_deg[0]
                << "/" << rms_deg[1] << "/" << rms_deg[2] << " deg; corr(torque, dw/dt) " << correlation[0] << "/"
                << correlation[1] << "/" << correlation[2] << "\n";
      // Roll and pitch everywhere; yaw where it is excited (jana04/06, eckart34 per SOURCE.md).
      EXPECT_GT(correlation[0], 0.0);
      EXPECT_GT(correlation[1], 0.0);
      if (name == "jana04" || name == "jana06" || name == "eckart34") {
        EXPECT_GT(correlation[2], 0.0);
      }
    }
  }
  EXPECT_EQ(flights, 7);
}

TEST(CrazyflieFlightRealData, ArplFlightsUseTheCommand) {
  const auto root = testing::SharedDataPath("real/crazyflie-arpl-sysid");
  if (!root) GTEST_SKIP() << "shared ARPL Crazyflie data not present";
  const ColumnMap map = ParseColumnMap(R"(time: {column: t_us, unit: us}
gyro: {columns: [gyro.x, gyro.y, gyro.z], unit: deg/s}
acc: {columns: [acc.x, acc.y, acc.z], unit: g}
rotors: {columns: [motor.m1, motor.m2, motor.m3, motor.m4], unit: pwm}
)",
                                       "arpl_map.yaml");
  for (const std::string name : {"log10", "log15", "log16"}) {
    SCOPED_TRACE(name);
    const FlightLog log = LoadCrazyflieFlight(*root + "/raw/" + name, 4);
    const FlightLog csv = ReadMappedCsv(*root + "/csv/" + name + ".csv", map, 4);
    EXPECT_EQ(log.metadata.at("rotor_signal"), "command");
    EXPECT_EQ(log.metadata.at("rotor_signal_source"), "motor.m1..motor.m4 (pwm / 65535)");
    EXPECT_FALSE(log.mocap.has_value());
    EXPECT_FALSE(log.voltage_v.has_value());
    ASSERT_EQ(log.num_samples(), csv.num_samples());
    EXPECT_LE((log.t_s - csv.t_s).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_EQ(log.rotor_radps, csv.rotor_radps);
    EXPECT_LE(MaxRelDiff(log.gyro_radps, csv.gyro_radps), 5e-7);
    EXPECT_LE(MaxRelDiff(log.acc_mps2, csv.acc_mps2), 5e-7);
    EXPECT_NEAR(log.MedianDt(), 1.0 / 1011, 3e-5);
    CrazyflieFlightOptions rpm;
    rpm.rotor_signal = "rpm";
    EXPECT_THROW(LoadCrazyflieFlight(*root + "/raw/" + name, 4, rpm), Error);
  }
}

// The micro-SD layout with the IMU as events (crazyflie-imrc-usd-events, SOURCE.md): 1009 Hz
// estGyroscope/estAcceleration beside a 504.5 Hz or 100.9 Hz fixed-frequency block with the RPM
// deck. `rotorid identify` on the two hover flights with the 39.0 g vehicle gives kt within 2 % of
// the source's 1.925e-8 N s^2 (plot_rpm.py's kf; measured 1.90e-8 and 1.89e-8).
TEST(CrazyflieFlightRealData, UsdEventImuHoverGivesTheSourcesKt) {
  const auto root = testing::SharedDataPath("real/crazyflie-imrc-usd-events/raw");
  if (!root) GTEST_SKIP() << "shared IMRC uSD event logs not present";
  const std::string dir = testing::MakeTempDir("cf-usd-events");
  std::string vehicle = testing::Slurp(testing::SourceDir() + "/data/vehicles/crazyflie21_brushed.yaml");
  const size_t mass_at = vehicle.find("\nmass: 0.0347\n");
  ASSERT_NE(mass_at, std::string::npos);
  vehicle.replace(mass_at, 14, "\nmass: 0.039\n");  // SOURCE.md: 39.0 g
  WriteFileAtomically(dir + "/cf39.yaml", vehicle);
  for (const auto& [name, block_hz] :
       std::vector<std::pair<std::string, double>>{{"hover_500hz", 504.5}, {"hover_100hz", 100.9}}) {
    SCOPED_TRACE(name);
    const std::string path = *root + "/" + name;
    const FlightLog log = LoadCrazyflieFlight(path, 4);
    EXPECT_NEAR(1.0 / log.MedianDt(), 1009.0, 5.0);
    EXPECT_NEAR(log.duration_s(), 3.0, 0.02);
    EXPECT_NE(log.metadata.at("rotor_signal_source").find(FormatValue("%.1f Hz", block_hz)), std::string::npos);
    EXPECT_NEAR(log.acc_mps2.col(2).mean(), kStandardGravity, 0.3);  // hover: about +g
    EXPECT_GT(log.rotor_radps.minCoeff(), 1500.0);                   // 18.7-23.5 k rpm: airborne throughout
    const testing::CommandResult run = testing::RunRotorid(
        {"identify", "--vehicle", dir + "/cf39.yaml", "--log", path, "--allow-partial", "--json", dir + "/id.json"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json report = nlohmann::json::parse(testing::Slurp(dir + "/id.json"));
    const double kt = report.at("linear").at("parameters").at("kt").at("value").get<double>();
    std::cout << "  " << name << ": kt " << kt << " N s^2 (source 1.925e-8)\n";
    EXPECT_NEAR(kt / 1.925e-8, 1.0, 0.02);
  }
  std::filesystem::remove_all(dir);
}

// The rotor-order check on a lagged command signal: jana01 driven by PWM through the vehicle's
// map lags the rotation by the motors' response (the RPM deck 12 ms, the command 53 ms). Measured
// at the lag that explains the angular acceleration best (chosen without the vehicle file), the
// correct file passes (roll/pitch correlation 0.75/0.86; at zero lag 0.35/0.66, a warning) and a
// swap of rotors 1 and 2 is still refused (pitch -0.10), with the RPM deck named as a swap.
TEST(CrazyflieFlightRealData, RotorOrderCheckAllowsForTheCommandsLag) {
  const auto path = testing::SharedDataPath("real/crazyflie-imrc-rpm/brushed/raw/jana01");
  if (!path) GTEST_SKIP() << "shared IMRC Crazyflie data not present";
  const std::string dir = testing::MakeTempDir("cf-rotor-order");
  const std::string correct = testing::SourceDir() + "/data/vehicles/crazyflie21_brushed.yaml";
  std::string swapped = testing::Slurp(correct);
  const std::string m1 = "  - {position: [ 0.0325, -0.0325, 0.0], spin: +1}  # M1 front-right, CCW\n";
  const std::string m2 = "  - {position: [-0.0325, -0.0325, 0.0], spin: -1}  # M2 back-right, CW\n";
  const size_t at = swapped.find(m1 + m2);
  ASSERT_NE(at, std::string::npos);
  swapped.replace(at, m1.size() + m2.size(), m2 + m1);
  WriteFileAtomically(dir + "/swapped.yaml", swapped);
  const auto rotor_order = [&](const std::string& vehicle, const std::string& signal) {
    const testing::CommandResult run =
        testing::RunRotorid({"identify", "--vehicle", vehicle, "--log", *path, "--allow-partial", "--rotor-signal",
                             signal, "--json", dir + "/id.json"});
    const nlohmann::json report = nlohmann::json::parse(testing::Slurp(dir + "/id.json"));
    for (const nlohmann::json& check : report.at("checks"))
      if (check.at("name") == "rotor_order") return check;
    ADD_FAILURE() << "no rotor_order check: " << run.err;
    return nlohmann::json();
  };
  const nlohmann::json command = rotor_order(correct, "command");
  EXPECT_EQ(command.at("status"), "ok") << command.at("message");
  EXPECT_NE(command.at("message").get<std::string>().find("ms earlier"), std::string::npos);
  EXPECT_EQ(rotor_order(correct, "rpm").at("status"), "ok");
  EXPECT_EQ(rotor_order(dir + "/swapped.yaml", "command").at("status"), "warning");
  const nlohmann::json rpm_swapped = rotor_order(dir + "/swapped.yaml", "rpm");
  EXPECT_EQ(rpm_swapped.at("status"), "error");
  EXPECT_NE(rpm_swapped.at("message").get<std::string>().find("rotors 1 and 2 appear swapped"), std::string::npos)
      << rpm_swapped.at("message");
  std::filesystem::remove_all(dir);
}

// The same on the project's simulator: a Crazyflie command log (PWM through the map, --battery)
// whose motors lag the command by tau = 60 ms. The check's lag follows tau (measured 52 ms; 28 ms
// for tau = 30 ms), and a swap of rotors 1 and 2 in the vehicle file is named.
TEST(CrazyflieFlight, RotorOrderLagFollowsTheSimulatedMotorLag) {
  const std::string dir = testing::MakeTempDir("cf-rotor-lag");
  const testing::CommandResult sim = testing::RunRotorid(
      {"simulate", "--preset", "CF", "--seconds", "20", "--seed", "3", "--effect", "motor_tau_s=0.06", "--battery",
       "--out", dir + "/f.csv", "--truth", dir + "/t.json", "--vehicle-out", dir + "/v.yaml"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto rotor_order = [&](const std::string& vehicle) {
    testing::RunRotorid(
        {"identify", "--vehicle", vehicle, "--log", dir + "/f.csv", "--allow-partial", "--json", dir + "/id.json"});
    const nlohmann::json report = nlohmann::json::parse(testing::Slurp(dir + "/id.json"));
    for (const nlohmann::json& check : report.at("checks"))
      if (check.at("name") == "rotor_order") return check;
    return nlohmann::json();
  };
  const nlohmann::json correct = rotor_order(dir + "/v.yaml");
  ASSERT_FALSE(correct.is_null());
  EXPECT_EQ(correct.at("status"), "ok") << correct.at("message");
  const std::string message = correct.at("message").get<std::string>();
  const size_t at = message.find("with the rotor signal ");
  ASSERT_NE(at, std::string::npos) << message;
  const double lag_ms = std::stod(message.substr(at + 22));
  EXPECT_GT(lag_ms, 40.0) << message;
  EXPECT_LT(lag_ms, 65.0) << message;

  // Rotors 1 and 2 exchanged in the vehicle file.
  std::string vehicle = testing::Slurp(dir + "/v.yaml");
  std::vector<size_t> lines;
  for (size_t p = vehicle.find("  - {position"); p != std::string::npos; p = vehicle.find("  - {position", p + 1))
    lines.push_back(p);
  ASSERT_GE(lines.size(), 2u);
  const size_t end1 = vehicle.find('\n', lines[0]) + 1, end2 = vehicle.find('\n', lines[1]) + 1;
  const std::string rotor1 = vehicle.substr(lines[0], end1 - lines[0]),
                    rotor2 = vehicle.substr(lines[1], end2 - lines[1]);
  vehicle.replace(lines[0], end2 - lines[0], rotor2 + rotor1);
  WriteFileAtomically(dir + "/swapped.yaml", vehicle);
  const nlohmann::json swapped = rotor_order(dir + "/swapped.yaml");
  ASSERT_FALSE(swapped.is_null());
  EXPECT_EQ(swapped.at("status"), "warning");  // a command signal: a warning, never an error
  EXPECT_NE(swapped.at("message").get<std::string>().find("rotors 1 and 2 appear swapped"), std::string::npos)
      << swapped.at("message");
  std::filesystem::remove_all(dir);
}

// The estimator pose of the uSD event logs (no estPose records): the attitude rate of the
// decompressed quaternion against the gyro events, the velocity against the position's slope, and
// the accelerometer rotated to the world against gravity, on figure8_100hz (12 s, up to 1 m/s).
TEST(CrazyflieFlightRealData, UsdEventEstimatorPoseAgreesWithTheImu) {
  const auto path = testing::SharedDataPath("real/crazyflie-imrc-usd-events/raw/figure8_100hz");
  if (!path) GTEST_SKIP() << "shared IMRC uSD event logs not present";
  const FlightLog log = LoadCrazyflieFlight(*path, 4);
  ASSERT_TRUE(log.mocap.has_value());
  ASSERT_TRUE(log.mocap->velocity_w_mps.has_value());
  const MocapTrack& m = *log.mocap;
  const int h = 50;  // +-50 ms for the slope (the block is at 100.9 Hz)
  Eigen::Vector3d slope_num = Eigen::Vector3d::Zero(), slope_den = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_error = Eigen::Vector3d::Zero(), velocity_power = Eigen::Vector3d::Zero();
  Eigen::Vector3d specific_force_w = Eigen::Vector3d::Zero();
  int count = 0;
  for (int k = h; k + h < log.num_samples(); ++k) {
    const Eigen::Matrix3d r0 = BryantToRotation(m.bryant_rad.row(k - 10).transpose());
    const Eigen::Matrix3d r1 = BryantToRotation(m.bryant_rad.row(k + 10).transpose());
    const Eigen::AngleAxisd step(r0.transpose() * r1);
    const Eigen::Vector3d w = step.axis() * step.angle() / (log.t_s[k + 10] - log.t_s[k - 10]);
    const Eigen::Vector3d gyro = log.gyro_radps.middleRows(k - 10, 21).colwise().mean().transpose();
    slope_num += w.cwiseProduct(gyro);
    slope_den += gyro.cwiseProduct(gyro);
    const Eigen::Vector3d slope =
        (m.position_w_m.row(k + h) - m.position_w_m.row(k - h)).transpose() / (log.t_s[k + h] - log.t_s[k - h]);
    const Eigen::Vector3d v = m.velocity_w_mps->row(k).transpose();
    velocity_error += (v - slope).cwiseAbs2();
    velocity_power += v.cwiseAbs2();
    specific_force_w += BryantToRotation(m.bryant_rad.row(k).transpose()) * log.acc_mps2.row(k).transpose();
    ++count;
  }
  const Eigen::Vector3d rate_slope = slope_num.cwiseQuotient(slope_den);
  const Eigen::Vector3d velocity_rms = (velocity_error / count).cwiseSqrt(),
                        speed_rms = (velocity_power / count).cwiseSqrt();
  specific_force_w /= count;
  std::cout << "  figure8_100hz: " << log.metadata.at("mocap") << "\n  attitude rate / gyro " << rate_slope.transpose()
            << "; velocity RMS " << speed_rms.transpose() << " m/s, error RMS " << velocity_rms.transpose()
            << "; mean specific force (world) " << specific_force_w.transpose() << "\n";
  for (int a = 0; a < 2; ++a) {  // roll and pitch (yaw barely moves: no yaw excitation)
    EXPECT_NEAR(rate_slope[a], 1.0, 0.1) << a;
    EXPECT_LT(velocity_rms[a], 0.2 * speed_rms[a]) << a;
  }
  EXPECT_LT(std::hypot(specific_force_w[0], specific_force_w[1]), 0.3);
  EXPECT_NEAR(specific_force_w[2], kStandardGravity, 0.3);
}

}  // namespace
}  // namespace rotorid

#include "rotorid/io/column_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/rotation.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

const char* kBasicMap = R"(# a Crazyflie CSV export
time: {column: t_us, unit: us}
gyro: {columns: [gyro.x, gyro.y, gyro.z], unit: deg/s}
acc:  {columns: [acc.x, acc.y, acc.z], unit: g}
rotors: {columns: [rpm.m1, rpm.m2, rpm.m3, rpm.m4], unit: rpm}
rotor_commands: {columns: [pwm.m1, pwm.m2, pwm.m3, pwm.m4], unit: pwm}
voltage: {column: vbat, unit: mV}
frame: flu
metadata: {vehicle: cf21}
)";

// A small CSV with every column kBasicMap names, plus a text column the map ignores.
std::string BasicCsv(int rows = 25) {
  std::string csv =
      "t_us,gyro.x,gyro.y,gyro.z,acc.x,acc.y,acc.z,rpm.m1,rpm.m2,rpm.m3,rpm.m4,pwm.m1,pwm.m2,pwm.m3,pwm.m4,"
      "vbat,mode\n";
  for (int i = 0; i < rows; ++i) {
    csv += std::to_string(1000000000000LL + 2000LL * i) + ",90,-180," + std::to_string(i) +
           ",0,0.5,1,6000,12000,60,0," + "65535,32767.5,0,13107,3700,hover\n";
  }
  return csv;
}

TEST(ColumnMap, ParsesTheExampleMap) {
  const ColumnMap map = ParseColumnMap(kBasicMap, "map.yaml");
  EXPECT_EQ(map.time.columns, std::vector<std::string>{"t_us"});
  EXPECT_DOUBLE_EQ(map.time.unit_factor, 1e-6);
  EXPECT_DOUBLE_EQ(map.gyro.unit_factor, kDeg);
  EXPECT_DOUBLE_EQ(map.acc.unit_factor, kStandardGravity);
  ASSERT_TRUE(map.rotors && map.rotor_commands && map.voltage);
  EXPECT_FALSE(map.rotors->is_command);
  EXPECT_TRUE(map.rotor_commands->is_command);
  EXPECT_EQ(map.rotors->location.line, 5);
  EXPECT_EQ(map.rotors->column_locations[1].line, 5);
  EXPECT_EQ(map.rotors->column_locations[1].column, 28);
  EXPECT_EQ(map.metadata.at("vehicle"), "cf21");
  EXPECT_FALSE(map.position.has_value());
}

TEST(ColumnMap, ConvertsUnitsToRotoridConventions) {
  const ColumnMap map = ParseColumnMap(kBasicMap, "map.yaml");
  const FlightLog log = ParseMappedCsv(BasicCsv(), "export.csv", map, 4);
  ASSERT_EQ(log.num_samples(), 25);
  // 1e12 us, a wall clock: counted from the first stamp, whose digits the metadata keep; the 2 ms
  // steps stay exact.
  EXPECT_EQ(log.t_s[0], 0.0);
  EXPECT_EQ(log.metadata.at("time_origin_s"), "1000000.000000000");
  EXPECT_EQ(log.t_s[1], 0.002);
  EXPECT_DOUBLE_EQ(log.gyro_radps(3, 0), kPi / 2);
  EXPECT_DOUBLE_EQ(log.gyro_radps(3, 1), -kPi);
  EXPECT_DOUBLE_EQ(log.gyro_radps(3, 2), 3 * kDeg);
  EXPECT_DOUBLE_EQ(log.acc_mps2(0, 1), 0.5 * kStandardGravity);
  EXPECT_DOUBLE_EQ(log.acc_mps2(0, 2), kStandardGravity);
  EXPECT_DOUBLE_EQ(log.rotor_radps(0, 0), 6000 * 2 * kPi / 60);
  EXPECT_DOUBLE_EQ(log.rotor_radps(0, 2), 2 * kPi);
  ASSERT_TRUE(log.voltage_v.has_value());
  EXPECT_DOUBLE_EQ((*log.voltage_v)[0], 3.7);
  EXPECT_EQ(log.metadata.at("rotor_signal"), "speed");
  EXPECT_EQ(log.metadata.at("rotor_signal_unit"), "rpm");
  EXPECT_EQ(log.metadata.at("vehicle"), "cf21");
  EXPECT_EQ(log.metadata.at("column_map"), "map.yaml");
}

TEST(ColumnMap, RotorSignalChoosesSpeedOrCommand) {
  const ColumnMap map = ParseColumnMap(kBasicMap, "map.yaml");
  const FlightLog command = ParseMappedCsv(BasicCsv(), "export.csv", map, 4, "command");
  EXPECT_EQ(command.metadata.at("rotor_signal"), "command");
  EXPECT_DOUBLE_EQ(command.rotor_radps(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(command.rotor_radps(0, 1), 0.5);
  EXPECT_DOUBLE_EQ(command.rotor_radps(0, 3), 0.2);
  EXPECT_EQ(ParseMappedCsv(BasicCsv(), "export.csv", map, 4, "rpm").metadata.at("rotor_signal"), "speed");

  const ColumnMap pwm_only = ParseColumnMap(R"(time: {column: t_us, unit: us}
gyro: {columns: [gyro.x, gyro.y, gyro.z], unit: deg/s}
acc: {columns: [acc.x, acc.y, acc.z], unit: g}
rotors: {columns: [pwm.m1, pwm.m2, pwm.m3, pwm.m4], unit: pwm}
)",
                                            "pwm.yaml");
  EXPECT_EQ(ParseMappedCsv(BasicCsv(), "export.csv", pwm_only, 4).metadata.at("rotor_signal"), "command");
  try {
    ParseMappedCsv(BasicCsv(), "export.csv", pwm_only, 4, "rpm");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pwm.yaml: rotor signal 'rpm' asked for"), std::string::npos) << e.what();
  }
  try {
    ParseMappedCsv(BasicCsv(), "export.csv", pwm_only, 6);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pwm.yaml:4:1: the map lists 4 rotor columns, the vehicle has 6"),
              std::string::npos)
        << e.what();
  }
}

TEST(ColumnMap, CommandUnitsAndRanges) {
  std::string csv = "t,a,b,c,d,e,f,u1,u2\n";
  for (int i = 0; i < 20; ++i) csv += std::to_string(i * 0.01) + ",0,0,0,0,0,9.8,1500,950\n";
  const FlightLog us = ParseMappedCsv(csv, "x.csv",
                                      ParseColumnMap(R"(time: {column: t, unit: s}
gyro: {columns: [a, b, c], unit: rad/s}
acc: {columns: [d, e, f], unit: m/s^2}
rotors: {columns: [u1, u2], unit: us}
)",
                                                     "m.yaml"));
  EXPECT_DOUBLE_EQ(us.rotor_radps(0, 0), 0.5);
  EXPECT_DOUBLE_EQ(us.rotor_radps(0, 1), 0.0);  // below the range: motor stopped, clamped
  const FlightLog ranged = ParseMappedCsv(csv, "x.csv",
                                          ParseColumnMap(R"(time: {column: t, unit: s}
gyro: {columns: [a, b, c], unit: rad/s}
acc: {columns: [d, e, f], unit: m/s^2}
rotors: {columns: [u1, u2], unit: us, range: [900, 1900]}
)",
                                                         "m.yaml"));
  EXPECT_DOUBLE_EQ(ranged.rotor_radps(0, 0), 0.6);
  EXPECT_DOUBLE_EQ(ranged.rotor_radps(0, 1), 0.05);
}

TEST(ColumnMap, FrdLogsBecomeFlu) {
  // A PX4-style export: FRD body, NED world, heading 30 deg (clockwise from north), pitched up
  // 10 deg, rolled right 5 deg; hovering, so the accelerometer reads -g on z_FRD.
  const double roll = 5 * kDeg, pitch = 10 * kDeg, yaw = 30 * kDeg;
  const Eigen::Quaterniond q_ned_frd(BryantToRotation(Eigen::Vector3d(roll, pitch, yaw)));
  std::string csv = "time,gx,gy,gz,ax,ay,az,m1,m2,m3,m4,x,y,z,qw,qx,qy,qz,roll,pitch,yaw\n";
  char row[512];
  for (int i = 0; i < 20; ++i) {
    std::snprintf(row, sizeof(row),
                  "%d,0.1,0.2,0.3,0.0,0.0,-9.8,0.5,0.5,0.5,0.5,1.0,2.0,-3.0,%.17g,%.17g,%.17g,%.17g,%g,%g,%g\n",
                  i * 4000, q_ned_frd.w(), q_ned_frd.x(), q_ned_frd.y(), q_ned_frd.z(), 5.0, 10.0, 30.0);
    csv += row;
  }
  const std::string common = R"(time: {column: time, unit: us}
gyro: {columns: [gx, gy, gz], unit: rad/s}
acc: {columns: [ax, ay, az], unit: m/s^2}
rotors: {columns: [m1, m2, m3, m4], unit: normalized}
position: {columns: [x, y, z], unit: m}
frame: frd
)";
  const FlightLog with_q =
      ParseMappedCsv(csv, "px4.csv", ParseColumnMap(common + "quaternion: {columns: [qw, qx, qy, qz]}\n", "q.yaml"));
  const FlightLog with_e = ParseMappedCsv(
      csv, "px4.csv", ParseColumnMap(common + "euler: {columns: [roll, pitch, yaw], unit: deg}\n", "e.yaml"));
  for (const FlightLog* log : {&with_q, &with_e}) {
    EXPECT_DOUBLE_EQ(log->gyro_radps(0, 0), 0.1);
    EXPECT_DOUBLE_EQ(log->gyro_radps(0, 1), -0.2);
    EXPECT_DOUBLE_EQ(log->gyro_radps(0, 2), -0.3);
    EXPECT_DOUBLE_EQ(log->acc_mps2(0, 2), 9.8);
    ASSERT_TRUE(log->mocap.has_value());
    EXPECT_DOUBLE_EQ(log->mocap->position_w_m(0, 1), -2.0);
    EXPECT_DOUBLE_EQ(log->mocap->position_w_m(0, 2), 3.0);  // 3 m below NED's origin is 3 m up
    // In a z-up world with an FLU body the same attitude reads roll 5, pitch -10, yaw -30 deg.
    EXPECT_NEAR(log->mocap->bryant_rad(0, 0), roll, 1e-12);
    EXPECT_NEAR(log->mocap->bryant_rad(0, 1), -pitch, 1e-12);
    EXPECT_NEAR(log->mocap->bryant_rad(0, 2), -yaw, 1e-12);
  }
}

TEST(ColumnMap, DelimitersQuotesCommentsAndSkippedLines) {
  std::string csv = "exported by tool X\nversion 3\n# comment\n\"t\" ; \"g x\" ; gy ; gz ; ax ; ay ; az ; r1 ; note\n";
  for (int i = 0; i < 20; ++i) csv += std::to_string(i) + " ; 1 ; 2 ; 3 ; 0 ; 0 ; 9.81 ; 100 ; \"a;b\"\n";
  csv += "# trailing comment\n\n";
  const ColumnMap map = ParseColumnMap(R"(time: {column: t, unit: ms}
gyro: {columns: ["g x", gy, gz], unit: rad/s}
acc: {columns: [ax, ay, az], unit: m/s^2}
rotors: {columns: [r1], unit: rad/s}
delimiter: ";"
skip_lines: 2
)",
                                       "semi.yaml");
  const FlightLog log = ParseMappedCsv(csv, "semi.csv", map);
  ASSERT_EQ(log.num_samples(), 20);
  EXPECT_DOUBLE_EQ(log.t_s[19], 0.019);
  EXPECT_DOUBLE_EQ(log.gyro_radps(5, 0), 1.0);
  EXPECT_EQ(log.num_rotors(), 1);

  std::string ws = "t gx gy gz ax ay az r1\n";
  for (int i = 0; i < 20; ++i) ws += std::to_string(i) + "\t 1  2 3 0 0 9.81 100\n";
  const FlightLog spaced = ParseMappedCsv(ws, "ws.txt",
                                          ParseColumnMap(R"(time: {column: t, unit: s}
gyro: {columns: [gx, gy, gz], unit: rad/s}
acc: {columns: [ax, ay, az], unit: m/s^2}
rotors: {columns: [r1], unit: rad/s}
delimiter: whitespace
)",
                                                         "ws.yaml"));
  EXPECT_EQ(spaced.num_samples(), 20);
  EXPECT_DOUBLE_EQ(spaced.gyro_radps(0, 2), 3.0);
}

void ExpectMapError(const std::string& yaml, const std::string& fragment) {
  try {
    ParseColumnMap(yaml, "bad.yaml");
    ADD_FAILURE() << "no error; expected " << fragment;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(ColumnMap, MapErrorsNameFileLineAndColumn) {
  const std::string base =
      "time: {column: t, unit: s}\ngyro: {columns: [a, b, c], unit: rad/s}\n"
      "acc: {columns: [d, e, f], unit: g}\n";
  ExpectMapError(base, "bad.yaml: missing 'rotors'");
  ExpectMapError(base + "rotors: {columns: [m1], unit: krpm}\n", "bad.yaml:4:31: unknown unit 'krpm' for rotors");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm}\nspeed: 3\n", "bad.yaml:5:1: unknown key 'speed'");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm, offset: 2}\n",
                 "bad.yaml:4:36: unknown key 'offset' in rotors");
  ExpectMapError("time: {column: t, unit: s}\ngyro: {columns: [a, b], unit: rad/s}\n",
                 "bad.yaml:2:17: gyro lists 2 columns, expected 3");
  ExpectMapError("gyro: {columns: [a, b, c], unit: rad/s}\n", "bad.yaml: missing 'time'");
  ExpectMapError("time: {column: t}\n", "bad.yaml:1:7: time needs a unit (s, ms, us, ns)");
  ExpectMapError("time: [t]\n", "bad.yaml:1:7: time must be a mapping");
  ExpectMapError("time: {columns: t, unit: s}\n", "bad.yaml:1:17: time columns must be a list");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm, range: [0, 1]}\n", "range applies to command units only");
  ExpectMapError(base + "rotors: {columns: [m1], unit: pwm, range: [5, 1]}\n", "range must have high > low");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm}\nposition: {columns: [x, y, z], unit: m}\n",
                 "bad.yaml:5:1: position needs an orientation too");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm}\nquaternion: {columns: [w, x, y, z], unit: rad}\n",
                 "quaternion takes no unit");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm}\nframe: ned\n", "bad.yaml:5:8: frame must be flu or frd");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm}\ndelimiter: \";;\"\n", "delimiter must be one character");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm}\ngravity: -1\n", "gravity must be positive");
  ExpectMapError("time: {column: t, unit: s\n", "bad.yaml:2:1: not valid YAML");
  ExpectMapError("- a\n- b\n", "bad.yaml: a column map must be a YAML mapping");
  ExpectMapError(base + "rotors: {columns: [m1], unit: rpm}\nrotor_commands: {columns: [u1], unit: rpm}\n",
                 "bad.yaml:5:39: unknown unit 'rpm' for rotor_commands (known: pwm, us, normalized, percent)");
}

void ExpectCsvError(const std::string& csv, const std::string& fragment, const std::string& map_text = kBasicMap) {
  try {
    ParseMappedCsv(csv, "data.csv", ParseColumnMap(map_text, "map.yaml"), 4);
    ADD_FAILURE() << "no error; expected " << fragment;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(ColumnMap, CsvErrorsNameFileLineAndColumn) {
  const std::string good = BasicCsv();
  std::string missing = good;
  missing.replace(missing.find("rpm.m2"), 6, "rpm.mX");
  ExpectCsvError(missing, "data.csv:1: no column 'rpm.m2' (named at map.yaml:5:28); the header has: t_us, gyro.x");
  std::string not_number = good;
  not_number.replace(not_number.find(",-180,", not_number.find('\n', not_number.find('\n') + 1)), 6, ",-1x0,");
  ExpectCsvError(not_number, "data.csv:3:18: column 'gyro.y' holds '-1x0', not a finite number");
  std::string nan = good;
  nan.replace(nan.find(",3700,"), 6, ",nan,");
  ExpectCsvError(nan, "data.csv:2:71: column 'vbat' holds 'nan', not a finite number");
  ExpectCsvError(good + "1,2,3\n", "data.csv:27: row has 3 cells, the header has 17");
  ExpectCsvError(good + std::to_string(1000000000000LL) + ",0,0,0,0,0,1,1,1,1,1,1,1,1,1,3700,x\n",
                 "data.csv:27: time goes backwards or repeats");
  std::string negative = good;
  negative.replace(negative.find(",6000,"), 6, ",-600,");
  ExpectCsvError(negative, "data.csv:2: column 'rpm.m1' holds a negative rotor speed");
  ExpectCsvError(BasicCsv(5), "data.csv: too few samples (5)");
  ExpectCsvError("# only a comment\n", "data.csv: no header line");
  std::string duplicated = good;
  duplicated.replace(duplicated.find(",mode"), 5, ",acc.z");
  ExpectCsvError(duplicated, "data.csv:1:39: column 'acc.z' appears more than once in the header");
  // Unreferenced columns may hold anything, even duplicates and text.
  std::string ignored = good;
  ignored.replace(ignored.find(",mode"), 5, ",vbat2");
  EXPECT_NO_THROW(ParseMappedCsv(ignored, "data.csv", ParseColumnMap(kBasicMap, "map.yaml"), 4));
}

// ---- Real exports ----

std::string NanobenchMap(const std::string& orientation) {
  return R"(time: {column: t, unit: s}
gyro: {columns: [imu_gyro_x, imu_gyro_y, imu_gyro_z], unit: rad/s}
acc: {columns: [imu_acc_x, imu_acc_y, imu_acc_z], unit: g}
rotors: {columns: [motor_motor_m1, motor_motor_m2, motor_motor_m3, motor_motor_m4], unit: pwm}
position: {columns: [px, py, pz], unit: m}
voltage: {column: pwr_pm_vbat, unit: V}
)" + orientation;
}

TEST(ColumnMapRealData, ReadsNanobenchExports) {
  const auto folder = testing::SharedDataPath("real/nanobench-cf21");
  if (!folder) GTEST_SKIP() << "shared NanoBench data not present";
  const ColumnMap with_q = ParseColumnMap(NanobenchMap("quaternion: {columns: [qw, qx, qy, qz]}\n"), "nb_q.yaml");
  // The roll/pitch/yaw columns hold radians (SOURCE.md says degrees; the quaternion says radians).
  const ColumnMap with_e =
      ParseColumnMap(NanobenchMap("euler: {columns: [roll, pitch, yaw], unit: rad}\n"), "nb_e.yaml");
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(*folder)) {
    if (entry.path().extension() != ".csv") continue;
    SCOPED_TRACE(entry.path().string());
    const FlightLog a = ReadMappedCsv(entry.path().string(), with_q, 4);
    const FlightLog b = ReadMappedCsv(entry.path().string(), with_e, 4);
    ++files;
    EXPECT_GT(a.num_samples(), 4200);
    EXPECT_NEAR(a.MedianDt(), 0.01, 1e-4);
    EXPECT_EQ(a.metadata.at("rotor_signal"), "command");
    EXPECT_LE(a.rotor_radps.maxCoeff(), 1.0);
    EXPECT_GE(a.rotor_radps.minCoeff(), 0.0);
    ASSERT_TRUE(a.mocap && b.mocap && a.voltage_v);
    EXPECT_GT(a.voltage_v->minCoeff(), 2.5);
    // At rest before take-off: specific force about +g on z, gyro about 0.
    EXPECT_NEAR(a.acc_mps2(0, 2), kStandardGravity, 0.3);
    double worst = 0.0;
    for (int i = 0; i < a.num_samples(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const double d = std::remainder(a.mocap->bryant_rad(i, k) - b.mocap->bryant_rad(i, k), 2 * kPi);
        worst = std::max(worst, std::abs(d));
      }
    }
    EXPECT_LT(worst, 2e-6) << "quaternion and euler columns disagree";
    std::cout << "  " << entry.path().filename().string() << ": " << a.num_samples() << " samples, " << a.duration_s()
              << " s; quaternion vs euler max " << worst << " rad\n";
  }
  EXPECT_EQ(files, 5);
}

}  // namespace
}  // namespace rotorid

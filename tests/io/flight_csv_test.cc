#include "rotorid/io/flight_csv.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "rotorid/core/error.h"

namespace rotorid {
namespace {

const std::string kHeader = "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,rotor_1,rotor_2,rotor_3,rotor_4";

// `n` rows 10 ms apart, each with `extra` appended; row `at` (0-based) replaced by `replacement`.
std::string Rows(int n, const std::string& extra = "", int at = -1, const std::string& replacement = "") {
  std::string out;
  for (int i = 0; i < n; ++i) {
    out += i == at ? replacement : std::to_string(0.01 * i) + ",0.1,0.2,0.3,0,0,9.8,900,910,920,930" + extra;
    out += "\n";
  }
  return out;
}

std::string ErrorOf(const std::string& text, int num_rotors = 4) {
  try {
    ParseFlightCsv(text, "f.csv", num_rotors);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(FlightCsv, ReadsColumnsMetadataAndMotionCapture) {
  // Comments and blank lines anywhere; a text column rotorid does not know is ignored.
  const double half_yaw = 0.25;  // quaternion of a 0.5 rad yaw
  std::string text = "# rotorid flight log v1\n# gravity: 9.7\n\n# a comment: with spaces before the colon is not\n" +
                     kHeader + ",pos_x,pos_y,pos_z,qw,qx,qy,qz,vel_x,vel_y,vel_z,voltage,mode\r\n";
  for (int i = 0; i < 25; ++i) {
    if (i == 10) text += "   \n# vehicle: cf\n";
    text += std::to_string(0.005 * i) + ",0.1,0.2,0.3,0.4,0.5,9.8,900,910,920,930,1,2," + std::to_string(0.1 * i) +
            "," + std::to_string(std::cos(half_yaw)) + ",0,0," + std::to_string(std::sin(half_yaw)) +
            ",0.5,0.6,0.7,3.9,hover\r\n";
  }
  const FlightLog log = ParseFlightCsv(text, "f.csv", -1);
  ASSERT_EQ(log.num_samples(), 25);
  EXPECT_EQ(log.source, "f.csv");
  EXPECT_DOUBLE_EQ(log.t_s[24], 0.12);
  EXPECT_DOUBLE_EQ(log.gyro_radps(3, 2), 0.3);
  EXPECT_DOUBLE_EQ(log.acc_mps2(3, 1), 0.5);
  ASSERT_EQ(log.num_rotors(), 4);
  EXPECT_DOUBLE_EQ(log.rotor_radps(7, 3), 930.0);
  ASSERT_TRUE(log.mocap);
  EXPECT_DOUBLE_EQ(log.mocap->position_w_m(20, 2), 2.0);
  EXPECT_NEAR(log.mocap->bryant_rad(5, 2), 0.5, 1e-5);
  EXPECT_NEAR(log.mocap->bryant_rad(5, 0), 0.0, 1e-12);
  ASSERT_TRUE(log.mocap->velocity_w_mps);
  EXPECT_DOUBLE_EQ((*log.mocap->velocity_w_mps)(0, 1), 0.6);
  ASSERT_TRUE(log.voltage_v);
  EXPECT_DOUBLE_EQ((*log.voltage_v)[0], 3.9);
  EXPECT_DOUBLE_EQ(log.gravity_mps2, 9.7);
  EXPECT_EQ(log.metadata.at("vehicle"), "cf");
  EXPECT_EQ(log.metadata.count("a comment"), 0u);
  EXPECT_EQ(log.metadata.size(), 2u);
}

TEST(FlightCsv, EulerAnglesAndDefaultGravity) {
  const FlightLog log =
      ParseFlightCsv(kHeader + ",pos_x,pos_y,pos_z,roll,pitch,yaw\n" + Rows(20, ",1,2,3,0.1,0.2,0.3"), "f.csv", 4);
  ASSERT_TRUE(log.mocap);
  EXPECT_DOUBLE_EQ(log.mocap->bryant_rad(19, 1), 0.2);
  EXPECT_FALSE(log.mocap->velocity_w_mps);
  EXPECT_FALSE(log.voltage_v);
  EXPECT_DOUBLE_EQ(log.gravity_mps2, kStandardGravity);
}

// Every message names the file, and the line and column where there is one.
TEST(FlightCsv, ErrorsNameFileLineAndColumn) {
  EXPECT_EQ(ErrorOf(""), "f.csv: empty file: no header line and no samples");
  EXPECT_EQ(ErrorOf("# only a comment\n\n"), "f.csv: empty file: no header line and no samples");
  EXPECT_EQ(ErrorOf("t,,gyro_x\n"), "f.csv:1:3: empty column name in header");
  EXPECT_EQ(ErrorOf("# c\nt,gyro_x,t\n"), "f.csv:2:10: duplicate column 't'");
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(30, "", 1, "0.01,0,0")),
            "f.csv:3: row has 3 cells, the header has 11 (truncated or malformed row)");
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(30, "", 0, "0,abc,0,0,0,0,9.8,900,900,900,900")),
            "f.csv:2:3: column 'gyro_x' is not a number: 'abc'");
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(30, "", 0, "0,0,0,0,0,0,,900,900,900,900")),
            "f.csv:2:13: column 'acc_z' is not a number: ''");
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(30, "", 2, "0.02,0,0,0,0,0,  inf ,900,900,900,900")),
            "f.csv:4:16: column 'acc_z' holds 'inf', not a finite number");
  EXPECT_EQ(ErrorOf("# c\n" + kHeader + ",note\n" + Rows(30, ",x", 4, "0.04,0,0,0,0,0,9.8,900,900,900,900,nan")),
            "no error");  // a column rotorid does not read may hold anything
  EXPECT_EQ(ErrorOf("\n\nt,gyro_x,gyro_y,acc_x,acc_y,acc_z,rotor_1\n"), "f.csv:3: missing required column 'gyro_z'");
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(5)), "f.csv: too few samples (5); at least 20 are needed");
  // Time: the line of the offending row, past blank and comment lines.
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(10) + "\n# c\n" + Rows(20)),
            "f.csv:14:1: time goes backwards or repeats: t = 0.000000 after 0.090000");
  EXPECT_EQ(ErrorOf("t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\n" + std::string(20, '\n') + "0,0,0,0,0,0,9.8\n"),
            "f.csv: too few samples (1); at least 20 are needed");
  // Rotors.
  std::string no_rotors;
  for (int i = 0; i < 20; ++i) no_rotors += std::to_string(i) + ",0,0,0,0,0,9.8\n";
  EXPECT_EQ(ErrorOf("t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\n" + no_rotors, -1),
            "f.csv:1: missing required column 'rotor_1'");
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(20), 5), "f.csv:1: missing required column 'rotor_5'");
  EXPECT_EQ(ErrorOf(kHeader + ",rotor_5\n" + Rows(20, ",1")),
            "f.csv:1:74: the log has column 'rotor_5' but the vehicle file has 4 rotors: give every rotor in the "
            "vehicle file");
  EXPECT_EQ(ErrorOf(kHeader + "\n" + Rows(20, "", 7, "0.07,0,0,0,0,0,9.8,900,-1,900,900")),
            "f.csv:1: column 'rotor_2' has negative rotor speeds; it must hold |Omega| in rad/s");
  // Motion capture and velocity.
  EXPECT_EQ(ErrorOf(kHeader + ",pos_x,pos_y,pos_z\n" + Rows(20, ",1,2,3")),
            "f.csv:1: pos_x..z given without roll,pitch,yaw or qw,qx,qy,qz");
  EXPECT_EQ(ErrorOf(kHeader + ",pos_x,pos_y,pos_z,roll,pitch\n" + Rows(20, ",1,2,3,0,0")),
            "f.csv:1: missing required column 'yaw'");
  EXPECT_EQ(ErrorOf(kHeader + ",pos_x,pos_y,pos_z,qw,qx,qy,qz\n" +
                    Rows(20, ",1,2,3,1,0,0,0", 2, "0.02,0,0,0,0,0,9.8,900,900,900,900,1,2,3,0.3,0,0.3,0")),
            "f.csv: quaternion of data row 3 is not a rotation");
  EXPECT_EQ(ErrorOf(kHeader + ",vel_x,vel_y,vel_z\n" + Rows(20, ",1,2,3")),
            "f.csv:1:74: vel_x..z (world frame) need the pose (pos_x..z with roll,pitch,yaw or qw,qx,qy,qz) to be "
            "turned into the body frame");
  EXPECT_EQ(ErrorOf(kHeader + ",pos_x,pos_y,pos_z,roll,pitch,yaw,vel_x,vel_y\n" + Rows(20, ",1,2,3,0,0,0,1,2")),
            "f.csv:1: missing required column 'vel_z'");
  // Metadata.
  EXPECT_EQ(ErrorOf("# gravity: -1\n" + kHeader + "\n" + Rows(20)),
            "f.csv: metadata 'gravity' must be a positive number, got '-1'");
  EXPECT_EQ(ErrorOf("# gravity: 9.81 m/s^2\n" + kHeader + "\n" + Rows(20)), "no error");  // text after the number
}

// Logs of a megabyte and more are parsed in two stretches at once: the rows, the comments among
// them and the first error must come out as from one pass (30 000 rows of 60 bytes: 1.8 MB).
TEST(FlightCsv, ALongLogReadsAsInOnePass) {
  const int n = 30000;
  std::string rows;
  for (int i = 0; i < n; ++i) {
    if (i == 100) rows += "# vehicle: first\n";
    if (i == 20000) rows += "\n# vehicle: second\n";  // past the middle: a later comment wins
    rows += std::to_string(0.01 * i) + ",0.1,0.2,0.3,0,0,9.8," + std::to_string(i) + ",910,920,930\n";
  }
  const FlightLog log = ParseFlightCsv(kHeader + "\n" + rows, "f.csv", 4);
  ASSERT_EQ(log.num_samples(), n);
  for (int i = 0; i < n; ++i) ASSERT_EQ(log.rotor_radps(i, 0), i) << i;
  EXPECT_EQ(log.metadata.at("vehicle"), "second");
  // Data row i stands on file line 2 + i, plus the comment above row 100 and the blank line and
  // comment above row 20000: row 25000 (in the second stretch) on line 25005.
  auto broken = [&](int row) {
    const std::string line =
        std::to_string(0.01 * row) + ",0.1,0.2,0.3,0,0,9.8," + std::to_string(row) + ",910,920,930\n";
    std::string text = kHeader + "\n" + rows;
    text.replace(text.find(line), line.size(), std::to_string(0.01 * row) + ",0.1,x,0.3,0,0,9.8,1,910,920,930\n");
    return text;
  };
  EXPECT_EQ(ErrorOf(broken(25000)), "f.csv:25005:16: column 'gyro_y' is not a number: 'x'");
  std::string both = broken(25000);
  const std::string row_5 = "0.050000,0.1,0.2,0.3,0,0,9.8,5,910,920,930\n";
  both.replace(both.find(row_5), row_5.size(), "0.05,0.1\n");
  EXPECT_EQ(ErrorOf(both), "f.csv:7: row has 2 cells, the header has 11 (truncated or malformed row)");
}

}  // namespace
}  // namespace rotorid

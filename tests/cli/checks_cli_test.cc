// The input mistakes of issue 11 through the rotorid binary: each exits 1 (bad input) or 3 (a check
// failed, the report still written) with a message naming the cause; a good flight passes every
// check. Plus the readers' robustness: time jumps, huge vehicle files, duplicate keys, unknown
// columns, outputs that are not regular files.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "rotorid/core/error.h"
#include "rotorid/ident/checks.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/io/vehicle_yaml.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;

class ChecksCliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(MakeTempDir("rotorid-checks"));
    const auto r = RunRotorid({"simulate", "--preset", "B", "--seconds", "40", "--seed", "21", "--out", Path("ok.csv"),
                               "--vehicle-out", Path("B.yaml"), "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string Path(const std::string& name) { return *dir_ + "/" + name; }
  static FlightLog Log() { return ReadFlightCsv(Path("ok.csv")); }
  static Vehicle Vehicle0() { return ReadVehicleYaml(Path("B.yaml")); }
  static std::string WriteLog(const std::string& name, const FlightLog& log) {
    WriteFlightCsv(Path(name), log);
    return Path(name);
  }
  static std::string WriteVehicle(const std::string& name, const Vehicle& vehicle) {
    WriteFileAtomically(Path(name), VehicleToYaml(vehicle));
    return Path(name);
  }
  // identify with --json; the report's checks by name (status), exit code and stderr.
  struct Outcome {
    testing::CommandResult run;
    std::map<std::string, std::string> status;
  };
  static Outcome Identify(const std::string& vehicle, const std::string& log, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"identify", "--vehicle", vehicle, "--log", log, "--json", Path("report.json")};
    args.insert(args.end(), extra.begin(), extra.end());
    std::remove(Path("report.json").c_str());
    Outcome o;
    o.run = RunRotorid(args);
    const std::string text = testing::Slurp(Path("report.json"));
    const nlohmann::json report = text.empty() ? nlohmann::json::object() : nlohmann::json::parse(text);
    if (report.contains("checks"))
      for (const auto& c : report["checks"]) {
        std::string& s = o.status[c["name"].get<std::string>()];
        if (s != "error") s = c["status"].get<std::string>();
      }
    return o;
  }
  static std::string* dir_;
};
std::string* ChecksCliTest::dir_ = nullptr;

TEST_F(ChecksCliTest, GoodFlightPassesEveryCheck) {
  const Outcome o = Identify(Path("B.yaml"), Path("ok.csv"));
  ASSERT_EQ(o.run.exit_code, 0) << o.run.err << o.run.out;
  for (const char* name : {"accelerometer_units", "motion", "airborne", "vehicle_scale", "rotor_order", "rotor_spins",
                           "gyro_units", "finite", "kt_positive", "kd_positive", "inertia", "relative_error"}) {
    ASSERT_TRUE(o.status.count(name)) << name;
    EXPECT_EQ(o.status.at(name), "ok") << name << "\n" << o.run.err;
  }
}

TEST_F(ChecksCliTest, SwappedRotorsAreNamed) {
  Vehicle v = Vehicle0();
  std::swap(v.rotors[0], v.rotors[1]);
  const std::string file = WriteVehicle("swapped.yaml", v);
  const Outcome o = Identify(file, Path("ok.csv"), {"--allow-partial"});
  EXPECT_EQ(o.run.exit_code, 3) << o.run.err;
  EXPECT_EQ(o.status.at("rotor_order"), "error");
  EXPECT_NE(o.run.err.find("rotors 1 and 2 appear swapped in " + file), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, ReversedSpinsAreNamed) {
  Vehicle v = Vehicle0();
  for (Rotor& r : v.rotors) r.spin = -r.spin;
  const Outcome o = Identify(WriteVehicle("spins.yaml", v), Path("ok.csv"));
  EXPECT_EQ(o.run.exit_code, 3) << o.run.err;
  EXPECT_NE(o.run.err.find("spin directions appear reversed"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, GyroInDegreesPerSecond) {
  FlightLog log = Log();
  log.gyro_radps *= 180.0 / M_PI;
  const Outcome o = Identify(Path("B.yaml"), WriteLog("gyro_deg.csv", log));
  // Exit 3 with the check, or exit 1 when the identification fails and names the check as the cause.
  EXPECT_TRUE(o.run.exit_code == 1 || o.run.exit_code == 3) << o.run.err;
  if (o.run.exit_code == 3) {
    EXPECT_EQ(o.status.at("gyro_units"), "error");
  }
  EXPECT_NE(o.run.err.find("gyro appears to be in deg/s"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, AccelerometerInG) {
  FlightLog log = Log();
  log.acc_mps2 /= 9.80665;
  const Outcome o = Identify(Path("B.yaml"), WriteLog("acc_g.csv", log));
  EXPECT_TRUE(o.run.exit_code == 1 || o.run.exit_code == 3) << o.run.exit_code;
  EXPECT_NE(o.run.err.find("accelerometer appears to be in g"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, MassInGrams) {
  Vehicle v = Vehicle0();
  v.mass_kg *= 1000.0;
  const std::string file = WriteVehicle("grams.yaml", v);
  const Outcome o = Identify(file, Path("ok.csv"));
  EXPECT_EQ(o.run.exit_code, 3) << o.run.err;
  EXPECT_NE(o.run.err.find("the mass in " + file + " appears to be in grams"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, RotorPositionsInMillimetres) {
  Vehicle v = Vehicle0();
  for (Rotor& r : v.rotors) r.position_m *= 1000.0;
  const std::string file = WriteVehicle("mm.yaml", v);
  const Outcome o = Identify(file, Path("ok.csv"));
  EXPECT_EQ(o.run.exit_code, 3) << o.run.err;
  EXPECT_NE(o.run.err.find("the rotor positions in " + file + " appear to be in mm"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, RotorSpeedInRpm) {
  FlightLog log = Log();
  log.rotor_radps *= 60.0 / (2.0 * M_PI);
  const Outcome o = Identify(Path("B.yaml"), WriteLog("rpm.csv", log));
  EXPECT_EQ(o.run.exit_code, 3) << o.run.err;
  EXPECT_NE(o.run.err.find("appear to be in rpm"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, ThreeRotorVehicleOnFourRotorLog) {
  Vehicle v = Vehicle0();
  v.rotors.pop_back();
  const Outcome o = Identify(WriteVehicle("three.yaml", v), Path("ok.csv"));
  EXPECT_EQ(o.run.exit_code, 1);
  EXPECT_NE(o.run.err.find("ok.csv"), std::string::npos) << o.run.err;
  EXPECT_NE(o.run.err.find("'rotor_4' but the vehicle file has 3 rotors"), std::string::npos) << o.run.err;
}

// Hovering on a bench: noise only, constant rotor speed.
TEST_F(ChecksCliTest, MotionlessLog) {
  FlightLog log = Log();
  Eigen::MatrixXd noise = 1e-3 * Eigen::MatrixXd::Random(log.num_samples(), 3);
  log.gyro_radps = noise;
  log.acc_mps2 = 10.0 * noise;
  log.acc_mps2.col(2).array() += 9.80665;
  log.rotor_radps = (900.0 + 0.5 * Eigen::MatrixXd::Random(log.num_samples(), 4).array()).matrix();
  const Outcome o = Identify(Path("B.yaml"), WriteLog("motionless.csv", log), {"--allow-partial"});
  EXPECT_TRUE(o.run.exit_code == 1 || o.run.exit_code == 3) << o.run.exit_code;
  EXPECT_NE(o.run.err.find("the log is motionless"), std::string::npos) << o.run.err;
}

// On the ground with idle motors: the IMU at rest while the rotor speeds vary.
TEST_F(ChecksCliTest, OnTheGroundWithIdleMotors) {
  FlightLog log = Log();
  log.gyro_radps = 3e-3 * Eigen::MatrixXd::Random(log.num_samples(), 3);
  log.acc_mps2 = 3e-2 * Eigen::MatrixXd::Random(log.num_samples(), 3);
  log.acc_mps2.col(2).array() += 9.80665;
  log.rotor_radps *= 0.25;
  const Outcome o = Identify(Path("B.yaml"), WriteLog("ground.csv", log), {"--allow-partial"});
  EXPECT_TRUE(o.run.exit_code == 1 || o.run.exit_code == 3) << o.run.exit_code;
  EXPECT_NE(o.run.err.find("recorded on the ground"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, GyroAndAccelerometerColumnsSwapped) {
  FlightLog log = Log();
  std::swap(log.gyro_radps, log.acc_mps2);
  const Outcome o = Identify(Path("B.yaml"), WriteLog("swapped_columns.csv", log), {"--allow-partial"});
  EXPECT_TRUE(o.run.exit_code == 1 || o.run.exit_code == 3) << o.run.exit_code;
  EXPECT_NE(o.run.err.find("gyro and accelerometer columns appear swapped"), std::string::npos) << o.run.err;
}

// One forward jump of 1e4 s used to be bridged by interpolation (1.2 GB, a wrong first moment).
// --segment auto splits the log there (each stretch its own flight); --segment none refuses it.
TEST_F(ChecksCliTest, TimeJumpIsRefusedWithItsPlace) {
  FlightLog log = Log();
  log.t_s.tail(log.num_samples() / 2).array() += 1e4;
  const std::string path = WriteLog("jump.csv", log);
  const Outcome split = Identify(Path("B.yaml"), path, {"--allow-partial"});
  EXPECT_NE(split.run.exit_code, 1) << split.run.err;
  EXPECT_NE(split.run.out.find("2 stretches"), std::string::npos) << split.run.out;
  const Outcome o = Identify(Path("B.yaml"), path, {"--segment", "none"});
  EXPECT_EQ(o.run.exit_code, 1);
  EXPECT_NE(o.run.err.find("jump.csv: the time jumps by 10000"), std::string::npos) << o.run.err;
  EXPECT_NE(o.run.err.find("data row " + std::to_string(log.num_samples() - log.num_samples() / 2 + 1)),
            std::string::npos)
      << o.run.err;
}

// A million rotors used to end in std::bad_alloc; now the file's size is refused before parsing.
TEST_F(ChecksCliTest, HugeRotorCountIsRefused) {
  std::string yaml = "name: B\nmass: 1.452\nrotors:\n";
  for (int i = 0; i < 100000; ++i) yaml += "  - {position: [0, 0.225, 0], spin: +1}\n";
  WriteFileAtomically(Path("huge.yaml"), yaml);
  const Outcome o = Identify(Path("huge.yaml"), Path("ok.csv"));
  EXPECT_EQ(o.run.exit_code, 1);
  EXPECT_NE(o.run.err.find("huge.yaml: 3 MB, more than the 1 MB rotorid reads"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, DuplicateVehicleKeyIsAnError) {
  WriteFileAtomically(Path("duplicate.yaml"), testing::Slurp(Path("B.yaml")) + "mass: 1.0\n");
  const Outcome o = Identify(Path("duplicate.yaml"), Path("ok.csv"));
  EXPECT_EQ(o.run.exit_code, 1);
  EXPECT_NE(o.run.err.find("duplicate.yaml:"), std::string::npos) << o.run.err;
  EXPECT_NE(o.run.err.find("duplicate key 'mass'"), std::string::npos) << o.run.err;
}

TEST_F(ChecksCliTest, UnknownTextColumnIsIgnored) {
  std::string csv = testing::Slurp(Path("ok.csv")), out;
  size_t start = 0;
  bool header = true;
  while (start < csv.size()) {
    const size_t end = csv.find('\n', start);
    const std::string line = csv.substr(start, end - start);
    start = end == std::string::npos ? csv.size() : end + 1;
    if (line.empty() || line[0] == '#') {
      out += line + "\n";
      continue;
    }
    out += line + (header ? ",flight_mode\n" : ",POSCTL\n");
    header = false;
  }
  WriteFileAtomically(Path("text_column.csv"), out);
  const Outcome o = Identify(Path("B.yaml"), Path("text_column.csv"));
  EXPECT_EQ(o.run.exit_code, 0) << o.run.err;
}

TEST_F(ChecksCliTest, JsonOnAFifoIsRefusedAndTheFifoKept) {
  const std::string fifo = Path("report.fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const auto r = RunRotorid({"identify", "--vehicle", Path("B.yaml"), "--log", Path("ok.csv"), "--json", fifo, "-q"});
  EXPECT_EQ(r.exit_code, 2);  // refused while parsing, before the work (issue 42)
  EXPECT_NE(r.err.find(fifo + "' exists and is not a regular file"), std::string::npos) << r.err;
  struct stat s {};
  ASSERT_EQ(stat(fifo.c_str(), &s), 0);
  EXPECT_TRUE(S_ISFIFO(s.st_mode));
}

// NaN std used to be written as null with exit 0.
TEST(Checks, NanOrZeroStdIsAnError) {
  CheckedParameters p;
  p.value = {{"kt", 3.6e-6}, {"kd", 5e-8}, {"B.I_xx", 0.026}, {"B.I_yy", 0.037}, {"B.I_zz", 0.054}};
  p.std = {{"kt", 1e-9}, {"kd", 1e-9}, {"B.I_xx", 1e-4}, {"B.I_yy", 1e-4}, {"B.I_zz", 1e-4}};
  for (const auto& [name, value] : p.value) p.essential[name] = true;
  EXPECT_FALSE(AnyCheckFailed(CheckParameters(p, {"B"}, "linear")));
  p.std["B.I_yy"] = std::numeric_limits<double>::quiet_NaN();
  std::vector<Check> checks = CheckParameters(p, {"B"}, "linear");
  EXPECT_TRUE(AnyCheckFailed(checks));
  EXPECT_NE(FailedCheckMessages(checks).find("NaN or inf in B.I_yy"), std::string::npos);
  p.std["B.I_yy"] = 0.0;
  checks = CheckParameters(p, {"B"}, "linear");
  EXPECT_NE(FailedCheckMessages(checks).find("std exactly 0 for B.I_yy"), std::string::npos);
  EXPECT_TRUE(AnyCheckFailed(
      CheckRelativeError({std::nullopt, std::nullopt, std::numeric_limits<double>::infinity()}, "linear", false)));
  EXPECT_TRUE(AnyCheckFailed(CheckRelativeError({std::nullopt, std::nullopt, 1378.0}, "linear", false)));
  EXPECT_FALSE(AnyCheckFailed(CheckRelativeError({std::nullopt, std::nullopt, 1378.0}, "held-out", true)));
}

// An inertia that violates the triangle inequality beyond 3 std, and kd < 0.
TEST(Checks, UnphysicalInertiaAndNegativeKd) {
  CheckedParameters p;
  p.value = {{"kt", 3.6e-6}, {"kd", -5e-8}, {"B.I_xx", 0.01}, {"B.I_yy", 0.01}, {"B.I_zz", 0.05}};
  p.std = {{"kt", 1e-9}, {"kd", 1e-9}, {"B.I_xx", 1e-4}, {"B.I_yy", 1e-4}, {"B.I_zz", 1e-4}};
  for (const auto& [name, value] : p.value) p.essential[name] = true;
  const std::string failed = FailedCheckMessages(CheckParameters(p, {"B"}, "linear"));
  EXPECT_NE(failed.find("kd = -5e-08 < 0"), std::string::npos) << failed;
  EXPECT_NE(failed.find("I_xx + I_yy < I_zz"), std::string::npos) << failed;
  EXPECT_NE(failed.find("spin directions in the vehicle file appear reversed"), std::string::npos) << failed;
  EXPECT_EQ(failed.find("yaw motion"), std::string::npos) << failed;
}

// kd and I_zz both negative, their ratio right (a simulated Crazyflie take-off and landing with
// little yaw): the yaw equation's scale is what the log does not fix, not the spins; both checks
// say so.
TEST(Checks, NegativeKdAndIzzNameTheYawScaleNotTheSpins) {
  CheckedParameters p;
  p.value = {{"kt", 2e-8}, {"kd", -1.31e-11}, {"CF.I_xx", 1.60e-5}, {"CF.I_yy", 1.65e-5}, {"CF.I_zz", -3.78e-6}};
  p.std = {{"kt", 8e-13}, {"kd", 8e-13}, {"CF.I_xx", 3.5e-8}, {"CF.I_yy", 6.5e-8}, {"CF.I_zz", 2.3e-7}};
  for (const auto& [name, value] : p.value) p.essential[name] = true;
  const std::vector<Check> checks = CheckParameters(p, {"CF"}, "linear");
  for (const char* name : {"kd_positive", "inertia"}) {
    const auto check = std::find_if(checks.begin(), checks.end(), [&](const Check& c) { return c.name == name; });
    ASSERT_NE(check, checks.end()) << name;
    EXPECT_EQ(check->status, CheckStatus::kError) << name;
    EXPECT_NE(check->message.find("too little yaw motion to fix their scale"), std::string::npos) << check->message;
    EXPECT_EQ(check->message.find("spin"), std::string::npos) << check->message;
  }
}

// kd and I_zz both positive and 2.4 times too large, their ratio right (a simulated take-off and low
// hover of configuration A): only I_xx + I_yy < I_zz fails, and the check names the yaw scale and the
// ratio the log does fix. With a roll inertia that fails too, the cause is not only the yaw scale.
TEST(Checks, TooLargeIzzWithKdNamesTheYawScale) {
  CheckedParameters p;
  p.value = {{"kt", 3.67e-6}, {"kd", 1.25e-7}, {"A.I_xx", 0.0173}, {"A.I_yy", 0.0183}, {"A.I_zz", 0.0711}};
  p.std = {{"kt", 1.3e-8}, {"kd", 1.25e-8}, {"A.I_xx", 1.9e-4}, {"A.I_yy", 1.8e-4}, {"A.I_zz", 7.1e-3}};
  for (const auto& [name, value] : p.value) p.essential[name] = true;
  const std::string failed = FailedCheckMessages(CheckParameters(p, {"A"}, "linear"));
  EXPECT_NE(failed.find("I_xx + I_yy < I_zz"), std::string::npos) << failed;
  EXPECT_NE(failed.find("kd / I_zz = 1.76e-06"), std::string::npos) << failed;
  EXPECT_NE(failed.find("too little yaw motion to fix their scale"), std::string::npos) << failed;
  EXPECT_EQ(failed.find("rotor order"), std::string::npos) << failed;

  p.value["A.I_xx"] = -0.0173;
  const std::string both = FailedCheckMessages(CheckParameters(p, {"A"}, "linear"));
  EXPECT_NE(both.find("I_xx = -0.0173 < 0"), std::string::npos) << both;
  EXPECT_NE(both.find("rotor order"), std::string::npos) << both;
  EXPECT_EQ(both.find("yaw motion"), std::string::npos) << both;
}

// The same take-off flight of A refined with the ground effect its linear model lacks: I_zz 0.0332
// +- 0.0008, kd 5.85e-8 (truth 0.029, 5.1e-8). The linear inertia error becomes a warning that says
// the model with effects passes; it stays an error when that model fails the same check, and each
// configuration's check is paired with that configuration's.
TEST(Checks, LinearInertiaErrorTheModelWithEffectsPassesIsAWarning) {
  CheckedParameters linear;
  linear.value = {{"kt", 3.67e-6}, {"kd", 1.25e-7}, {"A.I_xx", 0.0173}, {"A.I_yy", 0.0183}, {"A.I_zz", 0.0711}};
  linear.std = {{"kt", 1.3e-8}, {"kd", 1.25e-8}, {"A.I_xx", 1.9e-4}, {"A.I_yy", 1.8e-4}, {"A.I_zz", 7.1e-3}};
  for (const auto& [name, value] : linear.value) linear.essential[name] = true;
  CheckedParameters refined = linear;
  refined.value["kd"] = 5.85e-8;
  refined.value["A.I_zz"] = 0.0332;
  refined.std["A.I_zz"] = 8.5e-4;
  const std::vector<Check> linear_checks = CheckParameters(linear, {"A"}, "linear");
  ASSERT_TRUE(AnyCheckFailed(linear_checks));

  std::vector<Check> checks = linear_checks;
  ExcuseLinearParameterErrors(linear_checks, CheckParameters(refined, {"A"}, "refined"), &checks);
  EXPECT_FALSE(AnyCheckFailed(checks));
  const auto inertia = std::find_if(checks.begin(), checks.end(), [](const Check& c) { return c.name == "inertia"; });
  ASSERT_NE(inertia, checks.end());
  EXPECT_EQ(inertia->status, CheckStatus::kWarning);
  EXPECT_NE(inertia->message.find("too little yaw motion"), std::string::npos) << inertia->message;
  EXPECT_NE(inertia->message.find("the model with effects passes this check (refined A: positive definite"),
            std::string::npos)
      << inertia->message;

  refined.value["A.I_zz"] = 0.05;  // I_xx + I_yy < I_zz in the refined model too
  checks = linear_checks;
  ExcuseLinearParameterErrors(linear_checks, CheckParameters(refined, {"A"}, "refined"), &checks);
  EXPECT_TRUE(AnyCheckFailed(checks));

  // Two configurations: A fails in both models, B passes in both; A's error stays.
  for (const char* n : {"I_xx", "I_yy", "I_zz"}) {
    linear.value[std::string("B.") + n] = 0.02;
    linear.std[std::string("B.") + n] = 1e-4;
    linear.essential[std::string("B.") + n] = true;
  }
  refined = linear;
  const std::vector<Check> two = CheckParameters(linear, {"A", "B"}, "linear");
  checks = two;
  ExcuseLinearParameterErrors(two, CheckParameters(refined, {"A", "B"}, "refined"), &checks);
  EXPECT_TRUE(AnyCheckFailed(checks));
  EXPECT_NE(FailedCheckMessages(checks).find("linear A inertia is not physical"), std::string::npos);
}

}  // namespace
}  // namespace rotorid

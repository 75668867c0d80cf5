// End-to-end tests through the rotorid binary: simulate -> identify/validate/refine/delay, the
// JSON keys of INTERFACE.md, and the handling of bad input.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;

using testing::Slurp;

nlohmann::json LoadJson(const std::string& path) { return nlohmann::json::parse(Slurp(path)); }

class CliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(MakeTempDir("rotorid-cli"));
    for (const auto& [name, seed] : {std::pair<std::string, std::string>{"train", "11"}, {"val", "12"}}) {
      const auto r =
          RunRotorid({"simulate", "--preset", "B", "--seconds", "40", "--seed", seed, "--out", Path(name + ".csv"),
                      "--truth", Path(name + "_truth.json"), "--vehicle-out", Path("B.yaml"), "--quiet"});
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string Path(const std::string& name) { return *dir_ + "/" + name; }
  static std::vector<std::string> Flight() { return {"--vehicle", Path("B.yaml"), "--log", Path("train.csv")}; }
  static std::string* dir_;
};
std::string* CliTest::dir_ = nullptr;

TEST_F(CliTest, IdentifyWritesContractKeysAndRecoversTruth) {
  auto args = Flight();
  args.insert(args.begin(), "identify");
  args.insert(args.end(), {"--json", Path("identify.json")});
  const auto r = RunRotorid(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("kt"), std::string::npos);
  const nlohmann::json report = LoadJson(Path("identify.json"));
  const nlohmann::json truth = LoadJson(Path("train_truth.json"));
  const nlohmann::json& parameters = report["linear"]["parameters"];
  for (const char* name :
       {"kt", "kd", "B.ms_x", "B.ms_y", "B.ms_z", "B.I_xx", "B.I_yy", "B.I_zz", "B.I_xy", "B.I_xz", "B.I_yz"}) {
    ASSERT_TRUE(parameters.contains(name)) << name;
    for (const char* key : {"value", "std", "rel_std_pct", "essential"}) EXPECT_TRUE(parameters[name].contains(key));
  }
  EXPECT_NEAR(parameters["kt"]["value"].get<double>(), truth["parameters"]["kt"].get<double>(),
              1e-3 * truth["parameters"]["kt"].get<double>());
  EXPECT_NEAR(parameters["B.I_xx"]["value"].get<double>(), truth["parameters"]["B.I_xx"].get<double>(),
              0.01 * truth["parameters"]["B.I_xx"].get<double>());
  const nlohmann::json& rel = report["linear"]["relative_error_pct"];
  EXPECT_TRUE(rel["Fx"].is_null());
  EXPECT_TRUE(rel["Fy"].is_null());
  for (const char* c : {"Fz", "Mx", "My", "Mz"}) EXPECT_TRUE(rel[c].is_number()) << c;

  const auto v = RunRotorid({"validate", "--params", Path("identify.json"), "--vehicle", Path("B.yaml"), "--log",
                             Path("val.csv"), "--json", Path("validate.json")});
  ASSERT_EQ(v.exit_code, 0) << v.err;
  const nlohmann::json validate = LoadJson(Path("validate.json"));
  EXPECT_LT(validate["relative_error_pct"]["Fz"].get<double>(), 5.0);
}

TEST_F(CliTest, PaperMethodIsAvailable) {
  auto args = Flight();
  args.insert(args.begin(), {"identify", "--method", "paper"});
  args.insert(args.end(), {"--json", Path("paper.json")});
  const auto r = RunRotorid(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(LoadJson(Path("paper.json"))["linear"]["method"], "paper");
}

TEST_F(CliTest, RefineAndDelayWriteContractKeys) {
  auto args = Flight();
  args.insert(args.begin(), "refine");
  args.insert(args.end(), {"--effects", "delay,acc_bias", "--validate-vehicle", Path("B.yaml"), "--validate-log",
                           Path("val.csv"), "--json", Path("refine.json")});
  const auto r = RunRotorid(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = LoadJson(Path("refine.json"));
  for (const char* block : {"linear", "refined"}) ASSERT_TRUE(report[block]["parameters"].contains("kt")) << block;
  for (const char* e : {"delay_s", "motor_tau_s", "acc_bias", "gyro_bias", "misalignment_rad"})
    EXPECT_TRUE(report["refined"]["effects"].contains(e)) << e;
  EXPECT_TRUE(report["refined"]["effects"]["acc_bias"]["value"].is_array());
  EXPECT_TRUE(report["held_out"]["refined"]["relative_error_pct"]["Fz"].is_number());

  auto delay_args = Flight();
  delay_args.insert(delay_args.begin(), "delay");
  delay_args.insert(delay_args.end(), {"--json", Path("delay.json")});
  const auto d = RunRotorid(delay_args);
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const nlohmann::json delay = LoadJson(Path("delay.json"));
  EXPECT_NEAR(delay["delay_s"].get<double>(), 0.0, 0.001);  // a clean flight
  EXPECT_GT(delay["delay_std_s"].get<double>(), 0.0);
}

// A hover without manoeuvres leaves the inertia unidentifiable: a clear message and a non-zero exit.
TEST_F(CliTest, UnexcitedFlightIsRefusedWithReason) {
  const auto s = RunRotorid({"simulate", "--preset", "B", "--seconds", "30", "--seed", "3", "--excitation", "0",
                             "--out", Path("hover.csv"), "--quiet"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto r = RunRotorid({"identify", "--vehicle", Path("B.yaml"), "--log", Path("hover.csv")});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(r.err.find("not identifiable") != std::string::npos ||
              r.err.find("could not be identified") != std::string::npos)
      << r.err;
}

// An accelerometer bias never passes silently.
TEST_F(CliTest, AccelerometerBiasIsFlagged) {
  const auto s = RunRotorid({"simulate", "--preset", "B", "--seconds", "30", "--seed", "5", "--effect",
                             "acc_bias=0.3,-0.2,0.3", "--out", Path("biased.csv"), "--quiet"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto r = RunRotorid({"identify", "--vehicle", Path("B.yaml"), "--log", Path("biased.csv")});
  EXPECT_TRUE(r.err.find("systematic force error") != std::string::npos ||
              r.err.find("scale lost") != std::string::npos)
      << r.err;
}

// An effect that the refinement leaves on its bound is not an estimate: refine writes its report and
// exits 3, the check naming the effect (an acc bias of 3 m/s^2 in z against a bound of 2).
TEST_F(CliTest, RefinedEffectOnItsBoundExitsThree) {
  const auto s = RunRotorid({"simulate", "--preset", "B", "--seconds", "30", "--seed", "5", "--effect",
                             "acc_bias=0.1,-0.1,3.0", "--out", Path("bound.csv"), "--quiet"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto r = RunRotorid({"refine", "--vehicle", Path("B.yaml"), "--log", Path("bound.csv"), "--effects", "acc_bias",
                             "--json", Path("bound.json"), "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("acc_bias ended on the bound of its range"), std::string::npos) << r.err;
  const nlohmann::json report = LoadJson(Path("bound.json"));
  EXPECT_TRUE(report["refined"]["effects"]["acc_bias"]["on_bound"].get<bool>());
  bool failed = false;
  for (const auto& check : report["checks"])
    failed = failed || (check["name"] == "effects_on_bounds" && check["status"] == "error");
  EXPECT_TRUE(failed) << report["checks"].dump();
}

struct BadInput {
  std::string name;
  std::string content;
  std::string expected;  // part of the message
};

void PrintTo(const BadInput& c, std::ostream* os) { *os << c.name; }

class BadInputTest : public CliTest, public ::testing::WithParamInterface<BadInput> {};

TEST_P(BadInputTest, NamedErrorAndNonZeroExit) {
  const BadInput& c = GetParam();
  const std::string path = Path("bad_" + c.name + ".csv");
  std::ofstream(path) << c.content;
  const auto r = RunRotorid({"identify", "--vehicle", Path("B.yaml"), "--log", path});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(path), std::string::npos) << "message must name the file: " << r.err;
}

std::string Rows(int n, double t0 = 0.0, const std::string& override_row = "", int override_at = -1) {
  std::string s = "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,rotor_1,rotor_2,rotor_3,rotor_4\n";
  for (int i = 0; i < n; ++i) {
    if (i == override_at) {
      s += override_row + "\n";
      continue;
    }
    s += std::to_string(t0 + 0.005 * i) + ",0,0,0,0,0,9.8,900,900,900,900\n";
  }
  return s;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadInputTest,
    ::testing::Values(
        BadInput{"empty", "", "empty file"},
        BadInput{"missing_column",
                 "t,gyro_x,gyro_y,acc_x,acc_y,acc_z,rotor_1,rotor_2,rotor_3,rotor_4\n0,0,0,0,0,9.8,1,1,1,1\n",
                 "missing required column 'gyro_z'"},
        BadInput{"non_numeric", Rows(50, 0.0, "0.1,abc,0,0,0,0,9.8,900,900,900,900", 20), ":22:"},
        BadInput{"nan", Rows(50, 0.0, "0.1,nan,0,0,0,0,9.8,900,900,900,900", 20), "not a finite number"},
        BadInput{"backwards", Rows(50, 0.0, "0.01,0,0,0,0,0,9.8,900,900,900,900", 30), "time goes backwards"},
        BadInput{"truncated", Rows(50) + "0.3,0,0", "truncated"}, BadInput{"too_few", Rows(5), "too few samples"},
        BadInput{"negative_rotor", Rows(50, 0.0, "0.1,0,0,0,0,0,9.8,-900,900,900,900", 20), "negative rotor"}),
    [](const auto& test_info) { return test_info.param.name; });

TEST_F(CliTest, BadVehicleFileIsNamed) {
  const std::string vehicle = Path("bad_vehicle.yaml");
  std::ofstream(vehicle) << "name: X\nmass: 1.0\nrotors:\n  - {position: [0, 1, 0], spin: 2}\n";
  const auto r = RunRotorid({"identify", "--vehicle", vehicle, "--log", Path("train.csv")});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad_vehicle.yaml:4"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("spin"), std::string::npos) << r.err;
}

// --first-moment per-flight: each log of a configuration has its own first moment, named
// <config>.flight<k>.ms_x in the order given; validate fits a new flight's own, export takes the mean.
TEST_F(CliTest, PerFlightFirstMomentNamesEachFlight) {
  const auto r = RunRotorid({"identify", "--vehicle", Path("B.yaml"), "--log", Path("train.csv"), "--vehicle",
                             Path("B.yaml"), "--log", Path("val.csv"), "--first-moment", "per-flight", "--json",
                             Path("per_flight.json"), "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = LoadJson(Path("per_flight.json"));
  const nlohmann::json truth = LoadJson(Path("train_truth.json"));
  const nlohmann::json& parameters = report["linear"]["parameters"];
  EXPECT_EQ(report["settings"]["first_moment"], "per-flight");
  EXPECT_FALSE(parameters.contains("B.ms_x"));
  for (const char* name : {"B.flight1.ms_x", "B.flight1.ms_y", "B.flight1.ms_z", "B.flight2.ms_x", "B.flight2.ms_y",
                           "B.flight2.ms_z", "B.I_xx"}) {
    ASSERT_TRUE(parameters.contains(name)) << name;
    for (const char* key : {"value", "std", "rel_std_pct", "essential"}) EXPECT_TRUE(parameters[name].contains(key));
  }
  // Both flights fly the same truth: each recovers it.
  for (const char* flight : {"B.flight1.ms_x", "B.flight2.ms_x"})
    EXPECT_NEAR(parameters[flight]["value"].get<double>(), truth["parameters"]["B.ms_x"].get<double>(),
                3.0 * parameters[flight]["std"].get<double>())
        << flight;

  const auto v = RunRotorid({"validate", "--params", Path("per_flight.json"), "--vehicle", Path("B.yaml"), "--log",
                             Path("val.csv"), "--json", Path("per_flight_validate.json"), "--quiet"});
  ASSERT_EQ(v.exit_code, 0) << v.err;
  const nlohmann::json validate = LoadJson(Path("per_flight_validate.json"));
  ASSERT_TRUE(validate["first_moments"].contains("B.held_out1.ms_x")) << validate.dump();
  EXPECT_NEAR(validate["first_moments"]["B.held_out1.ms_x"].get<double>(),
              parameters["B.flight2.ms_x"]["value"].get<double>(),
              3.0 * parameters["B.flight2.ms_x"]["std"].get<double>());
  EXPECT_LT(validate["relative_error_pct"]["Fz"].get<double>(), 5.0);

  const auto e = RunRotorid({"export", "--params", Path("per_flight.json"), "--vehicle", Path("B.yaml"), "--format",
                             "yaml", "--out", Path("per_flight.yaml"), "--quiet"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(Slurp(Path("per_flight.yaml")).find("note: \"first moment: the mean of 2 per-flight"), std::string::npos)
      << Slurp(Path("per_flight.yaml"));

  const auto bad =
      RunRotorid({"identify", "--vehicle", Path("B.yaml"), "--log", Path("train.csv"), "--first-moment", "per-log"});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("per-flight"), std::string::npos) << bad.err;
}

TEST_F(CliTest, HelpWorksEverywhere) {
  for (const char* command : {"simulate", "identify", "validate", "refine", "delay", "ablate", "diagnose"}) {
    const auto r = RunRotorid({command, "--help"});
    EXPECT_EQ(r.exit_code, 0) << command;
    EXPECT_NE(r.out.find("--json"), std::string::npos) << command;
  }
}

}  // namespace
}  // namespace rotorid

// End-to-end tests of the CLI's conventions and workflow (docs/cli.md): usage errors, output
// paths checked before the work, --window and --segment, input.flights[] and the "read:" line.

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;
using testing::Slurp;

nlohmann::json LoadJson(const std::string& path) { return nlohmann::json::parse(Slurp(path)); }

class CliWorkflowTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(MakeTempDir("rotorid-cli-workflow"));
    const auto r = RunRotorid({"simulate", "--preset", "B", "--seconds", "20", "--seed", "5", "--out", Path("f.csv"),
                               "--vehicle-out", Path("B.yaml"), "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string Path(const std::string& name) { return *dir_ + "/" + name; }
  static std::vector<std::string> Args(std::vector<std::string> head) {
    for (const std::string& a : std::vector<std::string>{"--vehicle", Path("B.yaml"), "--log", Path("f.csv")})
      head.push_back(a);
    return head;
  }
  static std::string* dir_;
};
std::string* CliWorkflowTest::dir_ = nullptr;

void ExpectUsageError(const testing::CommandResult& r, const std::string& what) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("rotorid: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--help"), std::string::npos) << "no hint: " << r.err;
  EXPECT_EQ(r.out.find("read:"), std::string::npos) << "work started before the usage error: " << r.out;
}

TEST_F(CliWorkflowTest, UsageErrorsExitTwoWithPrefixAndHint) {
  ExpectUsageError(RunRotorid({"frobnicate"}), "unknown subcommand 'frobnicate'");
  ExpectUsageError(RunRotorid({}), "a subcommand is required");
  ExpectUsageError(RunRotorid(Args({"identify", "--frobnicate"})), "--frobnicate");
  ExpectUsageError(RunRotorid({"identify", "--vehicle"}), "--vehicle");
  ExpectUsageError(RunRotorid(Args({"identify", "--cutoff-hz", "fast"})), "--cutoff-hz");
  ExpectUsageError(RunRotorid(Args({"identify", "--source", "gps"})), "--source");
  ExpectUsageError(RunRotorid(Args({"refine", "--effects", "delay,wobble"})), "wobble");
  ExpectUsageError(RunRotorid(Args({"identify", "--segment", "sometimes"})), "--segment");
  ExpectUsageError(RunRotorid(Args({"identify", "--window", "12,3"})), "must start before it ends");
  ExpectUsageError(RunRotorid(Args({"identify", "--window", "1,5", "--window", "6,9"})), "2 windows for 1 --log");
  ExpectUsageError(RunRotorid(Args({"diagnose", "--folds", "1"})), "folds");
  const auto help = RunRotorid({"identify", "--help"});
  EXPECT_EQ(help.exit_code, 0);
}

TEST_F(CliWorkflowTest, OutputPathsAreCheckedBeforeTheWork) {
  ExpectUsageError(RunRotorid(Args({"identify", "--json", ""})), "must not be empty");
  ExpectUsageError(RunRotorid(Args({"diagnose", "--json", Path("missing/d.json")})), "does not exist");
  ExpectUsageError(RunRotorid(Args({"identify", "--json", *dir_})), "is a folder");
  std::ofstream(Path("plain_file")) << "x";
  ExpectUsageError(RunRotorid(Args({"refine", "--report", Path("plain_file")})), "is not a folder");
  ExpectUsageError(RunRotorid({"simulate", "--out", Path("missing/x.csv")}), "does not exist");
}

TEST_F(CliWorkflowTest, LibraryLogLinesOnlyUnderVerbose) {
  const auto quiet = RunRotorid(Args({"refine", "--effects", "delay,motor_lag", "-q"}));
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
  EXPECT_EQ(quiet.out, "");
  // simulate takes -q like the other commands.
  const auto quiet_simulate = RunRotorid({"simulate", "--preset", "A", "--seconds", "3", "--out", Path("q.csv"), "-q"});
  ASSERT_EQ(quiet_simulate.exit_code, 0) << quiet_simulate.err;
  EXPECT_EQ(quiet_simulate.out + quiet_simulate.err, "");
  const auto normal = RunRotorid(Args({"refine", "--effects", "delay,motor_lag"}));
  ASSERT_EQ(normal.exit_code, 0) << normal.err;
  // glog lines start with a severity letter and the date, e.g. "W1201 20:04:09.123 ...".
  for (size_t pos = 0; pos < normal.err.size(); pos = normal.err.find('\n', pos) + 1) {
    EXPECT_FALSE(normal.err.size() > pos + 5 && std::string("IWEF").find(normal.err[pos]) != std::string::npos &&
                 std::isdigit(static_cast<unsigned char>(normal.err[pos + 1])))
        << normal.err;
    if (normal.err.find('\n', pos) == std::string::npos) break;
  }
}

TEST_F(CliWorkflowTest, WindowCutsTheLogAndIsRecorded) {
  const auto r = RunRotorid(Args({"identify", "--window", "4,14", "--segment", "none", "--json", Path("w.json")}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("read: " + Path("f.csv") + " (csv, 200 Hz, rpm from rotor_1..rotor_4), 4.00-14.00 s"),
            std::string::npos)
      << r.out;
  const nlohmann::json flight = LoadJson(Path("w.json"))["input"]["flights"].at(0);
  EXPECT_EQ(flight["file"], Path("f.csv"));
  EXPECT_EQ(flight["format"], "csv");
  EXPECT_EQ(flight["rotor_signal"], "rpm");
  EXPECT_NEAR(flight["sample_rates_hz"]["imu"].get<double>(), 200.0, 0.5);
  EXPECT_NEAR(flight["used_s"].get<double>(), 10.0, 0.01);
  EXPECT_EQ(flight["window_s"], nlohmann::json({4.0, 14.0}));
  ASSERT_EQ(flight["segments_left_out"].size(), 2u);
  EXPECT_EQ(flight["segments_left_out"][0]["reason"], "outside --window");
  EXPECT_NEAR(flight["segments_left_out"][1]["start"].get<double>(), 14.0, 0.01);
  ASSERT_EQ(flight["segments_kept"].size(), 1u);
  EXPECT_NEAR(flight["segments_kept"][0]["start"].get<double>(), 4.0, 0.01);

  const auto outside = RunRotorid(Args({"identify", "--window", "30,40"}));
  EXPECT_EQ(outside.exit_code, 1) << outside.err;
  EXPECT_NE(outside.err.find(Path("f.csv") + ": --window 30,40 holds no samples"), std::string::npos) << outside.err;
}

TEST_F(CliWorkflowTest, EveryReportHasInputFlights) {
  const auto identify = RunRotorid(Args({"identify", "--json", Path("i.json")}));
  ASSERT_EQ(identify.exit_code, 0) << identify.err;
  const std::vector<std::vector<std::string>> runs = {
      Args({"refine", "--effects", "delay", "--validate-vehicle", Path("B.yaml"), "--validate-log", Path("f.csv"),
            "--validate-window", "10,20", "--json", Path("r.json")}),
      Args({"delay", "--json", Path("d.json")}),
      Args({"validate", "--params", Path("i.json"), "--json", Path("v.json")})};
  for (const auto& args : runs) {
    const auto r = RunRotorid(args);
    ASSERT_EQ(r.exit_code, 0) << args[0] << ": " << r.err;
    const nlohmann::json report = LoadJson(*(std::find(args.begin(), args.end(), "--json") + 1));
    ASSERT_EQ(report["input"]["flights"].size(), 1u) << args[0];
    EXPECT_EQ(report["input"]["flights"][0]["rotor_signal"], "rpm") << args[0];
  }
  const nlohmann::json refine = LoadJson(Path("r.json"));
  EXPECT_NEAR(refine["input"]["validate_flights"][0]["used_s"].get<double>(), 10.0, 0.01);
}

TEST_F(CliWorkflowTest, AblateAndDelayWriteTheirReports) {
  for (const std::string command : {"ablate", "delay"}) {
    const std::string folder = Path("report_" + command);
    auto args = Args({command, "--report", folder, "--json", Path(command + ".json")});
    if (command == "ablate") args.insert(args.end(), {"--effects", "delay,motor_lag"});
    const auto r = RunRotorid(args);
    ASSERT_EQ(r.exit_code, 0) << command << ": " << r.err;
    EXPECT_NE(r.out.find("report: " + folder + "/report.html"), std::string::npos) << r.out;
    const std::string html = Slurp(folder + "/report.html");
    EXPECT_NE(html.find("rotorid " + command), std::string::npos) << command;
    // Progress goes to terminals only: none in a file.
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
  }
  EXPECT_NE(Slurp(Path("report_ablate") + "/report.html").find("lowest BIC"), std::string::npos);
}

// validate --report: the saved parameters applied to the given flights (it failed on a missing key
// of the saved report until the report took typed results).
TEST_F(CliWorkflowTest, ValidateWritesItsReport) {
  ASSERT_EQ(RunRotorid(Args({"identify", "--json", Path("params.json"), "-q"})).exit_code, 0);
  const std::string folder = Path("report_validate");
  const auto r = RunRotorid(Args({"validate", "--params", Path("params.json"), "--report", folder}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("report: " + folder + "/report.html"), std::string::npos) << r.out;
  const std::string html = Slurp(folder + "/report.html");
  EXPECT_NE(html.find("rotorid validate"), std::string::npos);
  EXPECT_NE(html.find("kt"), std::string::npos);
}

TEST_F(CliWorkflowTest, ConfigFileGivesOptionsAndIsRecorded) {
  std::ofstream(Path("run.yaml")) << "vehicle: [" << Path("B.yaml") << "]\nlog: [" << Path("f.csv")
                                  << "]\nwindow: [\"2,18\"]\ncutoff-hz: 8\nsegment: none\nall-parameters: true\n";
  const auto r =
      RunRotorid({"identify", "--config", Path("run.yaml"), "--edge-trim-s", "0.25", "--json", Path("c.json")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = LoadJson(Path("c.json"));
  EXPECT_EQ(report["settings"]["observation"]["filter"]["cutoff_hz"].get<double>(), 8.0);
  EXPECT_EQ(report["settings"]["observation"]["edge_trim_s"].get<double>(), 0.25);
  EXPECT_NEAR(report["input"]["flights"][0]["used_s"].get<double>(), 16.0, 0.01);
  EXPECT_EQ(report["config"]["file"], Path("run.yaml"));
  EXPECT_EQ(report["config"]["options"]["cutoff-hz"], 8.0);
  for (const auto& [name, entry] : report["linear"]["parameters"].items()) EXPECT_TRUE(entry["essential"]) << name;

  // The command line wins over the file.
  const auto wins =
      RunRotorid({"identify", "--config", Path("run.yaml"), "--cutoff-hz", "6", "--json", Path("c6.json")});
  ASSERT_EQ(wins.exit_code, 0) << wins.err;
  EXPECT_EQ(LoadJson(Path("c6.json"))["settings"]["observation"]["filter"]["cutoff_hz"].get<double>(), 6.0);

  std::ofstream(Path("bad.yaml")) << "cutof-hz: 8\n";
  ExpectUsageError(RunRotorid(Args({"identify", "--config", Path("bad.yaml")})), "cutof-hz");
}

// The ARPL Crazyflie logs (../shared/data/real/crazyflie-arpl-sysid/SOURCE.md): raw they cannot be
// identified; cut to the source's window, or segmented automatically, they can.
TEST(CliWorkflowRealTest, ArplCrazyflieWindowsAndSegmentsMakeRawLogsUsable) {
  const auto log = testing::SharedDataPath("real/crazyflie-arpl-sysid/raw/log15");
  if (!log) GTEST_SKIP() << "crazyflie-arpl-sysid absent";
  const std::string vehicle = testing::SourceDir() + "/data/vehicles/crazyflie21_brushed.yaml";
  const std::string dir = MakeTempDir("rotorid-arpl");
  const auto raw = RunRotorid({"identify", "--vehicle", vehicle, "--log", *log, "--segment", "none"});
  EXPECT_EQ(raw.exit_code, 1);
  EXPECT_NE(raw.err.find("kt could not be identified"), std::string::npos) << raw.err;

  const auto window = RunRotorid(
      {"identify", "--vehicle", vehicle, "--log", *log, "--window", "55,90", "--json", dir + "/window.json"});
  ASSERT_EQ(window.exit_code, 0) << window.err;
  const nlohmann::json report = LoadJson(dir + "/window.json");
  // The source notebook's Ixx = 1.029e-5 and Iyy = 1.105e-5 kg m^2 (its own mass and arm).
  EXPECT_NEAR(report["linear"]["parameters"]["cf21_brushed.I_xx"]["value"].get<double>(), 1.029e-5, 0.2e-5);
  EXPECT_NEAR(report["linear"]["parameters"]["cf21_brushed.I_yy"]["value"].get<double>(), 1.105e-5, 0.25e-5);
  const nlohmann::json& flight = report["input"]["flights"][0];
  EXPECT_EQ(flight["format"], "crazyflie_usd");
  EXPECT_EQ(flight["rotor_signal"], "command");
  EXPECT_NE(flight["rotor_signal_source"].get<std::string>().find("motor.m1"), std::string::npos);
  EXPECT_NEAR(flight["sample_rates_hz"]["imu"].get<double>(), 1011.0, 5.0);

  const auto segmented = RunRotorid({"identify", "--vehicle", vehicle, "--log", *log, "--json", dir + "/auto.json"});
  ASSERT_EQ(segmented.exit_code, 0) << segmented.err;
  EXPECT_NE(segmented.out.find("on ground"), std::string::npos) << segmented.out;
  std::set<std::string> reasons;
  const nlohmann::json segmented_report = LoadJson(dir + "/auto.json");
  for (const auto& span : segmented_report["input"]["flights"][0]["segments_left_out"])
    reasons.insert(span["reason"].get<std::string>());
  for (const char* reason : {"on ground", "take-off", "landing", "impact or spike"})
    EXPECT_EQ(reasons.count(reason), 1u) << reason;
}

// On NanoBench's helix flight the acc bias predicts the most in sample and makes the held-out gap
// worse; the forward selection must then refine rotor drag, which it had screened out as the acc
// bias's rival, instead of stopping with nothing selected (docs/real_flights.md).
TEST(CliWorkflowRealTest, DiagnosisRefinesTheRivalsOfALeaderThatFailsOutOfSample) {
  const auto log = testing::SharedDataPath("real/nanobench-cf21/B5_helix_fast_rep1.csv");
  if (!log) GTEST_SKIP() << "nanobench-cf21 absent";
  const std::string dir = MakeTempDir("rotorid-nanobench");
  std::ofstream(dir + "/map.yaml")
      << "time: {column: t, unit: s}\n"
         "gyro: {columns: [imu_gyro_x, imu_gyro_y, imu_gyro_z], unit: rad/s}\n"
         "acc: {columns: [imu_acc_x, imu_acc_y, imu_acc_z], unit: g}\n"
         "rotors: {columns: [motor_motor_m1, motor_motor_m2, motor_motor_m3, motor_motor_m4], unit: pwm}\n"
         "position: {columns: [px, py, pz], unit: m}\n"
         "quaternion: {columns: [qw, qx, qy, qz]}\n";
  const auto run =
      RunRotorid({"diagnose", "-q", "--vehicle", testing::SourceDir() + "/data/vehicles/crazyflie21_brushed.yaml",
                  "--log", *log, "--column-map", dir + "/map.yaml", "--allow-partial", "--effects",
                  "acc_bias,rotor_drag", "--max-effects", "1", "--json", dir + "/d.json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json report = LoadJson(dir + "/d.json");
  ASSERT_EQ(report["selected"].size(), 1u);
  EXPECT_EQ(report["selected"][0], "rotor_drag");
  for (const auto& entry : report["ranking"]) {
    if (entry["effect"] == "acc_bias") {
      EXPECT_LT(entry["shrink_pct"].get<double>(), 0.0);  // it failed out of sample
    }
  }
}

// A ULog read through its motor commands says so (a truncated log without esc_rpm falls back to
// them in "auto").
TEST(CliWorkflowRealTest, UlogCommandSignalIsNamed) {
  const auto log = testing::SharedDataPath("real/px4-flightreview-rs-lowrate/raw/ekf_failure.ulg");
  if (!log) GTEST_SKIP() << "px4-flightreview-rs-lowrate absent";
  const std::string dir = MakeTempDir("rotorid-ulog-read");
  std::ofstream(dir + "/quad.yaml") << "name: q\nmass: 2.0\nrotors:\n"
                                    << "  - {position: [0.11, -0.11, 0], spin: 1}\n"
                                    << "  - {position: [-0.11, 0.11, 0], spin: 1}\n"
                                    << "  - {position: [0.11, 0.11, 0], spin: -1}\n"
                                    << "  - {position: [-0.11, -0.11, 0], spin: -1}\n";
  const auto r = RunRotorid({"identify", "--vehicle", dir + "/quad.yaml", "--log", *log, "--rotor-signal", "command",
                             "--allow-partial", "--json", dir + "/u.json"});
  // This log is too slow for identification (motors at 10 Hz, SOURCE.md): the checks say so with
  // exit 3 (Table III above 100 %), and the report is still written.
  ASSERT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("check relative_error: error"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("note: the rotor signal is the motor command"), std::string::npos) << r.out;
  const nlohmann::json flight = LoadJson(dir + "/u.json")["input"]["flights"][0];
  EXPECT_EQ(flight["format"], "px4_ulog");
  EXPECT_EQ(flight["rotor_signal"], "command+voltage");
  const std::string notes = flight["notes"].dump();
  EXPECT_NE(notes.find("not a measured speed"), std::string::npos) << notes;
  EXPECT_NE(notes.find("command_to_speed"), std::string::npos) << notes;
}

// A discarded inertia the noise-aware TLS still estimates (a Crazyflie-like take-off with ground
// effect barely moves in yaw: I_zz is discarded and profiled) is what the model predicts with: the
// report gives it as `predicts_with`, and `validate` on the identification flight reproduces
// identify's Table III only with it (held at 0, Mx differs).
TEST(ValidateCliTest, PredictsWithTheDiscardedInertiaTheModelEstimated) {
  const std::string dir = MakeTempDir("rotorid-predicts-with");
  const auto path = [&](const std::string& name) { return dir + "/" + name; };
  const auto sim = RunRotorid({"simulate", "--preset", "CF", "--seconds", "40", "--seed", "1", "--profile",
                               "takeoff-landing", "--effect", "ground_effect=1.0", "--out", path("f.csv"),
                               "--vehicle-out", path("CF.yaml"), "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::vector<std::string> flight = {"--vehicle", path("CF.yaml"), "--log", path("f.csv")};
  auto run = [&](std::vector<std::string> args) {
    args.insert(args.end(), flight.begin(), flight.end());
    return RunRotorid(args);
  };
  const auto identify = run({"identify", "--json", path("i.json")});
  ASSERT_EQ(identify.exit_code, 0) << identify.err;
  nlohmann::json report = LoadJson(path("i.json"));
  const nlohmann::json& izz = report["linear"]["parameters"]["CF.I_zz"];
  ASSERT_FALSE(izz["essential"].get<bool>()) << izz;
  EXPECT_EQ(izz["value"].get<double>(), 0.0);
  ASSERT_TRUE(izz.contains("predicts_with")) << izz;
  EXPECT_GT(izz["predicts_with"].get<double>(), 0.0);
  const size_t line = identify.out.find("\nCF.I_zz ");
  ASSERT_NE(line, std::string::npos) << identify.out;
  EXPECT_NE(identify.out.substr(line, identify.out.find('\n', line + 1) - line).find("no (discarded), predicted with "),
            std::string::npos)
      << identify.out;

  const auto validate = run({"validate", "--params", path("i.json"), "--json", path("v.json")});
  ASSERT_EQ(validate.exit_code, 0) << validate.err;
  const nlohmann::json& table = report["linear"]["relative_error_pct"];
  const nlohmann::json validated = LoadJson(path("v.json"))["relative_error_pct"];
  for (const char* c : {"Fz", "Mx", "My"})
    EXPECT_NEAR(validated[c].get<double>(), table[c].get<double>(), 1e-9 * table[c].get<double>()) << c;

  report["linear"]["parameters"]["CF.I_zz"].erase("predicts_with");
  std::ofstream(path("held_at_zero.json")) << report.dump();
  // Held at 0, I_zz makes no body with these I_xx, I_yy: validate says so (exit 3, the report written).
  const auto at_zero = run({"validate", "--params", path("held_at_zero.json"), "--json", path("z.json")});
  ASSERT_EQ(at_zero.exit_code, 3) << at_zero.err;
  EXPECT_NE(at_zero.err.find("physical_consistency"), std::string::npos) << at_zero.err;
  EXPECT_GT(std::abs(LoadJson(path("z.json"))["relative_error_pct"]["Mx"].get<double>() - table["Mx"].get<double>()),
            1e-3);
}

}  // namespace
}  // namespace rotorid

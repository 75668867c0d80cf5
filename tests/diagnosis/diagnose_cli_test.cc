// `rotorid diagnose` end to end: a simulated flight with a withheld delay, the report keys of
// INTERFACE.md section 5, the verdict on stdout, and errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/model/effects.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;

nlohmann::json LoadJson(const std::string& path) { return nlohmann::json::parse(testing::Slurp(path)); }

TEST(DiagnoseCliTest, WithheldDelayThroughTheCommandLine) {
  const std::string dir = MakeTempDir("rotorid-diagnose");
  const auto sim =
      RunRotorid({"simulate", "--preset", "B", "--seconds", "40", "--seed", "41", "--effect", "delay_s=0.025", "--out",
                  dir + "/flight.csv", "--vehicle-out", dir + "/B.yaml", "--truth", dir + "/truth.json", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto r = RunRotorid({"diagnose", "--vehicle", dir + "/B.yaml", "--log", dir + "/flight.csv", "--folds", "3",
                             "--json", dir + "/diagnosis.json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("which: delay"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("where:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("how far"), std::string::npos) << r.out;

  const nlohmann::json report = LoadJson(dir + "/diagnosis.json");
  EXPECT_EQ(report["command"], "diagnose");
  // Under the how-far line of Mx, its held-out residual after each step (one here), baseline -> final,
  // as in the JSON, and the change.
  const double baseline_mx = report["baseline"]["residual_rms"]["Mx"].get<double>();
  const double final_mx = report["final"]["residual_rms"]["Mx"].get<double>();
  char residual[128];
  std::snprintf(residual, sizeof residual, "\n          residual %.2e -> %.2e N m (%+.0f %%)\n", baseline_mx, final_mx,
                100.0 * (final_mx / baseline_mx - 1.0));
  const size_t mx = r.out.find("\n       Mx ", r.out.find("how far"));
  ASSERT_NE(mx, std::string::npos) << r.out;
  EXPECT_EQ(r.out.find(residual, mx + 1), r.out.find('\n', mx + 1)) << residual << " under " << r.out.substr(mx);
  for (const char* block : {"baseline", "final"})
    for (const char* c : {"Fx", "Fy", "Fz", "Mx", "My", "Mz"})
      ASSERT_TRUE(report[block]["relative_error_pct"].contains(c)) << block << "." << c;
  EXPECT_TRUE(report["baseline"]["relative_error_pct"]["Fx"].is_null());
  EXPECT_TRUE(report["baseline"]["relative_error_pct"]["Mx"].is_number());
  ASSERT_TRUE(report["where"]["component"].is_string());
  const std::string component = report["where"]["component"];
  EXPECT_TRUE(component == "Fz" || component == "Mx" || component == "My") << component;
  ASSERT_TRUE(report["ranking"].is_array());
  ASSERT_EQ(report["ranking"].size(), DiagnosisCandidates().size());  // every effect of "all" is ranked
  for (const nlohmann::json& entry : report["ranking"]) {
    for (const char* key : {"effect", "significant", "shrink_pct", "magnitude"})
      EXPECT_TRUE(entry.contains(key)) << key;
    EXPECT_TRUE(entry["significant"].is_boolean());
    EXPECT_TRUE(entry["shrink_pct"].is_number());
  }
  const nlohmann::json& first = report["ranking"][0];
  EXPECT_EQ(first["effect"], "delay");
  EXPECT_TRUE(first["significant"].get<bool>());
  ASSERT_TRUE(first["magnitude"].contains("delay_s"));
  EXPECT_NEAR(first["magnitude"]["delay_s"]["value"].get<double>(), 0.025, 1e-3);
  EXPECT_GT(first["magnitude"]["delay_s"]["std"].get<double>(), 0.0);
  const nlohmann::json& acc = *std::find_if(report["ranking"].begin(), report["ranking"].end(),
                                            [](const nlohmann::json& e) { return e["effect"] == "acc_bias"; });
  EXPECT_EQ(acc["magnitude"]["acc_bias"]["value"].size(), 3u);
  ASSERT_TRUE(report["selected"].is_array());
  ASSERT_FALSE(report["selected"].empty());
  EXPECT_EQ(report["selected"][0], "delay");
  EXPECT_LT(report["final"]["relative_error_pct"]["Mx"].get<double>(),
            report["baseline"]["relative_error_pct"]["Mx"].get<double>());
  EXPECT_EQ(report["settings"]["diagnosis"]["folds"], 3);
}

// A force rotorid does not model (simulate --external-force, 4 % of B's weight turning once per 12 s)
// beside a 10 ms delay: the delay is named, and the force is called unexplained on the console, in the
// JSON (INTERFACE.md 6) and in the HTML report.
TEST(DiagnoseCliTest, ExternalForceIsUnexplainedOnTheConsoleTheJsonAndTheReport) {
  const std::string dir = MakeTempDir("rotorid-diagnose-force");
  const auto sim = RunRotorid({"simulate", "--preset", "B", "--seconds", "40", "--seed", "27", "--effect",
                               "delay_s=0.01", "--external-force", "0.5,0,0", "--external-force-period", "12", "--out",
                               dir + "/flight.csv", "--vehicle-out", dir + "/B.yaml", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto r = RunRotorid({"diagnose", "--vehicle", dir + "/B.yaml", "--log", dir + "/flight.csv", "--folds", "3",
                             "--json", dir + "/diagnosis.json", "--report", dir + "/report"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("which: delay"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("unexplained: Fx"), std::string::npos) << r.out;
  const nlohmann::json report = LoadJson(dir + "/diagnosis.json");
  ASSERT_TRUE(report["unexplained"].is_array());
  ASSERT_GE(report["unexplained"].size(), 2u);
  for (const nlohmann::json& u : report["unexplained"]) {
    EXPECT_TRUE(u["component"] == "Fx" || u["component"] == "Fy") << u.dump();
    EXPECT_GT(u["share_pct"].get<double>(), 89.0);
    EXPECT_NE(u["note"].get<std::string>().find("external force"), std::string::npos);
  }
  const std::string html = testing::Slurp(dir + "/report/report.html");
  EXPECT_NE(html.find("id=\"diagnosis_unexplained\""), std::string::npos);
  EXPECT_NE(html.find("a force off the thrust axis"), std::string::npos);
}

// A clean Crazyflie-like flight with every candidate's inputs (seed 106, where a 0.3 mm lever arm
// was once selected at a 0.34 % held-out shrink): the arm is significant but below its 1 mm floor,
// so the report calls it negligible, with the floor and its reason, and selects nothing.
TEST(DiagnoseCliTest, ASubMillimetreLeverArmIsNegligibleNotSelected) {
  const std::string dir = MakeTempDir("rotorid-diagnose-negligible");
  const auto sim = RunRotorid({"simulate", "--preset", "CF", "--mocap", "--battery", "--seconds", "40", "--seed",
                               "106", "--out", dir + "/flight.csv", "--vehicle-out", dir + "/CF.yaml", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto r = RunRotorid({"diagnose", "-q", "--vehicle", dir + "/CF.yaml", "--log", dir + "/flight.csv",
                             "--effects", "every", "--json", dir + "/diagnosis.json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = LoadJson(dir + "/diagnosis.json");
  EXPECT_TRUE(report["selected"].empty()) << report["selected"].dump();
  const nlohmann::json& arm = *std::find_if(report["ranking"].begin(), report["ranking"].end(),
                                            [](const nlohmann::json& e) { return e["effect"] == "imu_lever_arm"; });
  EXPECT_EQ(arm["status"], "negligible") << arm.dump();
  const std::string note = arm["note"];
  EXPECT_EQ(note.rfind("negligible: too small to matter; imu_position_m = (", 0), 0u) << note;
  EXPECT_NE(note.find("is below 1 mm in norm (3 std included)"), std::string::npos) << note;
}

TEST(DiagnoseCliTest, BadCandidateAndMissingLogFail) {
  const std::string dir = MakeTempDir("rotorid-diagnose-bad");
  const auto sim = RunRotorid({"simulate", "--preset", "B", "--seconds", "10", "--seed", "42", "--out",
                               dir + "/flight.csv", "--vehicle-out", dir + "/B.yaml", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto bad_effect =
      RunRotorid({"diagnose", "--vehicle", dir + "/B.yaml", "--log", dir + "/flight.csv", "--effects", "delay,wobble"});
  EXPECT_EQ(bad_effect.exit_code, 2);  // a usage error
  EXPECT_NE(bad_effect.err.find("wobble"), std::string::npos) << bad_effect.err;
  const auto bad_folds =
      RunRotorid({"diagnose", "--vehicle", dir + "/B.yaml", "--log", dir + "/flight.csv", "--folds", "1"});
  EXPECT_EQ(bad_folds.exit_code, 2);
  EXPECT_NE(bad_folds.err.find("folds"), std::string::npos) << bad_folds.err;
  const auto missing = RunRotorid({"diagnose", "--vehicle", dir + "/B.yaml", "--log", dir + "/none.csv"});
  EXPECT_NE(missing.exit_code, 0);
}

}  // namespace
}  // namespace rotorid

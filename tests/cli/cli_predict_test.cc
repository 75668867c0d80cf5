// rotorid predict end to end (INTERFACE.md 6): simulate, identify, predict; the JSON keys of the
// contract, the truth flown from `simulate --truth`, a log without a pose, and the usage errors.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;
using testing::Slurp;

class CliPredictTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(MakeTempDir("rotorid-predict"));
    for (const char* mocap : {"--mocap", ""}) {
      const std::string stem = *dir_ + (mocap[0] ? "/pose" : "/imu");
      std::vector<std::string> args = {"simulate",
                                       "--seconds",
                                       "12",
                                       "--rate",
                                       "100",
                                       "--noise",
                                       "low",
                                       "--out",
                                       stem + ".csv",
                                       "--truth",
                                       stem + "_truth.json",
                                       "--vehicle-out",
                                       *dir_ + "/A.yaml",
                                       "-q"};
      if (mocap[0]) args.push_back(mocap);
      const auto sim = RunRotorid(args);
      ASSERT_EQ(sim.exit_code, 0) << sim.err;
    }
    const auto id = RunRotorid({"identify", "--vehicle", *dir_ + "/A.yaml", "--log", *dir_ + "/pose.csv", "--json",
                                *dir_ + "/identify.json", "-q"});
    ASSERT_EQ(id.exit_code, 0) << id.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static nlohmann::json Predict(const std::vector<std::string>& extra, int* exit_code) {
    std::vector<std::string> args = {"predict", "--vehicle", *dir_ + "/A.yaml", "--json", *dir_ + "/p.json", "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto run = RunRotorid(args);
    *exit_code = run.exit_code;
    if (run.exit_code != 0 && run.exit_code != 3) ADD_FAILURE() << run.err;
    return nlohmann::json::parse(Slurp(*dir_ + "/p.json"));
  }
  static std::string* dir_;
};
std::string* CliPredictTest::dir_ = nullptr;

TEST_F(CliPredictTest, WritesTheContractKeys) {
  int code = -1;
  const nlohmann::json r = Predict({"--params", *dir_ + "/identify.json", "--log", *dir_ + "/pose.csv", "--horizon",
                                    "20", "--report", *dir_ + "/html"},
                                   &code);
  EXPECT_TRUE(code == 0 || code == 3);
  // The HTML report: one MAE-against-h figure per group, the model's curve and naive's in each.
  const std::string html = Slurp(*dir_ + "/html/predict.html");
  size_t figures = 0;
  for (size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) ++figures;
  EXPECT_EQ(figures, 4u);
  EXPECT_NE(html.find("angular_velocity (rad/s)"), std::string::npos);
  const nlohmann::json& p = r.at("prediction");
  EXPECT_EQ(p.at("horizon_steps"), 20);
  EXPECT_DOUBLE_EQ(p.at("dt_s").get<double>(), 0.01);
  EXPECT_EQ(p.at("scope"), "airborne");
  EXPECT_GT(p.at("windows").get<int>(), 500);
  for (const char* group : {"position", "velocity", "rotation", "angular_velocity"}) {
    ASSERT_EQ(p.at("mae").at(group).size(), 20u) << group;
    ASSERT_EQ(p.at("naive_mae").at(group).size(), 20u) << group;
    // An identified model on a low-noise flight: well below the naive predictor at 0.2 s.
    EXPECT_LT(p["mae"][group][19].get<double>(), 0.2 * p["naive_mae"][group][19].get<double>()) << group;
    EXPECT_TRUE(p.at("flights").at(0).at("mae").at(group).contains("10")) << group;
  }
  EXPECT_EQ(p["flights"][0]["file"], *dir_ + "/pose.csv");
  EXPECT_EQ(p["flights"][0]["windows"], p["windows"]);
  // The torque comparison by band, pooled and per flight, in the JSON and the HTML; an identified
  // model on a low-noise flight follows the body in the bands where it moves.
  ASSERT_EQ(p.at("torque_bands").size(), 5u);
  EXPECT_EQ(p["flights"][0].at("torque_bands"), p["torque_bands"]);
  const nlohmann::json& band = p["torque_bands"][2];
  EXPECT_EQ(band.at("band"), "1-3 Hz");
  for (const char* key : {"body_rms_radps2", "model_rms_radps2", "error_rms_radps2", "gain", "correlation",
                          "error_torque_rms_nm"})
    EXPECT_TRUE(band.at(key).contains("yaw")) << key;
  EXPECT_NEAR(band["gain"]["roll"].get<double>(), 1.0, 0.1);
  EXPECT_FALSE(band.at("centre_of_mass_equivalent_mm").contains("yaw"));
  EXPECT_TRUE(p["torque_bands"][4].at("high_hz").is_null());  // up to the Nyquist frequency
  EXPECT_TRUE(p["torque_bands"][0]["gain"]["roll"].is_null());  // the mean band: one value, no slope
  EXPECT_NE(html.find("by frequency"), std::string::npos);
  bool consistency = false;
  for (const auto& check : r.at("checks")) consistency |= check.at("name") == "physical_consistency";
  EXPECT_TRUE(consistency);
  EXPECT_EQ(r.at("input").at("flights").size(), 1u);
}

TEST_F(CliPredictTest, TheSimulatorsTruthReproducesItsFlight) {
  int code = -1;
  const nlohmann::json r = Predict(
      {"--params", *dir_ + "/pose_truth.json", "--log", *dir_ + "/pose.csv", "--stride", "4", "--scope", "whole"},
      &code);
  EXPECT_EQ(code, 0);
  const nlohmann::json& p = r.at("prediction");
  EXPECT_EQ(p.at("scope"), "whole");
  EXPECT_EQ(p.at("block"), "refined");
  // The log's noise is all that is left (low preset): the model's error is flat in h.
  EXPECT_LT(p["mae"]["angular_velocity"][49].get<double>(), 2.0 * p["mae"]["angular_velocity"][0].get<double>());
  EXPECT_LT(p["mae"]["rotation"][49].get<double>(), 0.02 * p["naive_mae"]["rotation"][49].get<double>());
}

TEST_F(CliPredictTest, ALogWithoutAPoseScoresRotationAndRatesOnly) {
  int code = -1;
  const nlohmann::json r =
      Predict({"--params", *dir_ + "/identify.json", "--log", *dir_ + "/imu.csv", "--horizon", "20"}, &code);
  const nlohmann::json& mae = r.at("prediction").at("mae");
  EXPECT_EQ(mae.at("rotation").size(), 20u);
  EXPECT_EQ(mae.at("angular_velocity").size(), 20u);
  EXPECT_FALSE(mae.contains("position"));
  EXPECT_FALSE(mae.contains("velocity"));
  EXPECT_LT(mae["rotation"][19].get<double>(), 0.2 * r["prediction"]["naive_mae"]["rotation"][19].get<double>());
}

TEST_F(CliPredictTest, AWindowCutsTheLog) {
  int code = -1;
  const nlohmann::json r = Predict({"--params", *dir_ + "/identify.json", "--log", *dir_ + "/pose.csv", "--window",
                                    "2,7", "--segment", "none", "--horizon", "10"},
                                   &code);
  // 2.00 .. 7.00 s at 100 Hz: 501 samples, at most 491 start instants of 10 steps.
  EXPECT_GT(r["prediction"]["windows"].get<int>(), 400);
  EXPECT_LE(r["prediction"]["windows"].get<int>(), 491);
  EXPECT_DOUBLE_EQ(r["input"]["flights"][0]["window_s"][0].get<double>(), 2.0);
  EXPECT_EQ(r["settings"]["segment"], "none");
  EXPECT_EQ(r["settings"]["torque_bias_window_s"], 0.0);
  // The observer needs its 0.3 s of past inside the window: 30 start instants fewer.
  const nlohmann::json observed =
      Predict({"--params", *dir_ + "/identify.json", "--log", *dir_ + "/pose.csv", "--window", "2,7", "--segment",
               "none", "--horizon", "10", "--torque-bias-window", "0.3"},
              &code);
  EXPECT_EQ(observed["prediction"]["windows"].get<int>(), r["prediction"]["windows"].get<int>() - 30);
  EXPECT_DOUBLE_EQ(observed["settings"]["torque_bias_window_s"].get<double>(), 0.3);
}

TEST_F(CliPredictTest, UsageErrors) {
  const std::string log = *dir_ + "/pose.csv", vehicle = *dir_ + "/A.yaml", params = *dir_ + "/identify.json";
  for (const std::vector<std::string>& bad : {std::vector<std::string>{"--horizon", "0"},
                                              {"--scope", "sky"},
                                              {"--set", "kd"},
                                              {"--stride", "-1"},
                                              {"--torque-bias-window", "-0.1"}}) {
    std::vector<std::string> args = {"predict", "--params", params, "--vehicle", vehicle, "--log", log};
    args.insert(args.end(), bad.begin(), bad.end());
    const auto run = RunRotorid(args);
    EXPECT_EQ(run.exit_code, 2) << bad[0] << ": " << run.err;
  }
  // A parameter the report lacks is bad input, named with the report.
  const auto run =
      RunRotorid({"predict", "--params", params, "--vehicle", vehicle, "--log", log, "--set", "A.I_ww=1", "-q"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("A.I_ww"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace rotorid

// The physical_consistency check and the allowed ranges end to end, on the bundled simulated flights
// (data/sim: A and B with a 5 ms delay and a 20 ms motor lag the linear model lacks).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::RunRotorid;

std::vector<std::string> BundledAPlusB(const std::string& command, const std::string& json) {
  const std::string d = testing::SourceDir() + "/data/sim/";
  return {command,     "--vehicle",  d + "A.yaml", "--log",           d + "A_train.csv",
          "--vehicle", d + "B.yaml", "--log",      d + "B_train.csv", "--weight",
          "1",         "--weight",   "2",          "--json",          json,
          "-q"};
}

std::vector<nlohmann::json> ChecksNamed(const nlohmann::json& report, const std::string& name) {
  std::vector<nlohmann::json> out;
  for (const nlohmann::json& c : report["checks"])
    if (c["name"] == name) out.push_back(c);
  return out;
}

// The linear step discards kd and with it every I_zz (no yaw scale): before, A's I_zz was predicted
// with 0 and B's with 1.4e-3 for 0.054, neither a body. Now each is predicted inside the range a body
// allows, the model is a body (exit 0), and the check warns that B's estimate is far from any.
TEST(PhysicalConsistencyCliTest, TheBundledLinearModelPredictsWithBodiesAndSaysHowFarTheEstimateIs) {
  const std::string json = testing::MakeTempDir("phys_identify") + "/identify.json";
  const testing::CommandResult r = RunRotorid(BundledAPlusB("identify", json));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(testing::Slurp(json));
  const std::vector<nlohmann::json> checks = ChecksNamed(report, "physical_consistency");
  ASSERT_EQ(checks.size(), 2u);
  for (const nlohmann::json& c : checks) EXPECT_NE(c["status"], "error") << c.dump();
  for (const char* config : {"A", "B"}) {
    const nlohmann::json& zz = report["linear"]["parameters"][std::string(config) + ".I_zz"];
    ASSERT_FALSE(zz["essential"].get<bool>()) << config;
    ASSERT_TRUE(zz.contains("allowed_range")) << zz.dump();
    const double low = zz["allowed_range"][0], high = zz["allowed_range"][1], used = zz["predicts_with"];
    EXPECT_GT(used, low) << config;
    EXPECT_LT(used, high) << config;
    EXPECT_EQ(zz["value"].get<double>(), 0.0);
  }
  // B (mass 1.452 kg, I_xx 0.0266, I_yy 0.0308): its I_zz must lie near |I_xx - I_yy| .. I_xx + I_yy.
  const nlohmann::json& b_zz = report["linear"]["parameters"]["B.I_zz"]["allowed_range"];
  EXPECT_NEAR(b_zz[0].get<double>(), 0.0043, 1e-3);
  EXPECT_NEAR(b_zz[1].get<double>(), 0.057, 3e-3);
  const nlohmann::json& bodies = report["linear"]["bodies"];
  ASSERT_EQ(bodies.size(), 2u);
  EXPECT_TRUE(bodies[1]["consistent"].get<bool>());
  EXPECT_GT(bodies[1]["distance_std"].get<double>(), 3.0);
  EXPECT_EQ(checks[1]["status"], "warning");
  // One yaw scale for kd and I_zz, which these flights do not fix: said, with what would fix it.
  for (const nlohmann::json& c : checks)
    EXPECT_NE(c["message"].get<std::string>().find("I_zz is not fixed by these flights"), std::string::npos)
        << c.dump();
}

// With the delay and the lag refined, kd comes back and both refined bodies are physical as
// estimated: the constrained estimate is the unconstrained one (distance 0), and kd, A.I_zz, B.I_zz
// stay within 1 % of the truth (5.1e-8, 0.029, 0.0543).
TEST(PhysicalConsistencyCliTest, TheRefinedBundledModelIsABodyAsEstimatedAndKeepsItsAccuracy) {
  const std::string json = testing::MakeTempDir("phys_refine") + "/refine.json";
  std::vector<std::string> args = BundledAPlusB("refine", json);
  args.insert(args.end(), {"--effects", "delay,motor_lag"});
  const testing::CommandResult r = RunRotorid(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(testing::Slurp(json));
  for (const nlohmann::json& body : report["refined"]["bodies"]) {
    EXPECT_TRUE(body["consistent"].get<bool>()) << body.dump();
    EXPECT_EQ(body["distance_std"].get<double>(), 0.0) << body.dump();
  }
  const nlohmann::json& p = report["refined"]["parameters"];
  EXPECT_NEAR(p["kd"]["value"].get<double>() / 5.1e-8, 1.0, 0.01);
  EXPECT_NEAR(p["A.I_zz"]["value"].get<double>() / 0.029, 1.0, 0.01);
  EXPECT_NEAR(p["B.I_zz"]["value"].get<double>() / 0.054343925, 1.0, 0.012);
}

}  // namespace
}  // namespace rotorid

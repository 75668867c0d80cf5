#include "rotorid/ident/body_consistency.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace rotorid {
namespace {

// NanoBench B3 + B5 + B10's linear identification (issue 37, 40.85 g): the centre of mass 23 mm below
// O_d (ms_z at 3 std) with a small roll inertia at O_d.
CheckedParameters NanoBenchLike() {
  CheckedParameters p;
  p.value = {{"kt", 1.9e-8},       {"kd", 1.0e-10},     {"CF.ms_x", 1e-5},   {"CF.ms_y", -2e-5},
             {"CF.ms_z", -9.5e-4}, {"CF.I_xx", 1.6e-5}, {"CF.I_yy", 2.6e-5}, {"CF.I_zz", 2.9e-5},
             {"CF.I_xy", 0.0},     {"CF.I_xz", 0.0},    {"CF.I_yz", 0.0}};
  p.std = {{"kt", 1e-11},       {"kd", 1e-12},     {"CF.ms_x", 2e-5}, {"CF.ms_y", 2e-5},
           {"CF.ms_z", 3.2e-4}, {"CF.I_xx", 1e-6}, {"CF.I_yy", 1e-6}, {"CF.I_zz", 2e-6},
           {"CF.I_xy", 5e-7},   {"CF.I_xz", 5e-7}, {"CF.I_yz", 5e-7}};
  for (const auto& [name, value] : p.value) p.essential[name] = true;
  p.mass_kg = {{"CF", 0.04085}};
  return p;
}

const Check* Find(const std::vector<Check>& checks, const std::string& name) {
  const auto it = std::find_if(checks.begin(), checks.end(), [&](const Check& c) { return c.name == name; });
  return it == checks.end() ? nullptr : &*it;
}

TEST(BodyConsistencyTest, AFirstMomentTheFlightsDoNotFixIsAnErrorWithItsDistance) {
  const std::vector<Check> checks = CheckParameters(NanoBenchLike(), {"CF"}, "linear");
  // The older checks pass: I at O_d is positive definite and meets the triangle inequalities.
  ASSERT_NE(Find(checks, "inertia"), nullptr);
  EXPECT_EQ(Find(checks, "inertia")->status, CheckStatus::kOk);
  const Check* check = Find(checks, "physical_consistency");
  ASSERT_NE(check, nullptr);
  EXPECT_EQ(check->status, CheckStatus::kError);
  EXPECT_NE(check->message.find("a first moment the flights do not fix (ms_x"), std::string::npos) << check->message;
  EXPECT_NE(check->message.find("ms_z = -0.00095 +- 0.00032 (-23.3 mm)"), std::string::npos) << check->message;
  EXPECT_NE(check->message.find("std from the estimate"), std::string::npos) << check->message;
  const std::vector<BodyAssessment> bodies = AssessBodies(NanoBenchLike());
  ASSERT_EQ(bodies.size(), 1u);
  EXPECT_FALSE(bodies[0].consistency.consistent);
  ASSERT_TRUE(bodies[0].has_projection);
  EXPECT_TRUE(CheckPhysicalConsistency(0.04085, bodies[0].projection.body).consistent);
  EXPECT_GT(bodies[0].projection.distance_std, 1.0);
}

TEST(BodyConsistencyTest, APossibleBodyPassesAndAModelWithoutMassIsNotChecked) {
  CheckedParameters p = NanoBenchLike();
  p.value["CF.ms_z"] = -0.04085 * 0.005;  // 5 mm below O_d
  const std::vector<Check> checks = PhysicalConsistencyChecks(p, "linear");
  const Check* check = Find(checks, "physical_consistency");
  ASSERT_NE(check, nullptr);
  EXPECT_EQ(check->status, CheckStatus::kOk) << check->message;
  EXPECT_NE(check->message.find("centre of mass (0.245, -0.49, -5) mm"), std::string::npos) << check->message;
  // Without a std (validate reads values only) there is no metric: the check without the distance.
  CheckedParameters values_only = NanoBenchLike();
  values_only.std.clear();
  const std::vector<BodyAssessment> bodies = AssessBodies(values_only);
  ASSERT_EQ(bodies.size(), 1u);
  EXPECT_FALSE(bodies[0].consistency.consistent);
  EXPECT_FALSE(bodies[0].has_projection);
  p.mass_kg.clear();
  EXPECT_TRUE(PhysicalConsistencyChecks(p, "linear").empty());
}

// Flight A alone (issue 37): I_zz discarded and predicted with its profiled 1.9e-4 for 0.029, so
// I_yy > I_xx + I_zz. The check names the discarded inertia; SetAllowedRanges gives the range a body
// allows and a value inside it to predict with: the model is then a body, and the check warns that
// the estimate lies far from every body.
TEST(BodyConsistencyTest, ADiscardedInertiaIsPredictedWithinTheRangeABodyAllows) {
  IdimSystem layout;
  layout.config_names = {"A"};
  layout.parameter_names = {"kt", "kd"};
  for (const char* name : kBodyParameterNames) layout.parameter_names.push_back(std::string("A.") + name);
  const int p = layout.num_parameters(), zz = layout.Column("A.I_zz");
  TlsSolution solution;
  solution.chi = Eigen::VectorXd::Zero(p);
  solution.chi << 3.6e-6, 0.0, -0.004, -0.002, -0.006, 0.018, 0.0192, 0.0, 0.0, 0.0, 0.0;
  solution.std = Eigen::VectorXd::Constant(p, 1e-5);
  solution.covariance = solution.std.cwiseAbs2().asDiagonal();
  solution.essential.assign(p, true);
  solution.essential[1] = solution.essential[zz] = false;
  solution.std[1] = solution.std[zz] = 0.0;
  solution.profiled.assign(p, false);
  solution.profiled[zz] = true;
  solution.profiled_chi = Eigen::VectorXd::Zero(p);
  solution.profiled_chi[zz] = 1.9e-4;
  solution.profiled_std = Eigen::VectorXd::Zero(p);
  solution.profiled_std[zz] = 3.9e-5;

  CheckedParameters before = CheckedFromSolution(layout, solution);
  before.mass_kg = {{"A", 1.285}};
  const std::vector<Check> before_checks = PhysicalConsistencyChecks(before, "linear");
  const Check* failed = Find(before_checks, "physical_consistency");
  ASSERT_NE(failed, nullptr);
  EXPECT_EQ(failed->status, CheckStatus::kError);
  EXPECT_NE(failed->message.find("a discarded inertia the flights do not fix: I_zz (predicted with its estimate "
                                 "0.00019 +- 3.9e-05)"),
            std::string::npos)
      << failed->message;
  EXPECT_NE(failed->message.find("the paper's B"), std::string::npos) << failed->message;

  SetAllowedRanges(layout, {{"A", 1.285}}, &solution);
  ASSERT_TRUE(solution.HasAllowedRange(zz));
  EXPECT_FALSE(solution.HasAllowedRange(layout.Column("A.I_xx")));  // essential: no range
  // The range at the centre of mass (-3.1, -1.6, -4.7) mm: about |I_xx - I_yy| .. I_xx + I_yy.
  EXPECT_NEAR(solution.allowed_low[zz], 0.0012, 2e-4);
  EXPECT_NEAR(solution.allowed_high[zz], 0.0372, 2e-4);
  ASSERT_TRUE(solution.PredictsWithinRange(zz));
  const double margin = 0.01 * (solution.allowed_high[zz] - solution.allowed_low[zz]);
  EXPECT_NEAR(PredictionChi(solution)[zz], solution.allowed_low[zz] + margin, 1e-15);
  EXPECT_EQ(solution.chi[zz], 0.0);  // the reported value stays as discarded

  CheckedParameters after = CheckedFromSolution(layout, solution);
  after.mass_kg = {{"A", 1.285}};
  const std::vector<Check> after_checks = PhysicalConsistencyChecks(after, "linear");
  const Check* passed = Find(after_checks, "physical_consistency");
  ASSERT_NE(passed, nullptr);
  EXPECT_NE(passed->message.find("a physically possible body with the values it predicts with"), std::string::npos)
      << passed->message;
  // The estimate itself (I_zz 1.9e-4 +- 3.9e-5) lies 26 std below the range, less where I_xx and I_yy
  // (1e-5 std) give a little: a finding, not an error.
  EXPECT_EQ(passed->status, CheckStatus::kWarning) << passed->message;
  const BodyAssessment body = AssessBodies(after).front();
  const double along_zz_only = (solution.allowed_low[zz] - 1.9e-4) / 3.9e-5;
  EXPECT_LE(body.projection.distance_std, along_zz_only);
  EXPECT_GT(body.projection.distance_std, 0.9 * along_zz_only);
  EXPECT_EQ(body.projection.largest_move_parameter, 5);  // I_zz
}

}  // namespace
}  // namespace rotorid

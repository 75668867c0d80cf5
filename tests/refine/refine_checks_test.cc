#include "rotorid/refine/refine_checks.h"

#include <gtest/gtest.h>

#include <limits>

namespace rotorid {
namespace {

// The linear step's roll and pitch errors of a simulated Crazyflie yaw spin with an IMU lever arm
// (763 % and 988 %, the centripetal acceleration it does not model), and the refined model's.
IdentificationResult LinearWithErrors(std::vector<std::optional<double>> errors) {
  IdentificationResult linear;
  linear.relative_error_pct = std::move(errors);
  return linear;
}
const IdentificationResult kLinear = LinearWithErrors({std::nullopt, std::nullopt, 0.2, 763.0, 988.0, 4.0});
std::vector<Check> LinearChecks() {
  return CheckRelativeError(kLinear.relative_error_pct, "linear", /*held_out=*/false);
}

RefineResult RefinedWithErrors(std::vector<std::optional<double>> errors) {
  RefineResult refined;
  refined.relative_error_pct = std::move(errors);
  return refined;
}

TEST(ExcuseLinearErrorTheRefinementExplains, ALinearErrorTheRefinedModelExplainsIsAWarning) {
  std::vector<Check> checks = LinearChecks();
  ASSERT_TRUE(AnyCheckFailed(checks));
  ExcuseLinearErrorTheRefinementExplains(kLinear, RefinedWithErrors({std::nullopt, std::nullopt, 0.108, 1.76, 0.98, 3.65}),
                                         &checks);
  EXPECT_FALSE(AnyCheckFailed(checks));
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_EQ(checks[0].status, CheckStatus::kWarning);
  EXPECT_NE(checks[0].message.find("(Mx 763 %, My 988 %)"), std::string::npos) << checks[0].message;
  EXPECT_NE(checks[0].message.find("refined: Fz 0.108 %, Mx 1.76 %, My 0.98 %, Mz 3.65 %"), std::string::npos)
      << checks[0].message;
}

TEST(ExcuseLinearErrorTheRefinementExplains, StaysAnErrorWhenTheRefinedModelFailsToo) {
  for (const double refined_my : {101.0, std::numeric_limits<double>::quiet_NaN()}) {
    std::vector<Check> checks = LinearChecks();
    ExcuseLinearErrorTheRefinementExplains(kLinear, RefinedWithErrors({std::nullopt, std::nullopt, 0.1, 2.0, refined_my, 3.0}),
                                           &checks);
    EXPECT_TRUE(AnyCheckFailed(checks)) << refined_my;
  }
  // No refined errors at all (nothing to compare): unchanged.
  std::vector<Check> checks = LinearChecks();
  ExcuseLinearErrorTheRefinementExplains(kLinear, RefinedWithErrors({}), &checks);
  EXPECT_TRUE(AnyCheckFailed(checks));
  // A linear error that is not finite is a failure of the computation: left an error.
  const IdentificationResult inf_linear =
      LinearWithErrors({0.1, 0.1, 0.1, std::numeric_limits<double>::infinity(), 1.0, 1.0});
  std::vector<Check> not_finite = CheckRelativeError(inf_linear.relative_error_pct, "linear", /*held_out=*/false);
  ExcuseLinearErrorTheRefinementExplains(inf_linear, RefinedWithErrors({0.1, 0.1, 0.1, 1.0, 1.0, 1.0}), &not_finite);
  EXPECT_TRUE(AnyCheckFailed(not_finite));
  // Other checks and the held-out ones are left alone.
  std::vector<Check> others = {{"inertia", CheckStatus::kError, "linear A inertia is not physical (...)"},
                               {"relative_error", CheckStatus::kError, "held-out refined: relative error ..."}};
  ExcuseLinearErrorTheRefinementExplains(kLinear, RefinedWithErrors({0.1, 0.1, 0.1, 1.0, 1.0, 1.0}), &others);
  EXPECT_EQ(others[0].status, CheckStatus::kError);
  EXPECT_EQ(others[1].status, CheckStatus::kError);
}

}  // namespace
}  // namespace rotorid

#include "rotorid/refine/refine_checks.h"

#include <gtest/gtest.h>

#include <limits>

#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"
#include "sim/sim_test_options.h"
#include "support/test_support.h"

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

TEST(ExcuseLinearErrorsTheRefinementExplains, ALinearErrorTheRefinedModelExplainsIsAWarning) {
  std::vector<Check> checks = LinearChecks();
  ASSERT_TRUE(AnyCheckFailed(checks));
  ExcuseLinearErrorsTheRefinementExplains(
      kLinear, RefinedWithErrors({std::nullopt, std::nullopt, 0.108, 1.76, 0.98, 3.65}), &checks);
  EXPECT_FALSE(AnyCheckFailed(checks));
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_EQ(checks[0].status, CheckStatus::kWarning);
  EXPECT_NE(checks[0].message.find("(Mx 763 %, My 988 %)"), std::string::npos) << checks[0].message;
  EXPECT_NE(checks[0].message.find("refined: Fz 0.108 %, Mx 1.76 %, My 0.98 %, Mz 3.65 %"), std::string::npos)
      << checks[0].message;
}

TEST(ExcuseLinearErrorsTheRefinementExplains, StaysAnErrorWhenTheRefinedModelFailsToo) {
  for (const double refined_my : {101.0, std::numeric_limits<double>::quiet_NaN()}) {
    std::vector<Check> checks = LinearChecks();
    ExcuseLinearErrorsTheRefinementExplains(
        kLinear, RefinedWithErrors({std::nullopt, std::nullopt, 0.1, 2.0, refined_my, 3.0}), &checks);
    EXPECT_TRUE(AnyCheckFailed(checks)) << refined_my;
  }
  // No refined errors at all (nothing to compare): unchanged.
  std::vector<Check> checks = LinearChecks();
  ExcuseLinearErrorsTheRefinementExplains(kLinear, RefinedWithErrors({}), &checks);
  EXPECT_TRUE(AnyCheckFailed(checks));
  // A linear error that is not finite is a failure of the computation: left an error.
  const IdentificationResult inf_linear =
      LinearWithErrors({0.1, 0.1, 0.1, std::numeric_limits<double>::infinity(), 1.0, 1.0});
  std::vector<Check> not_finite = CheckRelativeError(inf_linear.relative_error_pct, "linear", /*held_out=*/false);
  ExcuseLinearErrorsTheRefinementExplains(inf_linear, RefinedWithErrors({0.1, 0.1, 0.1, 1.0, 1.0, 1.0}), &not_finite);
  EXPECT_TRUE(AnyCheckFailed(not_finite));
  // Other checks and the held-out ones are left alone.
  std::vector<Check> others = {{"inertia", CheckStatus::kError, "linear A inertia is not physical (...)"},
                               {"relative_error", CheckStatus::kError, "held-out refined: relative error ..."}};
  ExcuseLinearErrorsTheRefinementExplains(kLinear, RefinedWithErrors({0.1, 0.1, 0.1, 1.0, 1.0, 1.0}), &others);
  EXPECT_EQ(others[0].status, CheckStatus::kError);
  EXPECT_EQ(others[1].status, CheckStatus::kError);
}

// `refine` checks a delay at half the cut-off as the diagnosis does: on a clean take-off-and-landing
// flight of A the controller's reply to gyro noise fakes a 1 ms delay at the 10 Hz cut-off that is
// gone at 5 Hz (a warning); a true 10 ms delay on the same flight holds (ok, both values named).
TEST(CheckTimingAtHalfCutoff, AFakedDelayIsAWarningAndATrueOneHolds) {
  if (!testing::kOptimisedBuild) GTEST_SKIP() << "a 60 s flight and four refinements: optimised builds only";
  auto check = [](double delay_s) {
    const SimulationVehicle preset = PresetVehicle("A");
    SimulationOptions sim;
    sim.duration_s = 60.0;
    sim.seed = 2;
    sim.profile = FlightProfile::kTakeoffLanding;
    sim.effects.Set("delay_s", delay_s);
    const IdentificationResult linear = testing::IdentifySimulated(Simulate(preset.vehicle, preset.parameters, sim));
    RefineOptions options;
    options.effects = {ParseEffectKind("delay")};
    const RefineResult refined = Refine(linear, options);
    IdentifyOptions identify;  // as IdentifySimulated identified it
    identify.allow_partial = true;
    return CheckTimingAtHalfCutoff(linear, identify, refined, options);
  };
  const std::vector<Check> faked = check(0.0);
  ASSERT_EQ(faked.size(), 1u);
  EXPECT_EQ(faked[0].name, "timing_at_half_cutoff");
  EXPECT_EQ(faked[0].status, CheckStatus::kWarning) << faked[0].message;
  EXPECT_NE(faked[0].message.find("delay_s = "), std::string::npos) << faked[0].message;
  EXPECT_NE(faked[0].message.find("at 5 Hz"), std::string::npos) << faked[0].message;
  const std::vector<Check> held = check(0.010);
  ASSERT_EQ(held.size(), 1u);
  EXPECT_EQ(held[0].status, CheckStatus::kOk) << held[0].message;
  EXPECT_NE(held[0].message.find("holds at half the low-pass cut-off"), std::string::npos) << held[0].message;
}

}  // namespace
}  // namespace rotorid

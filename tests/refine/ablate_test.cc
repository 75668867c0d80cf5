#include "rotorid/refine/ablate.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "rotorid/core/error.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// A flight with a delay and a motor lag, ablated over {delay, motor_lag, acc_bias}: every subset is
// refined, the effect-free one is the TLS fit, and both criteria rank the true pair first; adding
// the acc bias it does not have is charged for its parameters.
TEST(AblateTest, InformationCriteriaPickTheInjectedEffects) {
  Effects injected;
  injected.Set("delay_s", 0.015);
  injected.Set("motor_tau_s", 0.03);
  const IdentificationResult linear = testing::IdentifySimulated(testing::SimulatePreset("B", 60.0, 5, injected));
  const std::vector<EffectKind> candidates = {ParseEffectKind("delay"), ParseEffectKind("motor_lag"),
                                              ParseEffectKind("acc_bias")};
  int progress_calls = 0;
  const AblationResult ablation = Ablate(linear, {}, candidates, RefineOptions{}, 2, [&](int done, int total) {
    EXPECT_LE(done, total);
    ++progress_calls;
  });
  ASSERT_EQ(ablation.entries.size(), 8u);
  EXPECT_EQ(progress_calls, 8);
  int essential = 0;
  for (bool e : linear.solution.essential) essential += e;
  for (const AblationEntry& entry : ablation.entries) {
    int dimension = 0;
    for (EffectKind k : entry.effects) dimension += EffectDimension(k);
    EXPECT_EQ(entry.num_parameters, essential + dimension);
  }
  EXPECT_TRUE(ablation.entries[0].effects.empty());
  EXPECT_NEAR(ablation.entries[0].result.refined_criterion, ablation.entries[0].result.linear_criterion,
              1e-9 * ablation.entries[0].result.linear_criterion);

  auto best_by = [&](auto criterion) {
    return std::min_element(ablation.entries.begin(), ablation.entries.end(),
                            [&](const AblationEntry& a, const AblationEntry& b) { return criterion(a) < criterion(b); })
        ->effects;
  };
  const std::vector<EffectKind> truth = {ParseEffectKind("delay"), ParseEffectKind("motor_lag")};
  EXPECT_EQ(best_by([](const AblationEntry& e) { return e.bic; }), truth);
  EXPECT_EQ(best_by([](const AblationEntry& e) { return e.aic; }), truth);
  // The true pair's estimates.
  const AblationEntry& pair = ablation.entries[3];
  ASSERT_EQ(pair.effects, truth);
  EXPECT_NEAR(pair.result.effects.Scalar("delay_s"), 0.015, 1e-3);
  EXPECT_NEAR(pair.result.effects.Scalar("motor_tau_s"), 0.03, 3e-3);
  // Every effect subset fits at least as well as no effect at all (nested models).
  for (const AblationEntry& entry : ablation.entries)
    EXPECT_LE(entry.result.refined_criterion, ablation.entries[0].result.refined_criterion * (1 + 1e-6));
}

TEST(AblateTest, RefusesTooManyEffects) {
  const IdentificationResult linear = testing::IdentifySimulated(testing::SimulatePreset("B", 10.0, 2));
  const std::vector<EffectKind> nine(9, ParseEffectKind("delay"));
  EXPECT_THROW(Ablate(linear, {}, nine, RefineOptions{}, 1), Error);
}

}  // namespace
}  // namespace rotorid

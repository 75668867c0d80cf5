#include "rotorid/sim/realistic_effects.h"

#include <gtest/gtest.h>

#include <cmath>

#include "rotorid/core/units.h"

namespace rotorid {
namespace {

// Every draw lies in the documented ranges, both signs of the biases occur, the misalignment axis
// covers the sphere evenly, and effects that were not asked for stay zero.
TEST(RealisticEffectsTest, DrawsWithinTheRangesAndOnlyWhatIsAsked) {
  RandomStream random = EffectDrawStream(7, {ParseEffectKind("acc_bias")});
  constexpr int kDraws = 4000;
  Eigen::Vector3d axis_sum = Eigen::Vector3d::Zero();
  int positive_acc = 0, positive_gyro = 0;
  for (int i = 0; i < kDraws; ++i) {
    const Effects e =
        DrawRealisticEffects({ParseEffectKind("delay"), ParseEffectKind("motor_lag"), ParseEffectKind("acc_bias"),
                              ParseEffectKind("gyro_bias"), ParseEffectKind("misalignment")},
                             &random);
    ASSERT_GE(e.Scalar("delay_s"), 0.005);
    ASSERT_LE(e.Scalar("delay_s"), 0.040);
    ASSERT_GE(e.Scalar("motor_tau_s"), 0.020);
    ASSERT_LE(e.Scalar("motor_tau_s"), 0.060);
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(std::abs(e.Get("acc_bias")[a]), 0.1);
      ASSERT_LE(std::abs(e.Get("acc_bias")[a]), 0.5);
      ASSERT_GE(std::abs(e.Get("gyro_bias")[a]), 0.005);
      ASSERT_LE(std::abs(e.Get("gyro_bias")[a]), 0.03);
    }
    positive_acc += e.Get("acc_bias")[0] > 0.0;
    positive_gyro += e.Get("gyro_bias")[2] > 0.0;
    const double angle_deg = e.Get("misalignment_rad").norm() * kRadToDeg;
    ASSERT_GE(angle_deg, 1.0 - 1e-12);
    ASSERT_LE(angle_deg, 4.0 + 1e-12);
    axis_sum += e.Get("misalignment_rad").normalized();
  }
  // Binomial(4000, 1/2): std 32; a uniform axis: each mean component has std 1/sqrt(3 * 4000) = 0.009.
  EXPECT_NEAR(positive_acc, kDraws / 2, 5 * 32);
  EXPECT_NEAR(positive_gyro, kDraws / 2, 5 * 32);
  EXPECT_LT((axis_sum / kDraws).cwiseAbs().maxCoeff(), 5 * 0.0092);

  const Effects delay_only = DrawRealisticEffects({ParseEffectKind("delay")}, &random);
  EXPECT_GT(delay_only.Scalar("delay_s"), 0.0);
  EXPECT_EQ(delay_only.Scalar("motor_tau_s"), 0.0);
  EXPECT_TRUE(delay_only.Get("acc_bias").isZero());
  EXPECT_TRUE(delay_only.Get("gyro_bias").isZero());
  EXPECT_TRUE(delay_only.Get("misalignment_rad").isZero());

  // Per-rotor thrust scales: one per rotor, spread within the range, summing to zero.
  const Effects scales = DrawRealisticEffects({ParseEffectKind("rotor_thrust_scale")}, &random, 6);
  const Eigen::VectorXd s = scales.Get("rotor_thrust_scale");
  ASSERT_EQ(s.size(), 6);
  EXPECT_NEAR(s.sum(), 0.0, 1e-15);
  EXPECT_GT(s.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE(s.cwiseAbs().maxCoeff(), 0.06);
}

// A study is repeatable: the same seed and kinds give the same effects; other kinds, another stream.
TEST(RealisticEffectsTest, StreamsRepeatAndDifferByKinds) {
  RandomStream a = EffectDrawStream(3, {ParseEffectKind("delay")});
  RandomStream b = EffectDrawStream(3, {ParseEffectKind("delay")});
  RandomStream c = EffectDrawStream(3, {ParseEffectKind("delay"), ParseEffectKind("motor_lag")});
  const double first = DrawRealisticEffects({ParseEffectKind("delay")}, &a).Scalar("delay_s");
  EXPECT_EQ(first, DrawRealisticEffects({ParseEffectKind("delay")}, &b).Scalar("delay_s"));
  EXPECT_NE(first, DrawRealisticEffects({ParseEffectKind("delay")}, &c).Scalar("delay_s"));
}

}  // namespace
}  // namespace rotorid

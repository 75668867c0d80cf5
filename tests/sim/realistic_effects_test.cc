#include "rotorid/sim/realistic_effects.h"

#include <gtest/gtest.h>

#include <cmath>

#include "rotorid/core/units.h"

namespace rotorid {
namespace {

// Every draw lies in the documented ranges, both signs of the biases occur, the misalignment axis
// covers the sphere evenly, and effects that were not asked for stay zero.
TEST(RealisticEffectsTest, DrawsWithinTheRangesAndOnlyWhatIsAsked) {
  RandomStream random = EffectDrawStream(7, {EffectKind::kAccBias});
  constexpr int kDraws = 4000;
  Eigen::Vector3d axis_sum = Eigen::Vector3d::Zero();
  int positive_acc = 0, positive_gyro = 0;
  for (int i = 0; i < kDraws; ++i) {
    const Effects e = DrawRealisticEffects({EffectKind::kDelay, EffectKind::kMotorLag, EffectKind::kAccBias,
                                            EffectKind::kGyroBias, EffectKind::kMisalignment},
                                           &random);
    ASSERT_GE(e.delay_s, 0.005);
    ASSERT_LE(e.delay_s, 0.040);
    ASSERT_GE(e.motor_tau_s, 0.020);
    ASSERT_LE(e.motor_tau_s, 0.060);
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(std::abs(e.acc_bias[a]), 0.1);
      ASSERT_LE(std::abs(e.acc_bias[a]), 0.5);
      ASSERT_GE(std::abs(e.gyro_bias[a]), 0.005);
      ASSERT_LE(std::abs(e.gyro_bias[a]), 0.03);
    }
    positive_acc += e.acc_bias[0] > 0.0;
    positive_gyro += e.gyro_bias[2] > 0.0;
    const double angle_deg = e.misalignment_rad.norm() * kRadToDeg;
    ASSERT_GE(angle_deg, 1.0 - 1e-12);
    ASSERT_LE(angle_deg, 4.0 + 1e-12);
    axis_sum += e.misalignment_rad.normalized();
  }
  // Binomial(4000, 1/2): std 32; a uniform axis: each mean component has std 1/sqrt(3 * 4000) = 0.009.
  EXPECT_NEAR(positive_acc, kDraws / 2, 5 * 32);
  EXPECT_NEAR(positive_gyro, kDraws / 2, 5 * 32);
  EXPECT_LT((axis_sum / kDraws).cwiseAbs().maxCoeff(), 5 * 0.0092);

  const Effects delay_only = DrawRealisticEffects({EffectKind::kDelay}, &random);
  EXPECT_GT(delay_only.delay_s, 0.0);
  EXPECT_EQ(delay_only.motor_tau_s, 0.0);
  EXPECT_TRUE(delay_only.acc_bias.isZero());
  EXPECT_TRUE(delay_only.gyro_bias.isZero());
  EXPECT_TRUE(delay_only.misalignment_rad.isZero());
}

// A study is repeatable: the same seed and kinds give the same effects; other kinds, another stream.
TEST(RealisticEffectsTest, StreamsRepeatAndDifferByKinds) {
  RandomStream a = EffectDrawStream(3, {EffectKind::kDelay});
  RandomStream b = EffectDrawStream(3, {EffectKind::kDelay});
  RandomStream c = EffectDrawStream(3, {EffectKind::kDelay, EffectKind::kMotorLag});
  const double first = DrawRealisticEffects({EffectKind::kDelay}, &a).delay_s;
  EXPECT_EQ(first, DrawRealisticEffects({EffectKind::kDelay}, &b).delay_s);
  EXPECT_NE(first, DrawRealisticEffects({EffectKind::kDelay}, &c).delay_s);
}

}  // namespace
}  // namespace rotorid

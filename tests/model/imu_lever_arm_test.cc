// The `imu_lever_arm` effect's models: the simulator's accelerometer at r and the model's
// correction.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "rotorid/model/effects.h"

namespace rotorid {
namespace {

const Eigen::Vector3d kImuPosition(0.022, -0.015, 0.027);  // m, in F_d

}  // namespace

// Not in the registry yet (docs/adding_an_effect.md, "Status"): the test takes the descriptor
// from its file.
namespace internal {
const EffectDescriptor& ImuLeverArmEffect();
}  // namespace internal

namespace {

const EffectDescriptor& LeverArm() { return internal::ImuLeverArmEffect(); }

TEST(ImuLeverArmTest, DescribesItselfWithTheInterfaceNames) {
  EXPECT_EQ(LeverArm().name(), "imu_lever_arm");
  EXPECT_EQ(LeverArm().parameter_name(), "imu_position_m");
  EXPECT_EQ(LeverArm().FixedDimension(), 3);
  EXPECT_EQ(LeverArm().stage(), EffectStage::kImuSensor);
  EXPECT_EQ(LeverArm().info().chain_position, 0);  // next to the physics, before misalignment and bias
}

// The sensor model and the correction are each other's inverse, and the correction is the one
// INTERFACE.md writes: s = s_r - w' x r - w x (w x r), the gyro untouched.
TEST(ImuLeverArmTest, CorrectionUndoesTheSensorModel) {
  const Eigen::Vector3d w(0.7, -1.2, 2.5), w_dot(3.0, -4.0, 1.5), s(0.3, -0.2, 9.6);
  ImuSample<double> sample{w, w_dot, s};
  LeverArm().ApplyToSensor(kImuPosition.data(), &sample);
  const Eigen::Vector3d expected = s + w_dot.cross(kImuPosition) + w.cross(w.cross(kImuPosition));
  EXPECT_LT((sample.specific_force - expected).norm(), 1e-14);
  EXPECT_EQ(sample.angular_velocity, w);
  LeverArm().CorrectImu(kImuPosition.data(), &sample);
  EXPECT_LT((sample.specific_force - s).norm(), 1e-14);
}

}  // namespace
}  // namespace rotorid

// The `imu_lever_arm` effect: the simulator's accelerometer at r, the model's correction, and a
// simulated lever arm recovered by the refinement.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "rotorid/core/error.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/model/effects.h"
#include "rotorid/refine/refine.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

const Eigen::Vector3d kImuPosition(0.022, -0.015, 0.027);  // m, in F_d

const EffectDescriptor& LeverArm() { return *ParseEffectKind("imu_lever_arm"); }

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

// A flight controller 20 mm forward, 15 mm to the right and 10 mm above O_d on configuration B,
// flown for 60 s. The force rows see r only as ms - m r; the moment rows fix ms_x, ms_y (the
// thrust's lever) but hardly ms_z (the specific force is along z), so r_x and r_y are recovered,
// and r_z is held at the vehicle file's value (0 here): ms_z then carries ms_z - m r_z, the first
// moment the force rows see. Estimated, r_z took ms_z's place (18.7 mm here, 2-4 mm on simulated
// Crazyflies without a lever arm).
TEST(ImuLeverArmTest, RefinementRecoversASimulatedLeverArmAndHoldsItsZ) {
  const Eigen::Vector3d truth(0.020, -0.015, 0.010);
  Effects effects;
  effects.Set("imu_position_m", truth);
  const SimulationResult sim = testing::SimulatePreset("B", 60.0, 3, effects);
  const IdentificationResult linear = testing::IdentifySimulated(sim);
  RefineOptions options;
  options.effects = {&LeverArm()};
  const RefineResult refined = Refine(linear, options);
  ASSERT_TRUE(refined.has_covariance);
  const Eigen::VectorXd r = refined.effects.Get(&LeverArm());
  const Eigen::VectorXd std_dev = refined.effects_std.Get(&LeverArm());
  for (int a = 0; a < 2; ++a) {
    EXPECT_NEAR(r[a], truth[a], 0.002) << "axis " << a;
    EXPECT_NEAR(r[a], truth[a], 3 * std_dev[a]) << "axis " << a << ", std " << std_dev[a];
  }
  EXPECT_NEAR(r[2], 0.0, 1e-6) << "r_z is held, not estimated";
  EXPECT_EQ(std_dev[2], 0.0);
  EXPECT_EQ(LeverArm().FreeDimension(sim.vehicle), 2);
  // ms_x and ms_y, fixed by the moment rows, stay at the truth: the lever arm does not trade
  // against them. ms_z, when the essential selection keeps it, is the force rows' ms_z - m r_z.
  const auto named = NamedParameters(linear.system, refined.refined.chi);
  for (int a = 0; a < 2; ++a) {
    const std::string name = std::string("B.ms_") + "xy"[a];
    EXPECT_NEAR(named.at(name), sim.truth.body.first_moment[a], 0.02 * std::abs(sim.truth.body.first_moment[a]))
        << name;
  }
  const auto ms_z = std::find(linear.system.parameter_names.begin(), linear.system.parameter_names.end(), "B.ms_z") -
                    linear.system.parameter_names.begin();
  if (refined.refined.essential[static_cast<size_t>(ms_z)]) {
    EXPECT_NEAR(named.at("B.ms_z"), sim.truth.body.first_moment[2] - sim.vehicle.mass_kg * truth[2],
                3 * refined.refined.std[ms_z]);
  }
  for (const std::string& pair : refined.resting_on_discarded)
    EXPECT_EQ(pair.find("imu_position_m_z"), std::string::npos) << pair << ": a held coordinate rests on nothing";
}

// A lever arm known from the vehicle (`imu_position` in the vehicle file) is corrected in
// processing: the refinement then finds nothing left of it (and the arm itself when it is not
// given), and the first moments stay at the truth.
TEST(ImuLeverArmTest, KnownLeverArmFromTheVehicleFileIsCorrectedInProcessing) {
  const Eigen::Vector3d truth(0.020, -0.015, 0.010);
  Effects effects;
  effects.Set("imu_position_m", truth);
  const SimulationResult sim = testing::SimulatePreset("B", 60.0, 3, effects);
  SimulationResult known = sim;
  known.vehicle.known_effects["imu_lever_arm"] = truth;
  const IdentificationResult ignored = testing::IdentifySimulated(sim);
  const IdentificationResult corrected = testing::IdentifySimulated(known);
  RefineOptions options;
  options.effects = {&LeverArm()};
  const Eigen::VectorXd left_when_ignored = Refine(ignored, options).effects.Get(&LeverArm());
  const Eigen::VectorXd left_when_known = Refine(corrected, options).effects.Get(&LeverArm());
  for (int a = 0; a < 2; ++a) {
    EXPECT_NEAR(left_when_ignored[a], truth[a], 0.002) << "axis " << a;
    EXPECT_NEAR(left_when_known[a], 0.0, 0.002) << "axis " << a;
  }
  const std::map<std::string, double> values = NamedParameters(corrected.system, corrected.solution.chi);
  for (int a = 0; a < 2; ++a) {
    const std::string name = std::string("B.ms_") + "xy"[a];
    const auto column =
        std::find(corrected.system.parameter_names.begin(), corrected.system.parameter_names.end(), name) -
        corrected.system.parameter_names.begin();
    EXPECT_NEAR(values.at(name), sim.truth.body.first_moment[a], 3 * corrected.solution.std[column]) << name;
  }
}

TEST(ImuLeverArmTest, VehicleFileGivesAKnownLeverArmAndRefusesOneInMillimetres) {
  const std::string rotors =
      "name: B\nmass: 1.3\nrotors:\n  - {position: [0.2, 0, 0], spin: 1}\n"
      "  - {position: [-0.2, 0, 0], spin: 1}\n  - {position: [0, 0.2, 0], spin: -1}\n"
      "  - {position: [0, -0.2, 0], spin: -1}\n";
  const Vehicle vehicle = ParseVehicleYaml(rotors + "imu_position: [0.02, -0.015, 0.01]\n", "B.yaml");
  ASSERT_EQ(vehicle.known_effects.count("imu_lever_arm"), 1u);
  EXPECT_LT((vehicle.known_effects.at("imu_lever_arm") - Eigen::Vector3d(0.02, -0.015, 0.01)).norm(), 1e-15);
  // Written back as it was read.
  EXPECT_EQ(ParseVehicleYaml(VehicleToYaml(vehicle), "again.yaml").known_effects, vehicle.known_effects);
  try {
    ParseVehicleYaml(rotors + "imu_position: [20, -15, 10]\n", "B.yaml");
    ADD_FAILURE() << "a lever arm in mm was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("B.yaml:8:16"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("imu_position values must lie in [-0.3, 0.3] m"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rotorid

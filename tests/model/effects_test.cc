// The effect registry and the generic effect values (include/rotorid/model/effects.h), and the
// inputs a processed flight carries for effects that need more than the IMU and rotor signal.

#include "rotorid/model/effects.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "rotorid/core/error.h"
#include "rotorid/ident/observation.h"
#include "rotorid/model/rotation.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"

namespace rotorid {
namespace {

TEST(EffectRegistryTest, NamesAreUniqueAndParseInEitherForm) {
  std::set<std::string> names;
  for (EffectKind kind : AllEffects()) {
    EXPECT_TRUE(names.insert(kind->name()).second) << kind->name();
    if (kind->parameter_name() != kind->name()) {
      EXPECT_TRUE(names.insert(kind->parameter_name()).second);
    }
    EXPECT_EQ(ParseEffectKind(kind->name()), kind);
    EXPECT_EQ(ParseEffectKind(kind->parameter_name()), kind);
    EXPECT_EQ(AllEffects()[static_cast<size_t>(kind->index())], kind);
    EXPECT_LT(kind->info().lower_bound, kind->info().upper_bound) << kind->name();
    EXPECT_GT(kind->info().settle_tolerance, 0.0) << kind->name();
  }
  EXPECT_EQ(ParseEffectList("all"), DefaultCandidates());
  // An effect left out of "all" is taken when named.
  const EffectKind lever_arm = ParseEffectKind("imu_lever_arm");
  const std::vector<EffectKind> in_all = DefaultCandidates();
  EXPECT_EQ(std::count(in_all.begin(), in_all.end(), lever_arm), 0);
  EXPECT_EQ(ParseEffectList("delay,imu_lever_arm").back(), lever_arm);
  EXPECT_EQ(ParseEffectList("every"), AllEffects());
  EXPECT_THROW(ParseEffectKind("wind"), Error);
}

// The five effects of INTERFACE.md section 1 keep their names, order and sizes.
TEST(EffectRegistryTest, TheFirstFiveAreTheInterfaceEffects) {
  const std::vector<std::pair<std::string, std::string>> expected = {{"delay", "delay_s"},
                                                                     {"motor_lag", "motor_tau_s"},
                                                                     {"acc_bias", "acc_bias"},
                                                                     {"gyro_bias", "gyro_bias"},
                                                                     {"misalignment", "misalignment_rad"}};
  ASSERT_GE(AllEffects().size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(AllEffects()[k]->name(), expected[k].first);
    EXPECT_EQ(AllEffects()[k]->parameter_name(), expected[k].second);
    EXPECT_EQ(EffectDimension(AllEffects()[k]), k < 2 ? 1 : 3);
  }
}

TEST(EffectsTest, ValuesAreKeyedByDescriptorAndZeroWhenUnset) {
  Effects e;
  const EffectKind bias = ParseEffectKind("acc_bias");
  EXPECT_TRUE(e.IsZero(bias));
  EXPECT_EQ(e.Get(bias), Eigen::VectorXd::Zero(3));
  e.Assign("acc_bias=0.1,-0.2,0.3");
  EXPECT_EQ(e.Get("acc_bias"), Eigen::Vector3d(0.1, -0.2, 0.3));
  EXPECT_FALSE(e.StageIsZero(EffectStage::kImuSensor));
  EXPECT_TRUE(e.StageIsZero(EffectStage::kRotorSignal));
  EXPECT_THROW(e.Set(bias, Eigen::VectorXd::Zero(2)), Error);
  EXPECT_THROW(e.Assign("motor_tau_s=-0.01"), Error);  // its sign convention: tau >= 0
  EXPECT_THROW(e.Assign("delay_s=abc"), Error);
}

TEST(EffectsTest, FormatUsesTheDisplayUnit) {
  EXPECT_EQ(ParseEffectKind("delay")->Format(Eigen::VectorXd::Constant(1, 0.0123), Eigen::VectorXd()), "12.3 ms");
  EXPECT_EQ(ParseEffectKind("acc_bias")->Format(Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::VectorXd()),
            "(0.1, 0.2, 0.3) m/s^2");
}

// The physical ranges (MODEL.md 8): every effect has one at least as wide as what the simulator's
// studies draw, some scale with the vehicle, and an estimate outside by more than 3 std is named with
// its range.
TEST(EffectsTest, PhysicalRangesScaleWithTheVehicleAndAllowThreeStd) {
  const SimulationVehicle b = PresetVehicle("B"), cf = PresetVehicle("CF");
  for (EffectKind kind : AllEffects()) {
    const PlausibleRange& range = kind->info().plausible;
    EXPECT_FALSE(range.why.empty()) << kind->name();
    EXPECT_LT(range.low, range.high) << kind->name();
    // The simulator's realistic draws (sized for the paper's vehicle) are plausible on it.
    const DrawRange& draw = kind->info().draw;
    const int n = kind->Dimension(b.vehicle);
    const double high = draw.high * draw.to_si;
    const Eigen::VectorXd value = draw.shape == DrawShape::kRandomDirection
                                      ? Eigen::VectorXd(Eigen::VectorXd::Constant(n, high / std::sqrt(n)))
                                      : Eigen::VectorXd(Eigen::VectorXd::Constant(n, high));
    EXPECT_EQ(kind->Implausible(value, {}, b.vehicle), "") << kind->name();
  }
  // The lever arm is bounded by the arm length: 0.225 m on B, 0.046 m on the Crazyflie.
  const EffectKind lever_arm = ParseEffectKind("imu_lever_arm");
  const Eigen::Vector3d arm(-0.1, 0.0, 0.0);
  EXPECT_EQ(lever_arm->Implausible(arm, {}, b.vehicle), "");
  const std::string why = lever_arm->Implausible(arm, {}, cf.vehicle);
  EXPECT_NE(
      why.find("imu_position_m = (-100, 0, 0 held) mm (norm 100 mm) is outside its physical range (norm <= 46 mm)"),
      std::string::npos)
      << why;
  // 3 std of slack: 0.2 +- 0.04 is within 3 std of 0.1, 0.2 +- 0.03 is not.
  const EffectKind scale = ParseEffectKind("rotor_thrust_scale");
  const Eigen::Vector4d scales(0.2, -0.1, -0.05, -0.05);
  EXPECT_EQ(scale->Implausible(scales, Eigen::Vector4d::Constant(0.04), b.vehicle), "");
  EXPECT_EQ(scale->Implausible(scales, Eigen::Vector4d::Constant(0.03), b.vehicle),
            "rotor_thrust_scale_1 = 20 +- 3 % is outside its physical range [-10 %, 10 %]: propellers and motors "
            "differ by a few %");
  // Rotor inertia scales with mass x arm^2: 1e-5 kg m^2 is plausible on B, not on the Crazyflie.
  const EffectKind inertia = ParseEffectKind("rotor_inertia");
  EXPECT_EQ(inertia->Implausible(Eigen::VectorXd::Constant(1, 1e-5), {}, b.vehicle), "");
  EXPECT_NE(inertia->Implausible(Eigen::VectorXd::Constant(1, 1e-5), {}, cf.vehicle), "");
}

// A lever arm whose x, y norm is below 1 mm with 3 std is negligible; its held z does not count, and
// an estimate whose 3 std reach the floor is not. Effects without a floor are never negligible, and
// the simulator's smallest realistic draw of an effect with one is above it.
TEST(EffectsTest, EstimatesBelowAnEffectsFloorAreNegligible) {
  const EffectKind lever_arm = ParseEffectKind("imu_lever_arm");
  const Eigen::Vector3d std_dev(0.1e-3, 0.1e-3, 0.0);
  const std::string why = lever_arm->Negligible(Eigen::Vector3d(0.3e-3, -0.4e-3, 0.02), std_dev);
  EXPECT_EQ(why.rfind("imu_position_m = (0.3 +- 0.1, -0.4 +- 0.1, 20 held) mm is below 1 mm in norm (3 std included): "
                      "an IMU's position is known to about a millimetre",
                      0),
            0u)
      << why;
  EXPECT_EQ(lever_arm->Negligible(Eigen::Vector3d(0.3e-3, -0.4e-3, 0.0), 2.0 * std_dev), "");  // 0.5 + 3 x 0.2 mm
  EXPECT_EQ(lever_arm->Negligible(Eigen::Vector3d(1.1e-3, 0.0, 0.0), {}), "");
  // The timing effects' floor, 1 ms: the 0.10-0.11 +- 0.04 ms time shifts measured on flights
  // without one; a delay counts by its size, either sign.
  for (const char* timing : {"motor_lag", "delay", "acc_delay"}) {
    const EffectKind kind = ParseEffectKind(timing);
    EXPECT_NE(kind->Negligible(Eigen::VectorXd::Constant(1, 0.11e-3), Eigen::VectorXd::Constant(1, 0.04e-3)), "");
    EXPECT_EQ(kind->Negligible(Eigen::VectorXd::Constant(1, 0.5e-3), Eigen::VectorXd::Constant(1, 0.2e-3)), "");
  }
  EXPECT_EQ(ParseEffectKind("delay")->Negligible(Eigen::VectorXd::Constant(1, -2e-3), {}), "");
  EXPECT_NE(ParseEffectKind("misalignment")
                ->Negligible(Eigen::Vector3d(9.4e-5, 5.7e-5, -4.26e-3), Eigen::Vector3d(1.0e-4, 1.1e-4, 0.92e-3)),
            "");  // A_clean's 0.24 deg about z
  EXPECT_NE(ParseEffectKind("acc_bias")
                ->Negligible(Eigen::Vector3d(8.2e-5, -3.1e-4, 2.0e-3), Eigen::Vector3d(1.5e-4, 1.4e-4, 1.05e-3)),
            "");  // independent CF_battery_motor_lag's 0.2 mg
  EXPECT_NE(ParseEffectKind("rotor_thrust_scale")
                ->Negligible(Eigen::Vector4d(2.5e-4, 1.5e-4, -2.4e-4, -1.6e-4), Eigen::Vector4d::Constant(1.2e-4)),
            "");
  EXPECT_EQ(ParseEffectKind("rotor_thrust_scale")
                ->Negligible(Eigen::Vector4d(0.011, -0.003, -0.009, 0.001), Eigen::Vector4d::Constant(0.0055)),
            "");
  for (EffectKind kind : AllEffects()) {
    const double floor = kind->info().negligible.below;
    if (floor != 0.0) {
      // A floor never hides an effect of the sizes the simulator draws: a draw of sizes starts above
      // it; a spread around zero (per-rotor scales) is at least three floors wide each way, so the
      // largest of four rotors falls below the floor in about 1 % of flights.
      const DrawRange& draw = kind->info().draw;
      if (draw.low >= 0.0)
        EXPECT_GT(draw.low * draw.to_si, floor) << kind->name();
      else
        EXPECT_GE(std::min(-draw.low, draw.high) * draw.to_si / floor, 3.0 - 1e-9) << kind->name();
      continue;
    }
    EXPECT_EQ(kind->Negligible(Eigen::VectorXd::Zero(kind->Dimension(PresetVehicle("B").vehicle)), {}), "")
        << kind->name();
  }
}

// An effect that needs an input a log lacks is unavailable, with the reason.
TEST(EffectsTest, MissingInputsMakeAnEffectUnavailable) {
  EffectDescriptor::Info info;
  info.name = "needs_velocity";
  info.inputs = {FlightInput::kVelocity, FlightInput::kVoltage};
  const EffectDescriptor effect(info);
  FlightInputs available;
  available.voltage = true;
  const std::string reason = effect.Unavailable(available);
  EXPECT_NE(reason.find("needs_velocity needs the velocity"), std::string::npos) << reason;
  EXPECT_EQ(reason.find("voltage"), std::string::npos) << reason;
  available.velocity = true;
  EXPECT_EQ(effect.Unavailable(available), "");
}

// A motion-capture flight carries the velocity of O_d in F_d and the height: against the
// simulator's truth, within the low-pass' error.
TEST(ProcessedFlightInputsTest, MocapFlightCarriesVelocityInTheBodyFrameAndHeight) {
  const SimulationVehicle v = PresetVehicle("A");
  SimulationOptions options;
  options.duration_s = 20.0;
  options.mocap = true;
  options.noise = NoiseLevels::Preset("none");
  const SimulationResult sim = Simulate(v.vehicle, v.parameters, options);
  const ProcessedFlight flight = ProcessFlight(sim.log, sim.vehicle, 1.0, ObservationOptions());
  ASSERT_TRUE(flight.inputs().velocity);
  ASSERT_TRUE(flight.inputs().height);
  EXPECT_FALSE(flight.inputs().voltage);
  EXPECT_FALSE(flight.inputs().rotor_command);
  EXPECT_TRUE(flight.inputs().rotor_acceleration);
  double worst = 0.0, largest = 0.0, worst_height = 0.0;
  for (int i : flight.row_samples) {
    // The processed base time is the log's (no jitter here).
    const Eigen::Vector4d q = sim.states.attitude_wxyz.row(i).transpose();
    const Eigen::Matrix3d r_wb = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
    const Eigen::Vector3d truth = r_wb.transpose() * sim.states.velocity_w_mps.row(i).transpose();
    worst = std::max(worst, (flight.velocity_mps->row(i).transpose() - truth).norm());
    largest = std::max(largest, truth.norm());
    worst_height = std::max(worst_height, std::abs((*flight.height_m)[i] - sim.states.position_w_m(i, 2)));
  }
  EXPECT_GT(largest, 0.3);  // the flight moves
  EXPECT_LT(worst, 0.02 * largest);
  EXPECT_LT(worst_height, 0.01);
}

}  // namespace
}  // namespace rotorid

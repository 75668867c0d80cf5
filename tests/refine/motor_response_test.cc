#include "rotorid/refine/motor_response.h"

#include <gtest/gtest.h>

#include "rotorid/core/error.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"

namespace rotorid {
namespace {

// The simulator's motors follow the logged command through the `delay` and `motor_lag` effects; the
// estimate from the command and the true rotor speeds recovers both, and an identity static map.
TEST(MotorResponseTest, RecoversTheSimulatorsDelayAndLag) {
  const SimulationVehicle v = PresetVehicle("B");
  for (const auto& [delay, tau] : {std::pair{0.012, 0.035}, std::pair{0.0, 0.02}, std::pair{0.031, 0.055}}) {
    SCOPED_TRACE(delay);
    SimulationOptions options;
    options.duration_s = 10.0;
    options.seed = 11;
    options.effects.Set("delay_s", delay);
    options.effects.Set("motor_tau_s", tau);
    const SimulationResult sim = Simulate(v.vehicle, v.parameters, options);
    const MotorResponse r = EstimateMotorResponse(sim.log.t_s, sim.log.rotor_radps, sim.states.rotor_speed_radps);
    EXPECT_NEAR(r.delay_s, delay, 0.5e-3);
    EXPECT_NEAR(r.motor_tau_s, tau, 0.1 * tau);
    EXPECT_NEAR(r.static_map[1], 1.0, 0.02);
    EXPECT_GT(r.explained_pct, 99.0);
  }
}

TEST(MotorResponseTest, RejectsMismatchedOrBadInput) {
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(1000, 0.0, 4.995);
  const Eigen::MatrixXd four = Eigen::MatrixXd::Ones(1000, 4);
  EXPECT_THROW(EstimateMotorResponse(t, four, Eigen::MatrixXd::Ones(1000, 3)), Error);
  EXPECT_THROW(EstimateMotorResponse(t, four, Eigen::MatrixXd::Ones(999, 4)), Error);
  Eigen::MatrixXd bad = four;
  bad(10, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(EstimateMotorResponse(t, four, bad), Error);
  Eigen::VectorXd backwards = t;
  backwards[500] = backwards[498];
  EXPECT_THROW(EstimateMotorResponse(backwards, four, four), Error);
  EXPECT_THROW(EstimateMotorResponse(t.head(50), four.topRows(50), four.topRows(50)), Error);
}

}  // namespace
}  // namespace rotorid

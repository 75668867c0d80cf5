// LowPassFurther: a processed flight filtered again at a lower cut-off, as the diagnosis's check of
// timing effects at half the cut-off uses it. Its signals must be those of the cascade, its noise
// levels what white noise through the cascade measures.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "rotorid/core/error.h"
#include "rotorid/core/units.h"
#include "rotorid/ident/observation.h"
#include "rotorid/signal/differentiate.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// A 200 Hz log of vehicle B: gyro x a 1 Hz sine, gyro y a 7 Hz sine, gyro z white noise alone
// (0.01 rad/s, pixhawk-like); rotor speeds and accelerometer from a simulated flight.
FlightLog SyntheticLog() {
  FlightLog log = testing::SimulatePreset("B", 60.0, 1).log;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int i = 0; i < log.num_samples(); ++i) {
    const double t = log.t_s[i];
    log.gyro_radps.row(i) << 0.5 * std::sin(2.0 * kPi * 1.0 * t), 0.5 * std::sin(2.0 * kPi * 7.0 * t), noise(rng);
  }
  return log;
}

double InteriorStd(const Eigen::VectorXd& x) {
  const Eigen::VectorXd middle = x.segment(400, x.size() - 800);
  return std::sqrt((middle.array() - middle.mean()).square().mean());
}

TEST(LowPassFurtherTest, FiltersEverySignalThroughTheCascadeAndScalesTheNoise) {
  const FlightLog log = SyntheticLog();
  const Vehicle vehicle = testing::SimulatePreset("B", 1.0, 1).vehicle;
  const ProcessedFlight flight = ProcessFlight(log, vehicle, 1.0, ObservationOptions{});
  const ButterworthOptions half{4, FilterBand::kLowPass, 5.0, 0.0};
  const ProcessedFlight further = LowPassFurther(flight, half, DataSource::kImu);

  // The cascade is kept for the effects that re-filter the raw rotor signal; the rows stay.
  EXPECT_EQ(further.filter.sections.size(), 2 * flight.filter.sections.size());
  EXPECT_EQ(further.row_samples, flight.row_samples);
  EXPECT_NEAR(further.filter.Gain(7.0, 200.0),
              flight.filter.Gain(7.0, 200.0) * DesignButterworth(half, 200.0).Gain(7.0, 200.0), 1e-12);

  // 1 Hz passes both filters (4th-order Butterworth filtered forward and back: |H|^2 = 1 / (1 + (f/fc)^8)),
  // 7 Hz keeps 0.946 of its amplitude at 10 Hz and 0.063 of that at 5 Hz.
  const double amplitude_1hz = std::sqrt(2.0) * InteriorStd(further.angular_velocity.col(0));
  const double amplitude_7hz = std::sqrt(2.0) * InteriorStd(further.angular_velocity.col(1));
  EXPECT_NEAR(amplitude_1hz, 0.5, 0.005);
  EXPECT_NEAR(amplitude_7hz, 0.5 * 0.946 / (1.0 + std::pow(7.0 / 5.0, 8)), 0.003);

  // w' stays the derivative of w: filtering commutes with the central difference.
  const Eigen::MatrixXd derivative = FourthOrderCentralDifference(further.angular_velocity, further.dt_s);
  const Eigen::Index n = derivative.rows();
  EXPECT_LT((derivative - further.angular_acceleration).middleRows(400, n - 800).cwiseAbs().maxCoeff(),
            1e-3 * further.angular_acceleration.middleRows(400, n - 800).cwiseAbs().maxCoeff());

  // The noise levels: what white noise through the cascade measures (z carries noise alone).
  EXPECT_NEAR(further.noise.angular_velocity.z() / InteriorStd(further.angular_velocity.col(2)), 1.0, 0.05);
  EXPECT_NEAR(further.noise.angular_acceleration.z() / InteriorStd(further.angular_acceleration.col(2)), 1.0, 0.05);
  EXPECT_LT(further.noise.angular_acceleration.z(), 0.5 * flight.noise.angular_acceleration.z());

  // Rotor speeds through their squares: the hover level stays, the faster content goes.
  EXPECT_NEAR(further.rotor.col(0).mean(), flight.rotor.col(0).mean(), 1e-3 * flight.rotor.col(0).mean());
  EXPECT_LT(InteriorStd(FourthOrderCentralDifference(further.rotor, further.dt_s).col(0)),
            InteriorStd(FourthOrderCentralDifference(flight.rotor, flight.dt_s).col(0)));
}

TEST(LowPassFurtherTest, RejectsACutOffAboveNyquist) {
  const SimulationResult sim = testing::SimulatePreset("B", 5.0, 1);
  const ProcessedFlight flight = ProcessFlight(sim.log, sim.vehicle, 1.0, ObservationOptions{});
  EXPECT_THROW(LowPassFurther(flight, ButterworthOptions{4, FilterBand::kLowPass, 150.0, 0.0}, DataSource::kImu),
               Error);
}

}  // namespace
}  // namespace rotorid

namespace rotorid {
namespace {

// A library caller's edge trim beyond any flight (or inf) is refused by name, not counted into an int
// (the CLI's --edge-trim-s 1e7 segfaulted before its range was checked at parse time).
TEST(ObservationOptionsTest, AnEdgeTrimBeyondAnyFlightIsRefused) {
  ObservationOptions options;
  EXPECT_EQ(options.Validate(), "");
  for (double trim : {1e7, std::numeric_limits<double>::infinity(), std::nan("")}) {
    options.edge_trim_s = trim;
    EXPECT_NE(options.Validate().find("edge trim"), std::string::npos) << trim;
  }
  options.edge_trim_s = 600.0;
  EXPECT_EQ(options.Validate(), "");
}

}  // namespace
}  // namespace rotorid

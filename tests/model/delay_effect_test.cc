// The `delay` effect's interpolation of the logged rotor signal: exact at whole samples and smooth
// in the delay across them (MODEL.md 9, issue 11: with linear interpolation the criterion's slope
// jumped at sample multiples and refinements stopped there).

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "rotorid/model/effects.h"

namespace rotorid {
namespace {

constexpr double kDt = 0.005;  // 200 Hz

Eigen::VectorXd Signal() {
  Eigen::VectorXd x(400);
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const double t = kDt * static_cast<double>(k);
    x[k] = 1500.0 + 300.0 * std::sin(2 * M_PI * 3.1 * t) + 80.0 * std::cos(2 * M_PI * 11.7 * t);
  }
  return x;
}

// The delayed signal and its derivative with respect to the delay, at one sample.
std::pair<double, double> DelayedAt(double delay_s, Eigen::Index k) {
  const Eigen::VectorXd x = Signal();
  const Eigen::Matrix<RotorJet, -1, 1> in = x.cast<RotorJet>();
  Eigen::Matrix<RotorJet, -1, 1> out;
  RotorJet p(delay_s, 0);
  ParseEffectKind("delay")->TransformRotorSignal(&p, RotorSignalInput{kDt}, in, &out);
  return {out[k].a, out[k].v[0]};
}

TEST(DelayEffectTest, WholeSamplesShiftTheLogExactly) {
  const Eigen::VectorXd x = Signal();
  for (int samples : {0, 1, 5}) {
    Eigen::VectorXd out;
    const double delay = samples * kDt;
    ParseEffectKind("delay")->TransformRotorSignal(&delay, RotorSignalInput{kDt}, x, &out);
    for (Eigen::Index k = 10; k < 390; ++k) ASSERT_NEAR(out[k], x[k - samples], 1e-9) << samples << " samples";
  }
}

// Between samples the interpolation follows the continuous signal (a cubic is accurate to about
// (omega dt)^4 of the amplitude), and its derivative in the delay is continuous at sample
// multiples: the left and right slopes agree to what their distance from the knot explains.
TEST(DelayEffectTest, DerivativeInTheDelayIsContinuousAcrossSampleMultiples) {
  for (int samples : {1, 5}) {
    for (Eigen::Index k : {100, 201, 333}) {
      const double knot = samples * kDt, eps = 1e-9;
      const auto [left_value, left_slope] = DelayedAt(knot - eps, k);
      const auto [right_value, right_slope] = DelayedAt(knot + eps, k);
      EXPECT_NEAR(left_value, right_value, 1e-3);
      EXPECT_NEAR(left_slope, right_slope, 1e-4 * std::abs(right_slope) + 1e-3)
          << "slope jumps at " << samples << " samples, sample " << k;
      // The slope is the signal's time derivative, negated (Omega_log(t - delay)).
      const double t = kDt * static_cast<double>(k) - knot;
      const double truth = -(300.0 * 2 * M_PI * 3.1 * std::cos(2 * M_PI * 3.1 * t) -
                             80.0 * 2 * M_PI * 11.7 * std::sin(2 * M_PI * 11.7 * t));
      EXPECT_NEAR(right_slope, truth, 0.05 * std::abs(truth) + 200.0);
    }
  }
  // Half-way between samples the value follows the continuous signal.
  const double t = kDt * 200 - 2.5 * kDt;
  const double truth = 1500.0 + 300.0 * std::sin(2 * M_PI * 3.1 * t) + 80.0 * std::cos(2 * M_PI * 11.7 * t);
  EXPECT_NEAR(DelayedAt(2.5 * kDt, 200).first, truth, 0.5);
}

}  // namespace
}  // namespace rotorid

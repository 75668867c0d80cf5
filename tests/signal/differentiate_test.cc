#include "rotorid/signal/differentiate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>

#include "rotorid/core/error.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Largest error of CentralDifference on [sin(w t), cos(w t)] over one second, ends included.
double SinusoidDerivativeError(double frequency_hz, double dt) {
  const double omega = 2 * kPi * frequency_hz;
  const Eigen::Index n = static_cast<Eigen::Index>(std::llround(1.0 / dt)) + 1;
  Eigen::MatrixXd x(n, 2), expected(n, 2);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = k * dt;
    x.row(k) << std::sin(omega * t), std::cos(omega * t);
    expected.row(k) << omega * std::cos(omega * t), -omega * std::sin(omega * t);
  }
  return (CentralDifference(x, dt) - expected).cwiseAbs().maxCoeff();
}

TEST(CentralDifference, SinusoidErrorIsSecondOrder) {
  const double f = 2.0;
  const double coarse = SinusoidDerivativeError(f, 1e-3);
  const double fine = SinusoidDerivativeError(f, 5e-4);
  const double ratio = coarse / fine;
  std::cout << "derivative error at dt = 1 ms: " << coarse << ", at 0.5 ms: " << fine << ", ratio " << ratio << "\n";
  EXPECT_NEAR(ratio, 4.0, 0.1);
  // The one-sided end formula has the largest constant, w^3 dt^2 / 3.
  const double omega = 2 * kPi * f;
  EXPECT_LT(coarse, 1.01 * omega * omega * omega * 1e-6 / 3.0);
}

TEST(CentralDifference, ExactForQuadraticsIncludingTheEnds) {
  const double dt = 0.01;
  Eigen::MatrixXd x(7, 1);
  Eigen::VectorXd expected(7);
  for (Eigen::Index k = 0; k < 7; ++k) {
    const double t = 0.3 + k * dt;
    x(k, 0) = 3 * t * t - 2 * t + 5;
    expected[k] = 6 * t - 2;
  }
  EXPECT_LT((CentralDifference(x, dt).col(0) - expected).cwiseAbs().maxCoeff(), 1e-9);
  // Three samples are enough.
  EXPECT_LT((CentralDifference(x.topRows(3), dt).col(0) - expected.head(3)).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(CentralDifference, RejectsTooFewSamplesAndBadSteps) {
  const Eigen::MatrixXd two = Eigen::MatrixXd::Zero(2, 3);
  try {
    CentralDifference(two, 0.01);
    ADD_FAILURE() << "no exception";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("at least 3 samples (got 2)"), std::string::npos) << error.what();
  }
  const Eigen::MatrixXd five = Eigen::MatrixXd::Zero(5, 1);
  EXPECT_THROW(CentralDifference(five, 0.0), Error);
  EXPECT_THROW(CentralDifference(five, -0.01), Error);
  EXPECT_THROW(CentralDifference(five, std::nan("")), Error);
}

TEST(WhiteNoiseStd, RecoversNoiseOnASlowSinusoid) {
  std::mt19937_64 random(42);
  const double dt = 1e-3;
  double worst_relative_error = 0.0;
  for (double sigma : {1e-3, 1e-2, 1e-1}) {
    std::normal_distribution<double> noise(0.0, sigma);
    Eigen::VectorXd x(100000);
    for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = std::sin(2 * kPi * 0.5 * k * dt) + noise(random);
    const double relative_error = WhiteNoiseStd(x) / sigma - 1.0;
    worst_relative_error = std::max(worst_relative_error, std::abs(relative_error));
    EXPECT_LT(std::abs(relative_error), 0.05) << "sigma " << sigma;
  }
  std::cout << "WhiteNoiseStd worst relative error: " << worst_relative_error << "\n";
}

TEST(WhiteNoiseStd, MedianOfAbsoluteSecondDifferences) {
  // Second differences -2, 1, 3, -6: |.| sorted 1, 2, 3, 6, median 2.5.
  Eigen::VectorXd x(6);
  x << 0, 1, 0, 0, 3, 0;
  EXPECT_NEAR(WhiteNoiseStd(x), 2.5 / (0.6745 * std::sqrt(6.0)), 1e-15);
  // Odd count: 2, 1, 3 -> median 2.
  EXPECT_NEAR(WhiteNoiseStd(x.head(5)), 2.0 / (0.6745 * std::sqrt(6.0)), 1e-15);
  // A straight line has no noise.
  EXPECT_EQ(WhiteNoiseStd(Eigen::VectorXd::LinSpaced(50, -3.0, 7.0)), 0.0);
}

TEST(WhiteNoiseStd, RejectsShortOrNonFiniteInput) {
  EXPECT_THROW(WhiteNoiseStd(Eigen::VectorXd::Zero(2)), Error);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(10);
  x[4] = std::nan("");
  EXPECT_THROW(WhiteNoiseStd(x), Error);
}

}  // namespace
}  // namespace rotorid

namespace rotorid {
namespace {

// The fourth-order stencil's error on a sinusoid falls 16-fold when dt halves, and is far below
// the second-order one at identification rates.
TEST(FourthOrderCentralDifferenceTest, ConvergesAtFourthOrder) {
  auto max_error = [](double dt, bool fourth) {
    const int n = static_cast<int>(2.0 / dt);
    Eigen::MatrixXd x(n, 1);
    for (int k = 0; k < n; ++k) x(k, 0) = std::sin(2 * M_PI * 3.0 * k * dt);
    const Eigen::MatrixXd d = fourth ? FourthOrderCentralDifference(x, dt) : CentralDifference(x, dt);
    double worst = 0.0;
    for (int k = 2; k < n - 2; ++k)
      worst = std::max(worst, std::abs(d(k, 0) - 2 * M_PI * 3.0 * std::cos(2 * M_PI * 3.0 * k * dt)));
    return worst;
  };
  const double e1 = max_error(1.0 / 200, true), e2 = max_error(1.0 / 400, true);
  EXPECT_NEAR(e1 / e2, 16.0, 0.5);
  EXPECT_LT(e1, 1e-5 * 2 * M_PI * 3.0);
  EXPECT_GT(max_error(1.0 / 200, false), 100 * e1);
}

// The derivative at one sample, and the derivative of the derivative, are the whole series' rows to
// the last bit, edges included, for every length the whole-series version takes.
TEST(FourthOrderCentralDifferenceTest, AtOneSampleEqualsTheWholeSeriesBitForBit) {
  const double dt = 1.0 / 500;
  for (int n : {3, 4, 5, 6, 7, 9, 40}) {
    const Eigen::MatrixX3d x = Eigen::MatrixX3d::Random(n, 3) * 7.0;
    const Eigen::MatrixXd first = FourthOrderCentralDifference(x, dt);
    const Eigen::MatrixXd second = FourthOrderCentralDifference(first, dt);
    for (int k = 0; k < n; ++k) {
      const Eigen::RowVector3d at = FourthOrderCentralDifferenceAt(x, k, dt);
      const Eigen::RowVector3d at2 = SecondFourthOrderCentralDifferenceAt(x, k, dt);
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(at[c], first(k, c)) << "n " << n << " k " << k;
        EXPECT_EQ(at2[c], second(k, c)) << "n " << n << " k " << k;
      }
    }
  }
}

}  // namespace
}  // namespace rotorid

#include "report/spectrum.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "report/report_figures.h"
#include "rotorid/core/error.h"

namespace rotorid::internal {
namespace {

TEST(FftTest, MatchesAPlainDft) {
  std::mt19937 rng(3);
  std::normal_distribution<double> unit(0.0, 1.0);
  const int n = 64;
  std::vector<std::complex<double>> x(n);
  for (auto& v : x) v = {unit(rng), unit(rng)};
  std::vector<std::complex<double>> fast = x;
  Fft(&fast);
  for (int k = 0; k < n; ++k) {
    std::complex<double> sum = 0.0;
    for (int j = 0; j < n; ++j) sum += x[j] * std::polar(1.0, -2.0 * M_PI * j * k / n);
    EXPECT_NEAR(std::abs(fast[k] - sum), 0.0, 1e-10) << k;
  }
  std::vector<std::complex<double>> bad(12);
  EXPECT_THROW(Fft(&bad), Error);
}

TEST(FloorPowerOfTwoTest, Values) {
  EXPECT_EQ(FloorPowerOfTwo(0), 0);
  EXPECT_EQ(FloorPowerOfTwo(1), 1);
  EXPECT_EQ(FloorPowerOfTwo(511), 256);
  EXPECT_EQ(FloorPowerOfTwo(512), 512);
}

TEST(WelchTest, SineAmplitudeAndFrequency) {
  // A sine of amplitude A at a bin centre: its power A^2/2 is all in a few bins around f0.
  const double rate = 50.0, amplitude = 0.7, f0 = 50.0 / 256.0 * 20.0;
  Eigen::VectorXd x(4000);
  for (int i = 0; i < x.size(); ++i) x[i] = 3.0 + amplitude * std::sin(2.0 * M_PI * f0 * i / rate);
  const AmplitudeSpectrum s = WelchAmplitudeSpectrum({x}, rate, 256);
  ASSERT_EQ(s.frequency_hz.size(), 129);
  EXPECT_DOUBLE_EQ(s.frequency_hz[128], 25.0);
  Eigen::Index peak;
  s.asd.maxCoeff(&peak);
  EXPECT_NEAR(s.frequency_hz[peak], f0, 1e-9);
  const double df = s.frequency_hz[1];
  const double power = s.asd.array().square().sum() * df;
  EXPECT_NEAR(power, amplitude * amplitude / 2.0, 0.02 * amplitude * amplitude / 2.0);
  EXPECT_EQ(s.segments, (4000 - 256) / 128 + 1);  // half-overlapping segments
}

TEST(WelchTest, WhiteNoiseFloor) {
  // One-sided density of white noise sigma at rate fs: sigma / sqrt(fs / 2).
  std::mt19937 rng(5);
  std::normal_distribution<double> unit(0.0, 0.3);
  const double rate = 200.0;
  std::vector<Eigen::VectorXd> series(3, Eigen::VectorXd(20000));
  for (auto& x : series)
    for (int i = 0; i < x.size(); ++i) x[i] = unit(rng);
  const AmplitudeSpectrum s = WelchAmplitudeSpectrum(series, rate, 512);
  const double mean_asd = s.asd.segment(10, 200).array().square().mean();
  EXPECT_NEAR(std::sqrt(mean_asd), 0.3 / std::sqrt(rate / 2.0), 0.03 * 0.3 / std::sqrt(rate / 2.0));
  // Series shorter than a segment count for nothing.
  EXPECT_EQ(WelchAmplitudeSpectrum({Eigen::VectorXd::Ones(100)}, rate, 512).segments, 0);
  EXPECT_THROW(WelchAmplitudeSpectrum(series, rate, 500), Error);
  EXPECT_THROW(WelchAmplitudeSpectrum(series, 0.0, 512), Error);
}

TEST(DecimationTest, KeepsPeaksAndBound) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(10000);
  x[1234] = 5.0;
  x[8765] = -4.0;
  const std::vector<Eigen::Index> kept = DecimationIndices(x, 400);
  EXPECT_LE(kept.size(), 400u);
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  EXPECT_NE(std::find(kept.begin(), kept.end(), 1234), kept.end());
  EXPECT_NE(std::find(kept.begin(), kept.end(), 8765), kept.end());
  EXPECT_EQ(DecimationIndices(Eigen::VectorXd::Zero(50), 400).size(), 50u);
}

}  // namespace
}  // namespace rotorid::internal

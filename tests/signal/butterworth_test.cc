#include "rotorid/signal/butterworth.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "rotorid/core/error.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;
const double kHalfPower = 1.0 / std::sqrt(2.0);

double Db(double gain) { return 20.0 * std::log10(gain); }

SosFilter Design(int order, FilterBand band, double cutoff_hz, double sample_rate_hz, double high_cutoff_hz = 0.0) {
  ButterworthOptions options;
  options.order = order;
  options.band = band;
  options.cutoff_hz = cutoff_hz;
  options.high_cutoff_hz = high_cutoff_hz;
  return DesignButterworth(options, sample_rate_hz);
}

std::vector<double> Multiply(const std::vector<double>& p, const std::vector<double>& q) {
  std::vector<double> product(p.size() + q.size() - 1, 0.0);
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = 0; j < q.size(); ++j) product[i + j] += p[i] * q[j];
  return product;
}

// The transfer function b(z^-1) / a(z^-1) of the whole cascade, trailing zero taps of first-order
// sections dropped so that an order-N filter gives N + 1 coefficients as scipy's output='ba'.
struct TransferFunction {
  std::vector<double> b{1.0}, a{1.0};
};
TransferFunction Expand(const SosFilter& filter) {
  TransferFunction tf;
  for (const Biquad& s : filter.sections) {
    const bool first_order = s.b2 == 0.0 && s.a2 == 0.0;
    tf.b = Multiply(tf.b, first_order ? std::vector<double>{s.b0, s.b1} : std::vector<double>{s.b0, s.b1, s.b2});
    tf.a = Multiply(tf.a, first_order ? std::vector<double>{1.0, s.a1} : std::vector<double>{1.0, s.a1, s.a2});
  }
  return tf;
}

void ExpectCoefficients(const std::vector<double>& actual, const std::vector<double>& expected, double tolerance) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(actual[i], expected[i], tolerance) << "coefficient " << i;
}

// scipy.signal.butter(4, 0.2) and butter(4, 0.2, 'high') as printed by scipy (8 decimals).
TEST(ButterworthDesign, MatchesScipyFourthOrderReference) {
  const std::vector<double> a = {1.0, -2.36951301, 2.31398841, -1.05466541, 0.18737949};
  const TransferFunction low = Expand(Design(4, FilterBand::kLowPass, 0.2 * 50.0, 100.0));
  ExpectCoefficients(low.b, {0.00482434, 0.01929737, 0.02894606, 0.01929737, 0.00482434}, 6e-9);
  ExpectCoefficients(low.a, a, 6e-9);
  const TransferFunction high = Expand(Design(4, FilterBand::kHighPass, 0.2 * 50.0, 100.0));
  ExpectCoefficients(high.b, {0.43284664, -1.73138658, 2.59707987, -1.73138658, 0.43284664}, 6e-9);
  ExpectCoefficients(high.a, a, 6e-9);
}

// Closed forms from substituting s = (1 - z^-1) / (1 + z^-1) into the analog prototypes, K = tan(pi Wn / 2).
TEST(ButterworthDesign, MatchesClosedFormLowOrders) {
  for (double wn : {0.05, 0.2, 0.5, 0.8}) {
    const double k = std::tan(kPi * wn / 2.0);
    SCOPED_TRACE(wn);
    // Order 1: one section with b2 = a2 = 0.
    const SosFilter first = Design(1, FilterBand::kLowPass, wn * 50.0, 100.0);
    ASSERT_EQ(first.sections.size(), 1u);
    const Biquad& s1 = first.sections[0];
    EXPECT_NEAR(s1.b0, k / (1 + k), 1e-15);
    EXPECT_NEAR(s1.b1, k / (1 + k), 1e-15);
    EXPECT_EQ(s1.b2, 0.0);
    EXPECT_NEAR(s1.a1, (k - 1) / (k + 1), 1e-15);
    EXPECT_EQ(s1.a2, 0.0);
    const SosFilter first_high = Design(1, FilterBand::kHighPass, wn * 50.0, 100.0);
    EXPECT_NEAR(first_high.sections[0].b0, 1 / (1 + k), 1e-15);
    EXPECT_NEAR(first_high.sections[0].b1, -1 / (1 + k), 1e-15);
    EXPECT_NEAR(first_high.sections[0].a1, (k - 1) / (k + 1), 1e-15);
    // Order 2: s^2 + sqrt(2) s + 1.
    const double d = 1 + std::sqrt(2.0) * k + k * k;
    const SosFilter second = Design(2, FilterBand::kLowPass, wn * 50.0, 100.0);
    ASSERT_EQ(second.sections.size(), 1u);
    const Biquad& s2 = second.sections[0];
    EXPECT_NEAR(s2.b0, k * k / d, 1e-15);
    EXPECT_NEAR(s2.b1, 2 * k * k / d, 1e-15);
    EXPECT_NEAR(s2.b2, k * k / d, 1e-15);
    EXPECT_NEAR(s2.a1, 2 * (k * k - 1) / d, 1e-15);
    EXPECT_NEAR(s2.a2, (1 - std::sqrt(2.0) * k + k * k) / d, 1e-15);
  }
  // butter(2, 0.5) = [1, 2, 1] / (2 + sqrt 2), [1, 0, (2 - sqrt 2) / (2 + sqrt 2)].
  const Biquad half = Design(2, FilterBand::kLowPass, 25.0, 100.0).sections[0];
  EXPECT_NEAR(half.b0, 0.29289321881345254, 1e-15);
  EXPECT_NEAR(half.a1, 0.0, 1e-15);
  EXPECT_NEAR(half.a2, 0.17157287525380990, 1e-15);
}

// Band-pass of order 1: H(s) = bw s / (s^2 + bw s + w0^2) with w0^2 = K1 K2, bw = K2 - K1.
TEST(ButterworthDesign, MatchesClosedFormFirstOrderBandPass) {
  const double fs = 200.0, f1 = 7.0, f2 = 31.0;
  const double k1 = std::tan(kPi * f1 / fs), k2 = std::tan(kPi * f2 / fs);
  const double w0_squared = k1 * k2, bw = k2 - k1, d = 1 + bw + w0_squared;
  const SosFilter filter = Design(1, FilterBand::kBandPass, f1, fs, f2);
  ASSERT_EQ(filter.sections.size(), 1u);
  const Biquad& s = filter.sections[0];
  EXPECT_NEAR(s.b0, bw / d, 1e-15);
  EXPECT_NEAR(s.b1, 0.0, 1e-15);
  EXPECT_NEAR(s.b2, -bw / d, 1e-15);
  EXPECT_NEAR(s.a1, 2 * (w0_squared - 1) / d, 1e-15);
  EXPECT_NEAR(s.a2, (1 - bw + w0_squared) / d, 1e-15);
}

TEST(ButterworthDesign, SectionLayoutAndStability) {
  for (FilterBand band : {FilterBand::kLowPass, FilterBand::kHighPass, FilterBand::kBandPass}) {
    for (int order = 1; order <= 12; ++order) {
      SCOPED_TRACE(testing::Message() << "band " << static_cast<int>(band) << " order " << order);
      const SosFilter filter = Design(order, band, 3.0, 100.0, 17.0);
      const std::size_t expected_sections = band == FilterBand::kBandPass ? order : (order + 1) / 2;
      ASSERT_EQ(filter.sections.size(), expected_sections);
      int first_order_sections = 0;
      for (const Biquad& s : filter.sections) {
        first_order_sections += s.b2 == 0.0 && s.a2 == 0.0;
        // Both poles inside the unit circle (stability triangle of 1 + a1 z^-1 + a2 z^-2).
        EXPECT_LT(std::abs(s.a2), 1.0);
        EXPECT_LT(std::abs(s.a1), 1.0 + s.a2);
      }
      EXPECT_EQ(first_order_sections, band != FilterBand::kBandPass && order % 2 == 1 ? 1 : 0);
    }
  }
}

TEST(ButterworthDesign, GainAtCutoffIsHalfPower) {
  double worst_error = 0.0;
  int designs = 0;
  for (double fs : {50.0, 100.0, 400.0, 1000.0}) {
    for (double cutoff_fraction : {0.004, 0.02, 0.1, 0.25, 0.45}) {
      const double fc = cutoff_fraction * fs;
      for (int order = 1; order <= 12; ++order) {
        for (FilterBand band : {FilterBand::kLowPass, FilterBand::kHighPass}) {
          const SosFilter filter = Design(order, band, fc, fs);
          const double error = std::abs(filter.Gain(fc, fs) - kHalfPower);
          EXPECT_LT(error, 1e-9) << "order " << order << " fc " << fc << " fs " << fs;
          worst_error = std::max(worst_error, error);
          ++designs;
        }
      }
    }
  }
  std::cout << "worst |gain(fc) - 1/sqrt 2| over " << designs << " low/high-pass designs: " << worst_error << "\n";
}

TEST(ButterworthDesign, UnitGainInThePassBand) {
  for (int order = 1; order <= 12; ++order) {
    SCOPED_TRACE(order);
    EXPECT_NEAR(Design(order, FilterBand::kLowPass, 7.0, 100.0).Gain(0.0, 100.0), 1.0, 1e-12);
    EXPECT_NEAR(Design(order, FilterBand::kHighPass, 7.0, 100.0).Gain(50.0, 100.0), 1.0, 1e-12);
    EXPECT_NEAR(Design(order, FilterBand::kHighPass, 7.0, 100.0).Gain(0.0, 100.0), 0.0, 1e-12);
    EXPECT_NEAR(Design(order, FilterBand::kLowPass, 7.0, 100.0).Gain(50.0, 100.0), 0.0, 1e-12);
  }
}

TEST(ButterworthDesign, BandPassEdgesAndCentre) {
  struct Band {
    double low, high, fs;
  };
  double worst_edge_error = 0.0, worst_centre_deviation = 0.0;
  for (const Band& b :
       {Band{2.0, 20.0, 200.0}, Band{5.0, 8.0, 100.0}, Band{30.0, 120.0, 500.0}, Band{0.5, 45.0, 100.0}}) {
    for (int order = 1; order <= 8; ++order) {
      SCOPED_TRACE(testing::Message() << b.low << "-" << b.high << " Hz at " << b.fs << " Hz, order " << order);
      const SosFilter filter = Design(order, FilterBand::kBandPass, b.low, b.fs, b.high);
      const double low_error = std::abs(filter.Gain(b.low, b.fs) - kHalfPower);
      const double high_error = std::abs(filter.Gain(b.high, b.fs) - kHalfPower);
      EXPECT_LT(low_error, 1e-9);
      EXPECT_LT(high_error, 1e-9);
      worst_edge_error = std::max({worst_edge_error, low_error, high_error});
      // Exactly 1 at the digital image of the analog centre sqrt(w1 w2) of the pre-warped edges ...
      const double warped_centre_hz =
          b.fs / kPi * std::atan(std::sqrt(std::tan(kPi * b.low / b.fs) * std::tan(kPi * b.high / b.fs)));
      EXPECT_NEAR(filter.Gain(warped_centre_hz, b.fs), 1.0, 1e-12);
      // ... and ~1 at the plain geometric centre (maximally flat pass band).
      const double deviation = std::abs(filter.Gain(std::sqrt(b.low * b.high), b.fs) - 1.0);
      EXPECT_LT(deviation, 1e-2);
      worst_centre_deviation = std::max(worst_centre_deviation, deviation);
      EXPECT_NEAR(filter.Gain(0.0, b.fs), 0.0, 1e-12);
      EXPECT_NEAR(filter.Gain(0.5 * b.fs, b.fs), 0.0, 1e-12);
    }
  }
  std::cout << "band-pass: worst edge gain error " << worst_edge_error << ", worst |gain - 1| at sqrt(f1 f2) "
            << worst_centre_deviation << "\n";
}

// Far from the cut-off a Butterworth filter of order N falls by 20 N dB per decade, monotonically.
TEST(ButterworthDesign, StopBandRollOff) {
  const double fs = 1000.0;
  double worst_slope_error_db = 0.0;
  for (int order = 1; order <= 8; ++order) {
    SCOPED_TRACE(order);
    const SosFilter low = Design(order, FilterBand::kLowPass, 0.5, fs);
    const double low_decade_db = Db(low.Gain(50.0, fs)) - Db(low.Gain(5.0, fs));
    EXPECT_NEAR(low_decade_db, -20.0 * order, 1.0);
    EXPECT_NEAR(Db(low.Gain(5.0, fs)), -20.0 * order, 1.0);  // One decade above the cut-off.
    const SosFilter high = Design(order, FilterBand::kHighPass, 20.0, fs);
    const double high_decade_db = Db(high.Gain(2.0, fs)) - Db(high.Gain(0.2, fs));
    EXPECT_NEAR(high_decade_db, 20.0 * order, 1.0);
    EXPECT_NEAR(Db(high.Gain(2.0, fs)), -20.0 * order, 1.0);
    worst_slope_error_db = std::max(
        {worst_slope_error_db, std::abs(low_decade_db + 20.0 * order), std::abs(high_decade_db - 20.0 * order)});

    double previous_low = low.Gain(0.0, fs), previous_high = high.Gain(0.5 * fs, fs);
    for (double f = 0.01; f < 0.5 * fs; f *= 1.05) {
      const double gain_low = low.Gain(f, fs), gain_high = high.Gain(0.5 * fs - f, fs);
      // Strictly falling in the stop band; in the flat pass band the gain is 1 up to evaluation rounding.
      EXPECT_LE(gain_low, previous_low + 1e-10) << f << " Hz";
      EXPECT_LE(gain_high, previous_high + 1e-10) << 0.5 * fs - f << " Hz";
      if (gain_low < kHalfPower) {
        EXPECT_LT(gain_low, previous_low) << f << " Hz";
      }
      if (gain_high < kHalfPower) {
        EXPECT_LT(gain_high, previous_high) << 0.5 * fs - f << " Hz";
      }
      previous_low = gain_low;
      previous_high = gain_high;
    }
  }
  std::cout << "worst deviation from 20 N dB/decade: " << worst_slope_error_db << " dB\n";
}

// The cascade in direct form II transposed must satisfy the difference equation of the expanded
// transfer function, sum a_j y[k-j] = sum b_j x[k-j], at every sample (residual evaluated on its own output).
TEST(SosFilterCausal, MatchesDifferenceEquation) {
  for (int order : {3, 6}) {
    const SosFilter filter = Design(order, FilterBand::kLowPass, 11.0, 100.0);
    const TransferFunction tf = Expand(filter);
    Eigen::VectorXd x(300);
    for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = std::sin(0.37 * k) + (k == 40 ? 5.0 : 0.0) + (k > 150);
    const Eigen::VectorXd y = SosFilterCausal(filter, x);
    double worst = 0.0;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      double reference = 0.0;
      for (std::size_t j = 0; j < tf.b.size() && static_cast<Eigen::Index>(j) <= k; ++j)
        reference += tf.b[j] * x[k - j];
      for (std::size_t j = 1; j < tf.a.size() && static_cast<Eigen::Index>(j) <= k; ++j)
        reference -= tf.a[j] * y[k - j];
      worst = std::max(worst, std::abs(y[k] - reference));
    }
    EXPECT_LT(worst, 1e-12) << "order " << order;
  }
}

TEST(SosFilterCausal, StepSettlesAtDcGainWithZeroInitialState) {
  const SosFilter filter = Design(5, FilterBand::kLowPass, 10.0, 100.0);
  const Eigen::VectorXd y = SosFilterCausal(filter, Eigen::VectorXd::Ones(400));
  EXPECT_NEAR(y[0], filter.sections[0].b0 * filter.sections[1].b0 * filter.sections[2].b0, 1e-15);
  EXPECT_LT(y[0], 1e-2);            // Starts from rest ...
  EXPECT_NEAR(y[399], 1.0, 1e-12);  // ... and settles at the DC gain.
  EXPECT_EQ(SosFilterCausal(filter, Eigen::VectorXd()).size(), 0);
}

TEST(ButterworthOptions, ValidateNamesTheViolatedConstraint) {
  ButterworthOptions options;
  EXPECT_EQ(options.Validate(100.0), "");

  struct Case {
    int order;
    FilterBand band;
    double cutoff, high, fs;
    const char* expected;
  };
  const Case cases[] = {
      {0, FilterBand::kLowPass, 10.0, 0.0, 100.0, "order must satisfy 1 <= order"},
      {-3, FilterBand::kHighPass, 10.0, 0.0, 100.0, "order must satisfy 1 <= order"},
      {4, FilterBand::kLowPass, 0.0, 0.0, 100.0, "cutoff_hz must satisfy 0 < cutoff_hz < Nyquist = 50 Hz"},
      {4, FilterBand::kLowPass, -1.0, 0.0, 100.0, "0 < cutoff_hz"},
      {4, FilterBand::kLowPass, 50.0, 0.0, 100.0, "cutoff_hz < Nyquist = 50 Hz (got 50 Hz)"},
      {4, FilterBand::kHighPass, std::nan(""), 0.0, 100.0, "cutoff_hz < Nyquist"},
      {4, FilterBand::kBandPass, 10.0, 10.0, 100.0, "band-pass needs cutoff_hz < high_cutoff_hz < Nyquist"},
      {4, FilterBand::kBandPass, 10.0, 5.0, 100.0, "high_cutoff_hz = 5 Hz"},
      {4, FilterBand::kBandPass, 10.0, 60.0, 100.0, "band-pass needs cutoff_hz < high_cutoff_hz < Nyquist = 50 Hz"},
      {4, FilterBand::kLowPass, 10.0, 0.0, 0.0, "sample rate must be positive"},
  };
  for (const Case& c : cases) {
    options.order = c.order;
    options.band = c.band;
    options.cutoff_hz = c.cutoff;
    options.high_cutoff_hz = c.high;
    const std::string message = options.Validate(c.fs);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "message: " << message;
    try {
      DesignButterworth(options, c.fs);
      ADD_FAILURE() << "no exception for: " << c.expected;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(message), std::string::npos) << error.what();
    }
  }
}

}  // namespace
}  // namespace rotorid

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "rotorid/signal/butterworth.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;

SosFilter Design(int order, FilterBand band, double cutoff_hz, double sample_rate_hz, double high_cutoff_hz = 0.0) {
  ButterworthOptions options;
  options.order = order;
  options.band = band;
  options.cutoff_hz = cutoff_hz;
  options.high_cutoff_hz = high_cutoff_hz;
  return DesignButterworth(options, sample_rate_hz);
}

Eigen::VectorXd Reversed(const Eigen::VectorXd& x) { return x.reverse(); }

// scipy.signal.sosfiltfilt rebuilt from independent pieces: explicit odd extension, and steady-state
// initial conditions obtained by filtering a long constant prefix from rest instead of sosfilt_zi.
Eigen::VectorXd ReferenceFiltFilt(const SosFilter& filter, const Eigen::VectorXd& x, Eigen::Index pad) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd extended(n + 2 * pad);
  for (Eigen::Index i = 0; i < pad; ++i) {
    extended[i] = 2 * x[0] - x[pad - i];
    extended[pad + n + i] = 2 * x[n - 1] - x[n - 2 - i];
  }
  extended.segment(pad, n) = x;
  const Eigen::Index prefix = 20000;
  auto causal_from_steady_state = [&](const Eigen::VectorXd& signal) {
    Eigen::VectorXd primed(prefix + signal.size());
    primed.head(prefix).setConstant(signal[0]);
    primed.tail(signal.size()) = signal;
    return Eigen::VectorXd(SosFilterCausal(filter, primed).tail(signal.size()));
  };
  const Eigen::VectorXd forward = causal_from_steady_state(extended);
  const Eigen::VectorXd backward = Reversed(causal_from_steady_state(Reversed(forward)));
  return backward.segment(pad, n);
}

// scipy's default: 3 * (2 * sections + 1 - min(#b2 == 0, #a2 == 0)).
Eigen::Index ScipyPadLength(const SosFilter& filter) {
  long zero_b2 = 0, zero_a2 = 0;
  for (const Biquad& s : filter.sections) {
    zero_b2 += s.b2 == 0.0;
    zero_a2 += s.a2 == 0.0;
  }
  return 3 * (2 * static_cast<long>(filter.sections.size()) + 1 - std::min(zero_b2, zero_a2));
}

Eigen::VectorXd TestSignal(Eigen::Index n) {
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) x[k] = 1.5 + 0.01 * k + std::sin(0.05 * k) + 0.3 * std::cos(0.9 * k + 0.2);
  return x;
}

TEST(FiltFilt, MatchesScipySemanticsRebuiltIndependently) {
  struct Case {
    int order;
    FilterBand band;
    double low, high;
    Eigen::Index n;
  };
  // Orders 3 and 5 contain a first-order section (shorter pad); n = 8 clamps the pad to n - 1.
  const Case cases[] = {{4, FilterBand::kLowPass, 10.0, 0.0, 500}, {3, FilterBand::kLowPass, 10.0, 0.0, 500},
                        {5, FilterBand::kHighPass, 5.0, 0.0, 300}, {2, FilterBand::kBandPass, 4.0, 15.0, 400},
                        {4, FilterBand::kLowPass, 10.0, 0.0, 8},   {3, FilterBand::kLowPass, 20.0, 0.0, 2}};
  for (const Case& c : cases) {
    SCOPED_TRACE(testing::Message() << "order " << c.order << " band " << static_cast<int>(c.band) << " n " << c.n);
    const SosFilter filter = Design(c.order, c.band, c.low, 100.0, c.high);
    const Eigen::VectorXd x = TestSignal(c.n);
    const Eigen::Index pad = std::min(ScipyPadLength(filter), c.n - 1);
    const Eigen::VectorXd y = FiltFilt(filter, x);
    const double error = (y - ReferenceFiltFilt(filter, x, pad)).cwiseAbs().maxCoeff();
    EXPECT_LT(error, 1e-10);
    // The comparison can tell pad lengths apart, so it does check the padding.
    if (pad >= 2 && c.n > pad + 1) {
      EXPECT_GT((y - ReferenceFiltFilt(filter, x, pad - 1)).cwiseAbs().maxCoeff(), 1e-6);
      EXPECT_GT((y - ReferenceFiltFilt(filter, x, pad + 1)).cwiseAbs().maxCoeff(), 1e-6);
    }
  }
  EXPECT_EQ(ScipyPadLength(Design(4, FilterBand::kLowPass, 10, 100)), 15);
  EXPECT_EQ(ScipyPadLength(Design(3, FilterBand::kLowPass, 10, 100)), 12);
}

// Projection onto sin/cos over an integer number of periods: amplitude and phase of a sinusoid.
struct Sinusoid {
  double amplitude, phase;
};
Sinusoid FitSinusoid(const Eigen::VectorXd& y, Eigen::Index begin, Eigen::Index count, double omega_per_sample) {
  double s = 0, c = 0;
  for (Eigen::Index k = begin; k < begin + count; ++k) {
    s += y[k] * std::sin(omega_per_sample * k);
    c += y[k] * std::cos(omega_per_sample * k);
  }
  // y = A sin(w k + phi) = A cos(phi) sin(w k) + A sin(phi) cos(w k).
  return {2.0 / count * std::hypot(s, c), std::atan2(c, s)};
}

TEST(FiltFilt, PassBandSinusoidHasZeroPhaseAndSquaredGain) {
  const double fs = 500.0;
  struct Case {
    int order;
    FilterBand band;
    double low, high, signal_hz;
  };
  const Case cases[] = {{4, FilterBand::kLowPass, 20.0, 0.0, 8.0},
                        {6, FilterBand::kLowPass, 20.0, 0.0, 18.0},
                        {3, FilterBand::kHighPass, 5.0, 0.0, 8.0},
                        {2, FilterBand::kBandPass, 5.0, 40.0, 12.5}};
  double worst_phase = 0.0, worst_amplitude = 0.0;
  for (const Case& c : cases) {
    SCOPED_TRACE(testing::Message() << "order " << c.order << " band " << static_cast<int>(c.band));
    const SosFilter filter = Design(c.order, c.band, c.low, fs, c.high);
    const double omega = 2 * kPi * c.signal_hz / fs, phase = 0.3;
    Eigen::VectorXd x(5000);
    for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = 2.0 * std::sin(omega * k + phase);
    const Eigen::VectorXd y = FiltFilt(filter, x);
    // Away from the edges; 1000 samples are a whole number of periods for every signal frequency above.
    const Sinusoid fit = FitSinusoid(y, 2000, 1000, omega);
    const double gain = filter.Gain(c.signal_hz, fs);
    worst_phase = std::max(worst_phase, std::abs(fit.phase - phase));
    worst_amplitude = std::max(worst_amplitude, std::abs(fit.amplitude / (2.0 * gain * gain) - 1.0));
    EXPECT_LT(std::abs(fit.phase - phase), 1e-3);
    EXPECT_NEAR(fit.amplitude, 2.0 * gain * gain, 1e-6);
    // Sample by sample too: y = |H|^2 x, so no shift anywhere in the middle.
    const double error = (y.segment(1000, 3000) - gain * gain * x.segment(1000, 3000)).cwiseAbs().maxCoeff();
    EXPECT_LT(error, 1e-6);
  }
  std::cout << "filtfilt sinusoid: worst phase error " << worst_phase << " rad, worst relative amplitude error "
            << worst_amplitude << "\n";
}

TEST(FiltFilt, ConstantAndRampPassWithTinyEdgeError) {
  const SosFilter low = Design(4, FilterBand::kLowPass, 5.0, 100.0);
  const Eigen::VectorXd constant = Eigen::VectorXd::Constant(1000, 3.7);
  EXPECT_LT((FiltFilt(low, constant).array() - 3.7).abs().maxCoeff(), 1e-12);
  EXPECT_LT(FiltFilt(Design(4, FilterBand::kHighPass, 5.0, 100.0), constant).cwiseAbs().maxCoeff(), 1e-12);

  // Odd extension continues a ramp exactly; only the constant-history initial state is slightly off.
  const Eigen::VectorXd ramp = Eigen::VectorXd::LinSpaced(1000, -1.0, 1.0);  // Slope 0.002 per sample.
  const Eigen::VectorXd y = FiltFilt(low, ramp);
  const double edge_error = (y - ramp).cwiseAbs().maxCoeff();
  const double slope = 2.0 / 999;
  const double interior_error = (y - ramp).segment(200, 600).cwiseAbs().maxCoeff();
  std::cout << "ramp through filtfilt: max error " << edge_error << " (at the edges), interior " << interior_error
            << ", slope " << slope << " per sample\n";
  EXPECT_LT(edge_error, 0.6 * slope);  // Within about half a sample of the ramp.
  EXPECT_LT(interior_error, 1e-10);
  // A causal pass lags the ramp by its group delay (about 8 samples here); the zero-phase edges do far better.
  const Eigen::VectorXd causal = SosFilterCausal(low, ramp);
  EXPECT_GT((causal - ramp).tail(500).cwiseAbs().maxCoeff(), 10 * edge_error);
}

TEST(FiltFilt, StepResponseIsSymmetricInTime) {
  const SosFilter filter = Design(5, FilterBand::kLowPass, 3.0, 100.0);
  const Eigen::Index center = 2000;
  Eigen::VectorXd x(2 * center + 1);
  for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = k < center ? -1.0 : (k > center ? 1.0 : 0.0);
  const Eigen::VectorXd y = FiltFilt(filter, x);
  double asymmetry = 0.0;
  for (Eigen::Index k = 0; k <= center; ++k) asymmetry = std::max(asymmetry, std::abs(y[center + k] + y[center - k]));
  std::cout << "step asymmetry " << asymmetry << "\n";
  EXPECT_LT(asymmetry, 1e-10);
  EXPECT_NEAR(y[center], 0.0, 1e-10);
  EXPECT_GT(y[center + 5], 0.1);  // It did smooth the step.
  EXPECT_LT(y[center + 5], 0.99);
  // A causal filter is not symmetric: the check above would catch a missing backward pass.
  const Eigen::VectorXd causal = SosFilterCausal(filter, x);
  EXPECT_GT(std::abs(causal[center + 20] + causal[center - 20]), 0.1);
}

TEST(FiltFilt, ShortInputs) {
  const SosFilter filter = Design(4, FilterBand::kLowPass, 10.0, 100.0);
  EXPECT_EQ(FiltFilt(filter, Eigen::VectorXd()).size(), 0);
  const Eigen::VectorXd one = Eigen::VectorXd::Constant(1, 4.2);
  EXPECT_EQ(FiltFilt(filter, one)[0], 4.2);
  for (Eigen::Index n = 2; n <= 40; ++n) {
    const Eigen::VectorXd constant = Eigen::VectorXd::Constant(n, -2.5);
    EXPECT_LT((FiltFilt(filter, constant).array() + 2.5).abs().maxCoeff(), 1e-12) << n;
    const Eigen::VectorXd ramp = Eigen::VectorXd::LinSpaced(n, 0.0, 1.0);
    EXPECT_TRUE(FiltFilt(filter, ramp).allFinite()) << n;
  }
}

TEST(FiltFilt, ColumnsAreFilteredIndependently) {
  const SosFilter filter = Design(3, FilterBand::kLowPass, 10.0, 100.0);
  Eigen::MatrixXd x(300, 3);
  x.col(0) = TestSignal(300);
  x.col(1) = TestSignal(300).reverse();
  x.col(2).setConstant(1.0);
  const Eigen::MatrixXd y = FiltFiltColumns(filter, x);
  ASSERT_EQ(y.rows(), 300);
  ASSERT_EQ(y.cols(), 3);
  for (Eigen::Index c = 0; c < 3; ++c) EXPECT_EQ(y.col(c), FiltFilt(filter, x.col(c))) << c;
  // A block view (outer stride larger than its row count) must give the same as a contiguous copy.
  Eigen::MatrixXd big(600, 4);
  big.setRandom();
  const Eigen::MatrixXd block = big.block(10, 1, 200, 2);
  EXPECT_EQ(FiltFiltColumns(filter, big.block(10, 1, 200, 2)), FiltFiltColumns(filter, block));
  EXPECT_EQ(FiltFiltColumns(filter, Eigen::MatrixXd(0, 3)).cols(), 3);
  // Columns run four (then two) side by side: each must still come out as if filtered alone, from
  // a block view as well, and for every length down to the shortest.
  Eigen::MatrixXd wide(400, 9);
  wide.setRandom();
  for (const Eigen::Index rows : {Eigen::Index{1}, Eigen::Index{2}, Eigen::Index{5}, Eigen::Index{300}}) {
    const Eigen::MatrixXd y_wide = FiltFiltColumns(filter, wide.block(7, 1, rows, 7));
    for (Eigen::Index c = 0; c < 7; ++c)
      EXPECT_EQ(y_wide.col(c), FiltFilt(filter, wide.block(7, 1 + c, rows, 1))) << rows << " rows, column " << c;
  }
}

}  // namespace
}  // namespace rotorid

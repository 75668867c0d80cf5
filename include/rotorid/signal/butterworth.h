#pragma once

// Butterworth filter design and zero-phase filtering (MODEL.md section 3).

#include <string>
#include <vector>

#include <Eigen/Core>

namespace rotorid {

enum class FilterBand { kLowPass, kHighPass, kBandPass };

struct ButterworthOptions {
  // Filter order (number of poles of the low/high-pass prototype; a band-pass has twice as many).
  int order = 4;
  FilterBand band = FilterBand::kLowPass;
  // Cut-off (-3 dB) frequency for low/high-pass; the lower edge of a band-pass (Hz).
  double cutoff_hz = 10.0;
  // Upper edge of a band-pass (Hz); unused otherwise.
  double high_cutoff_hz = 0.0;

  // Empty when the options are valid at this sample rate, else a message naming the violated constraint.
  std::string Validate(double sample_rate_hz) const;
};

// One second-order section: y = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2) x.
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};

// A digital IIR filter as cascaded second-order sections (numerically safe at any order).
struct SosFilter {
  std::vector<Biquad> sections;
  // Complex frequency response magnitude at f (Hz) for the given sample rate.
  double Gain(double frequency_hz, double sample_rate_hz) const;
};

// Digital Butterworth design by the bilinear transform with pre-warping (as scipy.signal.butter
// with output='sos'). Throws rotorid::Error when the options are invalid.
SosFilter DesignButterworth(const ButterworthOptions& options, double sample_rate_hz);

// Causal filtering with zero initial state (scipy.signal.sosfilt).
Eigen::VectorXd SosFilterCausal(const SosFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& x);

// Zero-phase forward-backward filtering with odd extension of the edges and steady-state initial
// conditions, as scipy.signal.sosfiltfilt(padtype='odd') with its default pad length
// 3 * (2 * sections + 1) (one tap less when there is a first-order section, as scipy counts it).
// Signals shorter than the pad are padded as far as they allow; sizes 0 and 1 come back unchanged.
Eigen::VectorXd FiltFilt(const SosFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& x);
// FiltFilt on every column.
Eigen::MatrixXd FiltFiltColumns(const SosFilter& filter, const Eigen::Ref<const Eigen::MatrixXd>& x);

}  // namespace rotorid

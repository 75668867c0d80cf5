#pragma once

// Residual spectra for the report: a radix-2 FFT and Welch's averaged periodogram.

#include <Eigen/Core>
#include <complex>
#include <vector>

namespace rotorid::internal {

// In-place radix-2 FFT (forward, no scaling). The size must be a power of two.
void Fft(std::vector<std::complex<double>>* data);

// Largest power of two <= n (0 for n < 1).
int FloorPowerOfTwo(int n);

struct AmplitudeSpectrum {
  Eigen::VectorXd frequency_hz;  // 0 .. fs/2, segment / 2 + 1 bins
  Eigen::VectorXd asd;           // amplitude spectral density, units / sqrt(Hz)
  int segments = 0;              // periodograms averaged
};

// Welch's method: Hann-windowed segments of `segment` samples (a power of two), overlapping by
// half, each with its mean removed; the one-sided power spectral densities of every segment of
// every series are averaged and the square root taken. Series shorter than a segment are skipped.
// Cost O(n log segment). Sine amplitude A at a bin centre integrates to A^2 / 2 over frequency.
AmplitudeSpectrum WelchAmplitudeSpectrum(const std::vector<Eigen::VectorXd>& series, double sample_rate_hz,
                                         int segment);

}  // namespace rotorid::internal

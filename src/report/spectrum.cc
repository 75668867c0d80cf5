#include "report/spectrum.h"

#include <cmath>
#include <utility>

#include "rotorid/core/error.h"

namespace rotorid::internal {

void Fft(std::vector<std::complex<double>>* data) {
  std::vector<std::complex<double>>& a = *data;
  const size_t n = a.size();
  if (n == 0 || (n & (n - 1)) != 0) throw Error("FFT size must be a power of two, got " + std::to_string(n));
  // Bit-reversal permutation, then iterative butterflies.
  for (size_t i = 1, j = 0; i < n; ++i) {
    size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (size_t length = 2; length <= n; length <<= 1) {
    const double angle = -2.0 * M_PI / static_cast<double>(length);
    const std::complex<double> step(std::cos(angle), std::sin(angle));
    for (size_t start = 0; start < n; start += length) {
      std::complex<double> twiddle(1.0, 0.0);
      for (size_t k = 0; k < length / 2; ++k) {
        const std::complex<double> even = a[start + k];
        const std::complex<double> odd = a[start + k + length / 2] * twiddle;
        a[start + k] = even + odd;
        a[start + k + length / 2] = even - odd;
        twiddle *= step;
      }
    }
  }
}

int FloorPowerOfTwo(int n) {
  if (n < 1) return 0;
  int p = 1;
  while (p <= n / 2) p *= 2;
  return p;
}

AmplitudeSpectrum WelchAmplitudeSpectrum(const std::vector<Eigen::VectorXd>& series, double sample_rate_hz,
                                         int segment) {
  if (segment < 2 || (segment & (segment - 1)) != 0)
    throw Error("Welch segment must be a power of two >= 2, got " + std::to_string(segment));
  if (!(sample_rate_hz > 0.0)) throw Error("Welch sample rate must be positive");
  const int bins = segment / 2 + 1;
  Eigen::VectorXd window(segment);
  for (int k = 0; k < segment; ++k) window[k] = 0.5 * (1.0 - std::cos(2.0 * M_PI * k / segment));
  const double window_power = window.squaredNorm();
  AmplitudeSpectrum out;
  out.frequency_hz = Eigen::VectorXd::LinSpaced(bins, 0.0, sample_rate_hz / 2.0);
  Eigen::VectorXd psd_sum = Eigen::VectorXd::Zero(bins);
  std::vector<std::complex<double>> buffer(segment);
  const int hop = segment / 2;
  for (const Eigen::VectorXd& x : series) {
    for (Eigen::Index start = 0; start + segment <= x.size(); start += hop) {
      const double mean = x.segment(start, segment).mean();
      for (int k = 0; k < segment; ++k) buffer[k] = {(x[start + k] - mean) * window[k], 0.0};
      Fft(&buffer);
      for (int k = 0; k < bins; ++k) {
        // One-sided: every bin but DC and Nyquist carries the power of its negative twin too.
        const double twin = (k == 0 || k == segment / 2) ? 1.0 : 2.0;
        psd_sum[k] += twin * std::norm(buffer[k]) / (sample_rate_hz * window_power);
      }
      ++out.segments;
    }
  }
  out.asd = out.segments > 0 ? (psd_sum / out.segments).cwiseSqrt().eval() : Eigen::VectorXd::Zero(bins);
  return out;
}

}  // namespace rotorid::internal

#include "rotorid/signal/butterworth.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/core/units.h"

namespace rotorid {
namespace {

using Complex = std::complex<double>;

// Beyond this the overall gain (kept in the first section, as scipy does) underflows for low cut-offs,
// and no identification task needs it.
constexpr int kMaxOrder = 32;

// Poles of one section in the analog domain, with s normalised by 2 fs so that the bilinear
// transform is z = (1 + s) / (1 - s).
struct AnalogPoleGroup {
  enum class Kind { kConjugatePair, kRealPair, kSingleReal } kind;
  Complex first;        // For a conjugate pair, one member (the other is its conjugate).
  double second = 0.0;  // The other pole of a real pair.
};

Complex Bilinear(Complex s) { return (1.0 + s) / (1.0 - s); }

// Upper-half-plane poles -exp(j pi m / (2 n)), m = -n+1, -n+3, ... < 0, of the unit-cut-off analog
// prototype (scipy.signal.buttap); their conjugates and, for odd n, the pole -1 complete the set.
std::vector<Complex> PrototypeUpperPoles(int order) {
  std::vector<Complex> poles;
  for (int m = -order + 1; m < 0; m += 2) poles.push_back(-std::exp(Complex(0.0, kPi * m / (2.0 * order))));
  return poles;
}

// Splits the roots of s^2 - 2 c s + w0^2 (the two band-pass poles made from the real prototype pole)
// into a conjugate pair or two real poles.
AnalogPoleGroup QuadraticPoles(double center, double w0_squared) {
  const double discriminant = center * center - w0_squared;
  if (discriminant < 0.0)
    return {AnalogPoleGroup::Kind::kConjugatePair, Complex(center, std::sqrt(-discriminant)), 0.0};
  const double root = std::sqrt(discriminant);
  return {AnalogPoleGroup::Kind::kRealPair, Complex(center + root, 0.0), center - root};
}

struct SectionDraft {
  Biquad biquad;
  double distance_to_unit_circle = 0.0;
};

}  // namespace

std::string ButterworthOptions::Validate(double sample_rate_hz) const {
  std::ostringstream message;
  if (!(std::isfinite(sample_rate_hz) && sample_rate_hz > 0.0)) {
    message << "sample rate must be positive and finite (got " << sample_rate_hz << " Hz)";
    return message.str();
  }
  if (order < 1 || order > kMaxOrder) {
    message << "order must satisfy 1 <= order <= " << kMaxOrder << " (got " << order << ")";
    return message.str();
  }
  if (band != FilterBand::kLowPass && band != FilterBand::kHighPass && band != FilterBand::kBandPass) {
    message << "unknown filter band " << static_cast<int>(band);
    return message.str();
  }
  const double nyquist_hz = 0.5 * sample_rate_hz;
  if (!(cutoff_hz > 0.0 && cutoff_hz < nyquist_hz)) {
    message << "cutoff_hz must satisfy 0 < cutoff_hz < Nyquist = " << nyquist_hz << " Hz (got " << cutoff_hz << " Hz)";
    return message.str();
  }
  if (band == FilterBand::kBandPass && !(high_cutoff_hz > cutoff_hz && high_cutoff_hz < nyquist_hz)) {
    message << "band-pass needs cutoff_hz < high_cutoff_hz < Nyquist = " << nyquist_hz
            << " Hz (got cutoff_hz = " << cutoff_hz << " Hz, high_cutoff_hz = " << high_cutoff_hz << " Hz)";
    return message.str();
  }
  return "";
}

double SosFilter::Gain(double frequency_hz, double sample_rate_hz) const {
  const Complex z_inv = std::exp(Complex(0.0, -2.0 * kPi * frequency_hz / sample_rate_hz));
  const Complex z_inv2 = z_inv * z_inv;
  Complex response = 1.0;
  for (const Biquad& s : sections)
    response *= (s.b0 + s.b1 * z_inv + s.b2 * z_inv2) / (1.0 + s.a1 * z_inv + s.a2 * z_inv2);
  return std::abs(response);
}

SosFilter DesignButterworth(const ButterworthOptions& options, double sample_rate_hz) {
  const std::string problem = options.Validate(sample_rate_hz);
  if (!problem.empty()) throw Error("Butterworth filter: " + problem);

  const int order = options.order;
  // Pre-warped cut-offs in units of 2 fs: the bilinear transform then maps them onto the requested
  // digital frequencies exactly.
  const double k_low = std::tan(kPi * options.cutoff_hz / sample_rate_hz);
  const std::vector<Complex> upper = PrototypeUpperPoles(order);
  const bool has_real_prototype_pole = order % 2 == 1;

  // Analog poles grouped by section, and the analog gain k' of H(s) = k' prod(s - z) / prod(s - p).
  // Every analog zero sits at s = 0 (high/band-pass) and maps to z = 1; the surplus of poles over
  // zeros maps to zeros at z = -1. So each section's numerator is fixed by the band alone.
  std::vector<AnalogPoleGroup> groups;
  double analog_gain = 1.0;
  Biquad pair_numerator, single_numerator;
  switch (options.band) {
    case FilterBand::kLowPass:
      for (const Complex& p : upper) groups.push_back({AnalogPoleGroup::Kind::kConjugatePair, k_low * p, 0.0});
      if (has_real_prototype_pole) groups.push_back({AnalogPoleGroup::Kind::kSingleReal, Complex(-k_low, 0.0), 0.0});
      analog_gain = std::pow(k_low, order);
      pair_numerator = {1.0, 2.0, 1.0, 0.0, 0.0};
      single_numerator = {1.0, 1.0, 0.0, 0.0, 0.0};
      break;
    case FilterBand::kHighPass:
      // s -> k / s; the prototype has prod(-p) = 1, so the gain stays 1.
      for (const Complex& p : upper) groups.push_back({AnalogPoleGroup::Kind::kConjugatePair, k_low / p, 0.0});
      if (has_real_prototype_pole) groups.push_back({AnalogPoleGroup::Kind::kSingleReal, Complex(-k_low, 0.0), 0.0});
      analog_gain = 1.0;
      pair_numerator = {1.0, -2.0, 1.0, 0.0, 0.0};
      single_numerator = {1.0, -1.0, 0.0, 0.0, 0.0};
      break;
    case FilterBand::kBandPass: {
      // s -> (s^2 + w0^2) / (s bw): every prototype pole p gives the roots of s^2 - p bw s + w0^2.
      const double k_high = std::tan(kPi * options.high_cutoff_hz / sample_rate_hz);
      const double w0_squared = k_low * k_high;
      const double bandwidth = k_high - k_low;
      for (const Complex& p : upper) {
        const Complex center = 0.5 * bandwidth * p;
        const Complex root = std::sqrt(center * center - w0_squared);
        groups.push_back({AnalogPoleGroup::Kind::kConjugatePair, center + root, 0.0});
        groups.push_back({AnalogPoleGroup::Kind::kConjugatePair, center - root, 0.0});
      }
      if (has_real_prototype_pole) groups.push_back(QuadraticPoles(-0.5 * bandwidth, w0_squared));
      analog_gain = std::pow(bandwidth, order);
      pair_numerator = {1.0, 0.0, -1.0, 0.0, 0.0};  // One zero at z = 1 and one at z = -1.
      break;
    }
  }

  // Bilinear transform of each group; the digital gain is k' / prod(1 - p) over all analog poles
  // (analog zeros at 0 contribute prod(1 - 0) = 1).
  std::vector<SectionDraft> drafts;
  double digital_gain = analog_gain;
  for (const AnalogPoleGroup& group : groups) {
    SectionDraft draft;
    draft.biquad = group.kind == AnalogPoleGroup::Kind::kSingleReal ? single_numerator : pair_numerator;
    const Complex z1 = Bilinear(group.first);
    switch (group.kind) {
      case AnalogPoleGroup::Kind::kConjugatePair:
        draft.biquad.a1 = -2.0 * z1.real();
        draft.biquad.a2 = std::norm(z1);
        draft.distance_to_unit_circle = std::abs(1.0 - std::abs(z1));
        digital_gain /= std::norm(1.0 - group.first);
        break;
      case AnalogPoleGroup::Kind::kRealPair: {
        const double z2 = Bilinear(group.second).real();
        draft.biquad.a1 = -(z1.real() + z2);
        draft.biquad.a2 = z1.real() * z2;
        draft.distance_to_unit_circle = std::min(std::abs(1.0 - std::abs(z1.real())), std::abs(1.0 - std::abs(z2)));
        digital_gain /= (1.0 - group.first.real()) * (1.0 - group.second);
        break;
      }
      case AnalogPoleGroup::Kind::kSingleReal:
        draft.biquad.a1 = -z1.real();
        draft.biquad.a2 = 0.0;
        draft.distance_to_unit_circle = std::abs(1.0 - std::abs(z1.real()));
        digital_gain /= 1.0 - group.first.real();
        break;
    }
    drafts.push_back(draft);
  }

  // Section order as scipy's zpk2sos: poles nearest the unit circle (the most resonant) last, the
  // whole gain in the first section.
  std::stable_sort(drafts.begin(), drafts.end(), [](const SectionDraft& a, const SectionDraft& b) {
    return a.distance_to_unit_circle > b.distance_to_unit_circle;
  });
  SosFilter filter;
  for (const SectionDraft& draft : drafts) filter.sections.push_back(draft.biquad);
  Biquad& first = filter.sections.front();
  first.b0 *= digital_gain;
  first.b1 *= digital_gain;
  first.b2 *= digital_gain;
  return filter;
}

namespace {

// Steady-state section states for a unit step input (scipy.signal.sosfilt_zi): section s sees the
// constant H_0(1)...H_{s-1}(1) and its DF2T states then satisfy z2 = b2 u - a2 y, z1 = b1 u - a1 y + z2.
std::vector<double> StepSteadyState(const std::vector<Biquad>& sections) {
  std::vector<double> zi(2 * sections.size());
  double input = 1.0;
  for (std::size_t s = 0; s < sections.size(); ++s) {
    const Biquad& q = sections[s];
    const double output = input * (q.b0 + q.b1 + q.b2) / (1.0 + q.a1 + q.a2);
    zi[2 * s + 1] = q.b2 * input - q.a2 * output;
    zi[2 * s] = q.b1 * input - q.a1 * output + zi[2 * s + 1];
    input = output;
  }
  return zi;
}

// scipy.signal.sosfiltfilt's default pad: 3 * ntaps, where first-order sections do not count their
// missing tap.
Eigen::Index DefaultPadLength(const std::vector<Biquad>& sections) {
  Eigen::Index zero_b2 = 0, zero_a2 = 0;
  for (const Biquad& q : sections) {
    zero_b2 += q.b2 == 0.0;
    zero_a2 += q.a2 == 0.0;
  }
  const Eigen::Index taps = 2 * static_cast<Eigen::Index>(sections.size()) + 1 - std::min(zero_b2, zero_a2);
  return 3 * taps;
}

// Direct form II transposed cascade over `count` rows of kLanes interleaved columns (row i of
// lane l at data[i * kLanes + l]), in place, forward or backward. The recursion is a chain of
// dependent multiply-adds per column; running kLanes columns side by side keeps the multipliers
// busy, and each lane does exactly the operations of one column alone.
template <int kLanes>
void RunCascadeLanes(const std::vector<Biquad>& sections, std::array<double, kLanes>* state, double* data,
                     Eigen::Index count, bool backward) {
  const std::size_t section_count = sections.size();
  double* row = backward ? data + (count - 1) * kLanes : data;
  const Eigen::Index step = backward ? -kLanes : kLanes;
  for (Eigen::Index i = 0; i < count; ++i, row += step) {
    double value[kLanes];
    for (int l = 0; l < kLanes; ++l) value[l] = row[l];
    for (std::size_t s = 0; s < section_count; ++s) {
      const Biquad& q = sections[s];
      std::array<double, kLanes>& z1 = state[2 * s];
      std::array<double, kLanes>& z2 = state[2 * s + 1];
      for (int l = 0; l < kLanes; ++l) {
        const double out = q.b0 * value[l] + z1[l];
        z1[l] = q.b1 * value[l] - q.a1 * out + z2[l];
        z2[l] = q.b2 * value[l] - q.a2 * out;
        value[l] = out;
      }
    }
    for (int l = 0; l < kLanes; ++l) row[l] = value[l];
  }
}

// Per-filter constants and the extension buffer, reused for every group of columns.
class ZeroPhaseFilter {
 public:
  explicit ZeroPhaseFilter(const SosFilter& filter)
      : sections_(filter.sections),
        steady_state_(StepSteadyState(filter.sections)),
        default_pad_(DefaultPadLength(filter.sections)) {}

  // kLanes columns of n samples each, starting at x + l * x_stride, into y + l * y_stride.
  template <int kLanes>
  void Apply(const double* x, Eigen::Index x_stride, Eigen::Index n, double* y, Eigen::Index y_stride) {
    if (n <= 1) {
      for (int l = 0; l < kLanes; ++l) std::copy(x + l * x_stride, x + l * x_stride + n, y + l * y_stride);
      return;
    }
    const Eigen::Index pad = std::min(default_pad_, n - 1);
    const Eigen::Index ext_size = n + 2 * pad;
    extended_.resize(static_cast<std::size_t>(ext_size * kLanes));
    double* ext = extended_.data();
    // Odd extension: the edges are continued point-symmetrically, which keeps value and slope.
    for (int l = 0; l < kLanes; ++l) {
      const double* xl = x + l * x_stride;
      for (Eigen::Index i = 0; i < n; ++i) ext[(pad + i) * kLanes + l] = xl[i];
      for (Eigen::Index i = 1; i <= pad; ++i) {
        ext[(pad - i) * kLanes + l] = 2.0 * xl[0] - xl[i];
        ext[(pad + n - 1 + i) * kLanes + l] = 2.0 * xl[n - 1] - xl[n - 1 - i];
      }
    }
    // Forward pass starting as if the first sample had always been there, then backward likewise.
    std::vector<std::array<double, kLanes>> state(steady_state_.size());
    SetState<kLanes>(ext, state.data());
    RunCascadeLanes<kLanes>(sections_, state.data(), ext, ext_size, false);
    SetState<kLanes>(ext + (ext_size - 1) * kLanes, state.data());
    RunCascadeLanes<kLanes>(sections_, state.data(), ext, ext_size, true);
    for (int l = 0; l < kLanes; ++l)
      for (Eigen::Index i = 0; i < n; ++i) y[l * y_stride + i] = ext[(pad + i) * kLanes + l];
  }

 private:
  template <int kLanes>
  void SetState(const double* level, std::array<double, kLanes>* state) const {
    for (std::size_t i = 0; i < steady_state_.size(); ++i)
      for (int l = 0; l < kLanes; ++l) state[i][l] = steady_state_[i] * level[l];
  }

  const std::vector<Biquad>& sections_;
  std::vector<double> steady_state_;
  std::vector<double> extended_;
  Eigen::Index default_pad_;
};

}  // namespace

Eigen::VectorXd SosFilterCausal(const SosFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& x) {
  Eigen::VectorXd y = x;
  std::vector<std::array<double, 1>> state(2 * filter.sections.size(), {0.0});
  RunCascadeLanes<1>(filter.sections, state.data(), y.data(), y.size(), false);
  return y;
}

Eigen::VectorXd FiltFilt(const SosFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& x) {
  Eigen::VectorXd y(x.size());
  ZeroPhaseFilter(filter).Apply<1>(x.data(), x.size(), x.size(), y.data(), y.size());
  return y;
}

Eigen::MatrixXd FiltFiltColumns(const SosFilter& filter, const Eigen::Ref<const Eigen::MatrixXd>& x) {
  Eigen::MatrixXd y(x.rows(), x.cols());
  ZeroPhaseFilter zero_phase(filter);
  // Columns of a column-major Ref are contiguous (inner stride 1), outer stride apart.
  constexpr int kLanes = 4;
  const Eigen::Index n = x.rows(), cols = x.cols();
  Eigen::Index c = 0;
  for (; c + kLanes <= cols; c += kLanes)
    zero_phase.Apply<kLanes>(x.col(c).data(), x.outerStride(), n, y.col(c).data(), n);
  for (; c + 2 <= cols; c += 2) zero_phase.Apply<2>(x.col(c).data(), x.outerStride(), n, y.col(c).data(), n);
  for (; c < cols; ++c) zero_phase.Apply<1>(x.col(c).data(), x.outerStride(), n, y.col(c).data(), n);
  return y;
}

}  // namespace rotorid

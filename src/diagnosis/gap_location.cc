#include "rotorid/diagnosis/gap_location.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include <unsupported/Eigen/FFT>

#include "diagnosis/held_out.h"
#include "diagnosis/linearization.h"
#include "rotorid/core/error.h"
#include "rotorid/model/parameters.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

std::string GapLocationOptions::Validate() const {
  if (bands.empty()) return "at least one frequency band is needed";
  for (const auto& [low, high] : bands) {
    if (!(low >= 0.0)) return "frequency bands must start at 0 Hz or above";
    if (high > 0.0 && !(high > low)) return "frequency band high edges must exceed their low edges";
  }
  if (!(window_s > 0.0)) return "window_s must be positive";
  if (!(window_step_s > 0.0)) return "window_step_s must be positive";
  if (worst_stretches < 0) return "worst_stretches must not be negative";
  return {};
}

namespace {

double RowRateHz(const ProcessedFlight& flight) {
  const int n = flight.num_rows_samples();
  if (n < 2) return 0.0;
  const double span = flight.t_s[flight.row_samples[n - 1]] - flight.t_s[flight.row_samples[0]];
  return span > 0.0 ? (n - 1) / span : 0.0;
}

// Energy (sum of squares, Parseval) of a series in each band, from its discrete Fourier transform.
std::vector<double> BandEnergies(const Eigen::VectorXd& x, double rate_hz,
                                 const std::vector<std::pair<double, double>>& bands) {
  std::vector<double> energy(bands.size(), 0.0);
  const Eigen::Index n = x.size();
  if (n < 2 || !(rate_hz > 0.0)) return energy;
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  std::vector<double> input(x.data(), x.data() + n);
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, input);
  for (size_t k = 0; k < spectrum.size(); ++k) {
    const double frequency = static_cast<double>(k) * rate_hz / static_cast<double>(n);
    // One-sided: every bin but DC and (even n) Nyquist stands for two.
    const bool single = k == 0 || (n % 2 == 0 && static_cast<Eigen::Index>(k) == n / 2);
    const double e = (single ? 1.0 : 2.0) * std::norm(spectrum[k]) / static_cast<double>(n);
    for (size_t b = 0; b < bands.size(); ++b) {
      const double high = bands[b].second > 0.0 ? bands[b].second : std::numeric_limits<double>::infinity();
      if (frequency >= bands[b].first && frequency < high) {
        energy[b] += e;
        break;
      }
    }
  }
  return energy;
}

std::vector<std::string> Activities(const Eigen::Vector3d& rate_rms, const Eigen::Vector3d& flight_rate_rms,
                                    double vertical_acceleration) {
  // A rate counts when it is well above the flight's typical level and not negligible.
  constexpr double kRateFactor = 1.25, kMinRate = 0.05;  // -, rad/s
  constexpr double kVerticalAcceleration = 0.25;        // m/s^2, net over the window
  std::vector<std::string> out;
  if (vertical_acceleration > kVerticalAcceleration) out.push_back("climbing");
  if (vertical_acceleration < -kVerticalAcceleration) out.push_back("descending");
  const char* names[3] = {"rolling", "pitching", "yawing"};
  for (int a = 0; a < 3; ++a)
    if (rate_rms[a] > kRateFactor * flight_rate_rms[a] && rate_rms[a] > kMinRate) out.push_back(names[a]);
  if (out.empty()) {
    // Nothing stands out: hovering when the rates are well below the flight's typical ones.
    const bool quiet = (rate_rms.array() < 0.5 * flight_rate_rms.array() || rate_rms.array() < kMinRate).all();
    out.push_back(quiet ? "hovering" : "typical manoeuvring");
  }
  return out;
}

// Energy per band and component of the linear model's residual (`baseline`), the final model's and
// the rotor-model wrench, over all flights, as RMS per row.
std::vector<BandGap> BandGaps(const std::vector<ProcessedFlight>& flights,
                              const std::vector<internal::FlightResidual>& baseline,
                              const std::map<std::string, double>& final_parameters, const Effects& final_effects,
                              const std::vector<std::pair<double, double>>& bands) {
  const size_t num_bands = bands.size();
  std::vector<ComponentVector> residual_energy(num_bands, ComponentVector::Zero());
  std::vector<ComponentVector> final_energy(num_bands, ComponentVector::Zero());
  std::vector<ComponentVector> model_energy(num_bands, ComponentVector::Zero());
  double total_rows = 0.0, highest_rate = 0.0;
  for (size_t f = 0; f < flights.size(); ++f) {
    const ProcessedFlight& flight = flights[f];
    const internal::FlightResidual final_residual = internal::ResidualOf(flight, final_parameters, final_effects);
    const double rate = RowRateHz(flight);
    highest_rate = std::max(highest_rate, rate);
    total_rows += static_cast<double>(flight.num_rows_samples());
    for (int j = 0; j < kNumWrenchComponents; ++j) {
      const std::vector<double> r = BandEnergies(baseline[f].residual.col(j), rate, bands);
      const std::vector<double> e = BandEnergies(final_residual.residual.col(j), rate, bands);
      const std::vector<double> m = BandEnergies(baseline[f].rotor_wrench.col(j), rate, bands);
      for (size_t b = 0; b < num_bands; ++b) {
        residual_energy[b][j] += r[b];
        final_energy[b][j] += e[b];
        model_energy[b][j] += m[b];
      }
    }
  }
  ComponentVector residual_total = ComponentVector::Zero();
  for (size_t b = 0; b < num_bands; ++b) residual_total += residual_energy[b];
  std::vector<BandGap> out;
  for (size_t b = 0; b < num_bands; ++b) {
    BandGap band;
    band.low_hz = bands[b].first;
    band.high_hz = bands[b].second > 0.0 ? bands[b].second : 0.5 * highest_rate;
    const double rows = std::max(total_rows, 1.0);
    band.residual_rms = (residual_energy[b] / rows).cwiseSqrt();
    band.final_residual_rms = (final_energy[b] / rows).cwiseSqrt();
    band.model_rms = (model_energy[b] / rows).cwiseSqrt();
    band.residual_to_model_pct.resize(kNumWrenchComponents);
    for (int j = 0; j < kNumWrenchComponents; ++j) {
      band.share_pct[j] = residual_total[j] > 0.0 ? 100.0 * residual_energy[b][j] / residual_total[j] : 0.0;
      if (band.model_rms[j] > 1e-12 * std::max(1.0, band.residual_rms[j]) && model_energy[b][j] > 0.0)
        band.residual_to_model_pct[j] = 100.0 * band.residual_rms[j] / band.model_rms[j];
    }
    out.push_back(band);
  }
  return out;
}

// The windows of one flight, the residual scaled per component by the flight's residual RMS.
std::vector<FlightStretch> FlightWindows(const ProcessedFlight& flight, const internal::FlightResidual& residual,
                                         const GapLocationOptions& options) {
  std::vector<FlightStretch> windows;
  const int n = flight.num_rows_samples();
  if (n < 2) return windows;
  const ComponentVector scale =
      (residual.residual.colwise().squaredNorm().transpose() / n).cwiseSqrt().cwiseMax(1e-300);
  Eigen::Vector3d flight_rate_rms = Eigen::Vector3d::Zero();
  for (int r = 0; r < n; ++r)
    flight_rate_rms += flight.angular_velocity.row(flight.row_samples[r]).transpose().cwiseAbs2();
  flight_rate_rms = (flight_rate_rms / n).cwiseSqrt();
  auto time = [&](int r) { return flight.t_s[flight.row_samples[r]]; };
  for (double start = time(0); start + options.window_s <= time(n - 1) + 1e-9; start += options.window_step_s) {
    const double end = start + options.window_s;
    ComponentVector residual_sq = ComponentVector::Zero(), wrench_sq = ComponentVector::Zero(),
                    scaled_sq = ComponentVector::Zero();
    Eigen::Vector3d rate_sq = Eigen::Vector3d::Zero();
    double vertical = 0.0;
    int rows = 0;
    for (int r = 0; r < n; ++r) {
      if (time(r) < start || time(r) >= end) continue;
      ++rows;
      for (int j = 0; j < kNumWrenchComponents; ++j) {
        residual_sq[j] += residual.residual(r, j) * residual.residual(r, j);
        wrench_sq[j] += residual.rotor_wrench(r, j) * residual.rotor_wrench(r, j);
        const double scaled = residual.residual(r, j) / scale[j];
        scaled_sq[j] += scaled * scaled;
      }
      const int i = flight.row_samples[r];
      rate_sq += flight.angular_velocity.row(i).transpose().cwiseAbs2();
      vertical += flight.specific_force(i, 2) - flight.gravity_mps2;
    }
    if (rows < 2) continue;
    FlightStretch w;
    w.flight = flight.source;
    w.start_s = start;
    w.end_s = end;
    w.mean_square_ratio = scaled_sq.sum() / (kNumWrenchComponents * rows);
    scaled_sq.maxCoeff(&w.dominant_component);
    w.relative_error_pct = internal::RelativeErrorFromSums(residual_sq, wrench_sq);
    w.angular_velocity_rms = (rate_sq / rows).cwiseSqrt();
    w.mean_vertical_acceleration_mps2 = vertical / rows;
    w.activities = Activities(w.angular_velocity_rms, flight_rate_rms, w.mean_vertical_acceleration_mps2);
    windows.push_back(std::move(w));
  }
  return windows;
}

// The `count` worst windows (largest mean square ratio) that do not overlap a worse one.
std::vector<FlightStretch> WorstStretches(std::vector<FlightStretch> windows, int count) {
  std::sort(windows.begin(), windows.end(),
            [](const FlightStretch& a, const FlightStretch& b) { return a.mean_square_ratio > b.mean_square_ratio; });
  std::vector<FlightStretch> worst;
  for (const FlightStretch& w : windows) {
    if (static_cast<int>(worst.size()) >= count) break;
    const bool overlaps = std::any_of(worst.begin(), worst.end(), [&](const FlightStretch& o) {
      return o.flight == w.flight && w.start_s < o.end_s && o.start_s < w.end_s;
    });
    if (!overlaps) worst.push_back(w);
  }
  return worst;
}

// Signatures of the candidate effects at zero, chi projected out.
std::vector<EffectSignature> Signatures(const IdentificationResult& linear,
                                        const std::map<std::string, double>& linear_parameters,
                                        const std::vector<EffectKind>& candidates) {
  const internal::EffectLinearization linearization = internal::LinearizeEffects(
      linear.flights, linear_parameters, internal::EstimatedParameterNames(linear), Effects{}, candidates);
  std::vector<EffectSignature> signatures;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const internal::EffectSubsetFit fit = internal::FitEffectSubset(linearization, {candidates[k]});
    EffectSignature signature;
    signature.kind = candidates[k];
    signature.labels = fit.labels;
    signature.residual_correlation = fit.residual_correlation;
    signature.linearized_estimate = fit.step;
    signature.linearized_std = fit.std;
    signature.linearized_shrink_pct = 100.0 * fit.predicted_shrink;
    ComponentVector energy = ComponentVector::Zero();
    for (size_t c = 0; c < linearization.labels.size(); ++c) {
      if (linearization.column_kind[c] != static_cast<int>(k)) continue;
      for (Eigen::Index i = 0; i < linearization.effect_jacobian.rows(); ++i) {
        const double g = linearization.effect_jacobian(i, static_cast<Eigen::Index>(c));
        energy[linearization.row_component[i]] += g * g;
      }
    }
    if (energy.sum() > 0.0) signature.component_share_pct = 100.0 * energy / energy.sum();
    signatures.push_back(std::move(signature));
  }
  return signatures;
}

}  // namespace

GapLocation LocateGap(const IdentificationResult& linear, const std::map<std::string, double>& final_parameters,
                      const Effects& final_effects, const std::vector<EffectKind>& candidates,
                      const GapLocationOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  GapLocation out;
  out.relative_error_pct = linear.relative_error_pct;
  const std::map<std::string, double> linear_parameters =
      NamedParameters(linear.system, PredictionChi(linear.solution));
  std::vector<internal::FlightResidual> baseline;
  for (const ProcessedFlight& flight : linear.flights)
    baseline.push_back(internal::ResidualOf(flight, linear_parameters, Effects{}));
  out.bands = BandGaps(linear.flights, baseline, final_parameters, final_effects, options.bands);
  std::vector<FlightStretch> windows;
  for (size_t f = 0; f < linear.flights.size(); ++f)
    for (FlightStretch& w : FlightWindows(linear.flights[f], baseline[f], options)) windows.push_back(std::move(w));
  out.worst_stretches = WorstStretches(std::move(windows), options.worst_stretches);
  if (!candidates.empty()) out.signatures = Signatures(linear, linear_parameters, candidates);
  return out;
}

}  // namespace rotorid

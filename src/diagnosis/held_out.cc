#include "diagnosis/held_out.h"

#include <algorithm>
#include <cmath>

#include "diagnosis/statistics.h"
#include "rotorid/core/error.h"
#include "rotorid/ident/identify.h"

namespace rotorid::internal {

namespace {
constexpr int kComponents = 6;
constexpr int kFz = 2;
constexpr int kMx = 3, kMy = 4;
}  // namespace

ProcessedFlight WithRowSamples(const ProcessedFlight& flight, std::vector<int> row_samples) {
  ProcessedFlight out = flight;
  out.row_samples = std::move(row_samples);
  return out;
}

std::vector<Fold> TimeBlockedFolds(const std::vector<ProcessedFlight>& flights, int folds, double guard_s) {
  if (folds < 2) throw Error("time-blocked folds: need at least 2 folds, got " + std::to_string(folds));
  std::vector<Fold> out(folds);
  for (size_t f = 0; f < flights.size(); ++f) {
    const ProcessedFlight& flight = flights[f];
    const int n = flight.num_rows_samples();
    if (n < 4 * folds)
      throw Error(flight.source + ": " + std::to_string(n) + " row samples are too few for " + std::to_string(folds) +
                  " held-out folds");
    const double row_dt =
        (flight.t_s[flight.row_samples[n - 1]] - flight.t_s[flight.row_samples[0]]) / std::max(1, n - 1);
    const int guard = row_dt > 0.0 ? static_cast<int>(std::ceil(guard_s / row_dt)) : 0;
    for (int k = 0; k < folds; ++k) {
      const int first = static_cast<int>(static_cast<long>(k) * n / folds);
      const int last = static_cast<int>(static_cast<long>(k + 1) * n / folds);
      std::vector<int> held, train;
      for (int r = 0; r < n; ++r) {
        if (r >= first && r < last)
          held.push_back(flight.row_samples[r]);
        else if (r < first - guard || r >= last + guard)
          train.push_back(flight.row_samples[r]);
      }
      out[k].train.push_back(WithRowSamples(flight, std::move(train)));
      out[k].evaluate.push_back(WithRowSamples(flight, std::move(held)));
      out[k].evaluate_flight.push_back(static_cast<int>(f));
    }
  }
  return out;
}

int HeldOutResidual::row_samples() const {
  int rows = 0;
  for (const FlightResidual& s : segments) rows += static_cast<int>(s.residual.rows());
  return rows;
}

namespace {

// The size of a segment's rotor wrench in component j, as a sum of squares. In Mx and My the part
// of the rotor moment that is constant over the segment is left out: near hover it is what balances
// the first moment's ms x g, and a free ms can balance any static moment an effect adds (per-rotor
// thrust scales, ms changed with them), so it measures no scale of the row. Counting it let such a
// pair inflate the model's rotor moment, and with it this score's divisor, without predicting
// anything better (independent A_ground_effect: thrust scales "shrank" Mx 5.3 -> 4.4 % with the
// residual RMS unchanged). Fz's static part is the thrust that balances m g, m known: kept.
double WrenchSquares(const Eigen::Ref<const Eigen::VectorXd>& wrench, int j) {
  if ((j != kMx && j != kMy) || wrench.size() == 0) return wrench.squaredNorm();
  return (wrench.array() - wrench.mean()).matrix().squaredNorm();
}

// Per evaluation flight and component: the RMS of the scored residual and of the rotor wrench.
void ResidualAndWrenchRms(const HeldOutResidual& model, int num_flights, Eigen::MatrixXd* residual_rms,
                          Eigen::MatrixXd* wrench_rms) {
  Eigen::MatrixXd residual_sq = Eigen::MatrixXd::Zero(num_flights, kComponents);
  Eigen::MatrixXd wrench_sq = Eigen::MatrixXd::Zero(num_flights, kComponents);
  Eigen::MatrixXd rows = Eigen::MatrixXd::Zero(num_flights, kComponents);
  for (size_t s = 0; s < model.segments.size(); ++s) {
    const int f = model.flight[s];
    for (int j = 0; j < kComponents; ++j) {
      if (!model.scored[s][j]) continue;
      residual_sq(f, j) += model.segments[s].residual.col(j).squaredNorm();
      wrench_sq(f, j) += WrenchSquares(model.segments[s].rotor_wrench.col(j), j);
      rows(f, j) += static_cast<double>(model.segments[s].residual.rows());
    }
  }
  const Eigen::MatrixXd per_row = rows.cwiseMax(1.0).cwiseInverse();
  *residual_rms = residual_sq.cwiseProduct(per_row).cwiseSqrt();
  *wrench_rms = wrench_sq.cwiseProduct(per_row).cwiseSqrt();
}

}  // namespace

HeldOutScales BaselineScales(const HeldOutResidual& baseline, int num_flights) {
  HeldOutScales scales;
  ResidualAndWrenchRms(baseline, num_flights, &scales.residual_rms, &scales.wrench_rms);
  scales.residual_rms = (scales.residual_rms.array() > 0.0).select(scales.residual_rms, 1.0);
  return scales;
}

Eigen::MatrixXd ResidualWeights(const HeldOutResidual& model, const HeldOutScales& scales) {
  const Eigen::Index num_flights = scales.residual_rms.rows();
  Eigen::MatrixXd residual_rms, wrench_rms;
  ResidualAndWrenchRms(model, static_cast<int>(num_flights), &residual_rms, &wrench_rms);
  Eigen::MatrixXd weights = scales.residual_rms.cwiseInverse();
  for (Eigen::Index f = 0; f < num_flights; ++f)
    for (int j = 0; j < kComponents; ++j)
      if (scales.wrench_rms(f, j) > 0.0 && wrench_rms(f, j) > 0.0)
        weights(f, j) *= scales.wrench_rms(f, j) / wrench_rms(f, j);
  return weights;
}

std::vector<std::optional<double>> RelativeErrorFromSums(const ComponentVector& residual_sq,
                                                         const ComponentVector& wrench_sq) {
  std::vector<std::optional<double>> out(kComponents);
  for (int j = 0; j < kComponents; ++j)
    if (wrench_sq[j] > 0.0) out[j] = 100.0 * std::sqrt(residual_sq[j] / wrench_sq[j]);
  return out;
}

std::vector<std::optional<double>> GapFromSums(const ComponentVector& residual_sq, const ComponentVector& wrench_sq) {
  std::vector<std::optional<double>> out = RelativeErrorFromSums(residual_sq, wrench_sq);
  // The rotor model has no horizontal force: measure Fx and Fy against the thrust.
  for (int j = 0; j < 2; ++j)
    if (wrench_sq[kFz] > 0.0) out[j] = 100.0 * std::sqrt(residual_sq[j] / wrench_sq[kFz]);
  return out;
}

ComponentVector NoiseResidualSquares(const ProcessedFlight& flight, const std::map<std::string, double>& parameters) {
  const std::vector<Eigen::MatrixXd> covariance = IdimNoiseCovariance(flight);
  const Eigen::VectorXd chi_t = FlightChiT(flight, parameters);
  ComponentVector out;
  for (int j = 0; j < kComponents; ++j) out[j] = std::max(0.0, chi_t.dot(covariance[j] * chi_t));
  return out;
}

HeldOutGap ScoreHeldOut(const HeldOutResidual& residual, const HeldOutScales& scales, const ComponentVector& noise_sq) {
  HeldOutGap gap;
  const Eigen::MatrixXd weights = ResidualWeights(residual, scales);
  ComponentVector residual_sq = ComponentVector::Zero(), wrench_sq = ComponentVector::Zero();
  std::vector<std::vector<Eigen::VectorXd>> scaled(kComponents);
  int rows = 0;
  for (size_t s = 0; s < residual.segments.size(); ++s) {
    const FlightResidual& segment = residual.segments[s];
    const int f = residual.flight[s];
    rows += static_cast<int>(segment.residual.rows());
    for (int j = 0; j < kComponents; ++j) {
      residual_sq[j] += segment.residual.col(j).squaredNorm();
      wrench_sq[j] += segment.rotor_wrench.col(j).squaredNorm();
      if (!residual.scored[s][j]) continue;
      Eigen::VectorXd series = segment.residual.col(j) * weights(f, j);
      gap.whitened_ssr += series.squaredNorm();
      gap.entries += static_cast<int>(series.size());
      scaled[j].push_back(std::move(series));
    }
  }
  gap.relative_error_pct = RelativeErrorFromSums(residual_sq, wrench_sq);
  gap.gap_pct = GapFromSums(residual_sq, wrench_sq);
  gap.noise_floor_pct = GapFromSums(noise_sq, wrench_sq);
  gap.model_error_pct = GapFromSums((residual_sq - noise_sq).cwiseMax(0.0), wrench_sq);
  if (rows > 0) gap.residual_rms = (residual_sq / rows).cwiseSqrt();
  double factor = 0.0;
  int scored_components = 0;
  for (int j = 0; j < kComponents; ++j) {
    if (scaled[j].empty()) continue;
    factor += AutocorrelationFactor(scaled[j]);
    ++scored_components;
  }
  gap.autocorrelation_factor = scored_components > 0 ? factor / scored_components : 1.0;
  return gap;
}

EffectTest TestAddedEffects(const HeldOutGap& without, const HeldOutGap& with, int added_parameters, double alpha,
                            double min_shrink_pct) {
  EffectTest test;
  test.added_parameters = added_parameters;
  const double n = static_cast<double>(with.entries);
  test.effective_samples = n / std::max(1.0, with.autocorrelation_factor);
  const double removed = without.whitened_ssr - with.whitened_ssr;
  test.shrink_pct = without.whitened_ssr > 0.0 ? 100.0 * removed / without.whitened_ssr : 0.0;
  const double q = static_cast<double>(added_parameters);
  if (removed > 0.0 && q > 0.0 && with.whitened_ssr > 0.0 && test.effective_samples > q + 1.0) {
    test.f_statistic = (removed / q) / (std::max(1.0, with.autocorrelation_factor) * with.whitened_ssr / (n - q));
    test.p_value = FSurvival(test.f_statistic, q, test.effective_samples - q);
  }
  test.significant = test.p_value < alpha && test.shrink_pct > min_shrink_pct;
  return test;
}

namespace {

// The one-sided paired test of per-row differences (series per segment): their mean, and its t
// statistic with the Bartlett long-run variance of the autocorrelated rows.
PairedComparison PairedTest(std::vector<Eigen::VectorXd> differences) {
  double sum = 0.0;
  Eigen::Index n = 0;
  for (const Eigen::VectorXd& d : differences) {
    sum += d.sum();
    n += d.size();
  }
  PairedComparison out;
  if (n < 2) return out;
  out.mean_difference = sum / static_cast<double>(n);
  for (Eigen::VectorXd& d : differences) d.array() -= out.mean_difference;
  double variance = 0.0;
  for (const Eigen::VectorXd& d : differences) variance += d.squaredNorm();
  variance /= static_cast<double>(n);
  const double long_run = variance * AutocorrelationFactor(differences);
  if (!(long_run > 0.0)) return out;
  out.t_statistic = out.mean_difference / std::sqrt(long_run / static_cast<double>(n));
  out.p_value = 0.5 * std::erfc(out.t_statistic / std::sqrt(2.0));
  return out;
}

}  // namespace

PairedComparison CompareHeldOut(const HeldOutResidual& a, const HeldOutResidual& b, const HeldOutScales& scales) {
  if (a.segments.size() != b.segments.size()) throw Error("held-out comparison of different row sets");
  const Eigen::MatrixXd weights_a = ResidualWeights(a, scales), weights_b = ResidualWeights(b, scales);
  std::vector<Eigen::VectorXd> differences;
  for (size_t s = 0; s < a.segments.size(); ++s) {
    const Eigen::MatrixXd& ra = a.segments[s].residual;
    const Eigen::MatrixXd& rb = b.segments[s].residual;
    if (ra.rows() != rb.rows()) throw Error("held-out comparison of different row sets");
    Eigen::RowVectorXd weight_a = weights_a.row(a.flight[s]), weight_b = weights_b.row(a.flight[s]);
    for (int j = 0; j < kComponents; ++j)
      if (!a.scored[s][j]) weight_a[j] = weight_b[j] = 0.0;
    Eigen::VectorXd d(ra.rows());
    for (Eigen::Index r = 0; r < ra.rows(); ++r)
      d[r] = rb.row(r).cwiseProduct(weight_b).squaredNorm() - ra.row(r).cwiseProduct(weight_a).squaredNorm();
    differences.push_back(std::move(d));
  }
  return PairedTest(std::move(differences));
}

namespace {

// A residual sum of squares `after` whose part beyond the noise (`noise`, that of `before`) exceeds
// before's by more than growth_pct in RMS and is at least the noise itself.
bool ModelErrorGrows(double before, double after, double noise, double growth_pct) {
  const double error_before = std::sqrt(std::max(0.0, before - noise));
  const double error_after = std::sqrt(std::max(0.0, after - noise));
  return after >= 2.0 * noise && error_after > (1.0 + growth_pct / 100.0) * error_before;
}

}  // namespace

std::vector<ComponentWorsening> WorsenedComponents(const HeldOutResidual& without, const HeldOutResidual& with,
                                                   const HeldOutScales& scales, const ComponentVector& noise_share,
                                                   double min_growth_pct, double alpha) {
  if (without.segments.size() != with.segments.size()) throw Error("held-out comparison of different row sets");
  const Eigen::MatrixXd weights_a = ResidualWeights(without, scales), weights_b = ResidualWeights(with, scales);
  std::vector<ComponentWorsening> worse;
  for (int j = 0; j < kComponents; ++j) {
    std::vector<Eigen::VectorXd> growth;
    double before_sq = 0.0, after_sq = 0.0, weighted_before = 0.0, weighted_after = 0.0;
    Eigen::Index n = 0;
    for (size_t s = 0; s < with.segments.size(); ++s) {
      if (!with.scored[s][j] || !without.scored[s][j]) continue;
      const int f = with.flight[s];
      const Eigen::VectorXd a = without.segments[s].residual.col(j).array().square();
      const Eigen::VectorXd b = with.segments[s].residual.col(j).array().square();
      if (a.size() != b.size()) throw Error("held-out comparison of different row sets");
      before_sq += a.sum();
      after_sq += b.sum();
      const Eigen::VectorXd d = std::pow(weights_b(f, j), 2) * b - std::pow(weights_a(f, j), 2) * a;
      weighted_before += std::pow(weights_a(f, j), 2) * a.sum();
      weighted_after += std::pow(weights_b(f, j), 2) * b.sum();
      n += a.size();
      growth.push_back(d);
    }
    if (n < 2 || !(weighted_before > 0.0)) continue;
    ComponentWorsening w;
    w.component = j;
    w.rms_before = std::sqrt(before_sq / static_cast<double>(n));
    w.rms_after = std::sqrt(after_sq / static_cast<double>(n));
    w.growth_pct = 100.0 * (std::sqrt(weighted_after / weighted_before) - 1.0);
    // Worse both as the score measures it and in physical units: the score's divisor, the model's own
    // rotor moment, is what true thrust scales change (CF take-off with ground effect: My's residual
    // falls 3.6 % while it grows 6.8 % against the rotor moment), and Mz's raw residual grows with kd.
    if (!ModelErrorGrows(before_sq, after_sq, noise_share[j] * before_sq, min_growth_pct) ||
        !ModelErrorGrows(weighted_before, weighted_after, noise_share[j] * weighted_before, min_growth_pct))
      continue;
    const PairedComparison test = PairedTest(std::move(growth));
    w.t_statistic = test.t_statistic;
    if (test.p_value < alpha) worse.push_back(w);
  }
  return worse;
}

EffectTest ScreeningTest(double shrink_fraction, int added_parameters, double effective_samples, Eigen::Index rows) {
  EffectTest test;
  test.screened = true;
  test.added_parameters = added_parameters;
  test.effective_samples = effective_samples;
  test.shrink_pct = 100.0 * shrink_fraction;
  const double q = added_parameters, n = static_cast<double>(rows);
  const double factor = effective_samples > 0.0 ? n / effective_samples : 1.0;
  if (shrink_fraction > 0.0 && shrink_fraction < 1.0 && effective_samples > q + 1.0) {
    test.f_statistic = shrink_fraction / (1.0 - shrink_fraction) * (n - q) / (q * factor);
    test.p_value = FSurvival(test.f_statistic, q, effective_samples - q);
  }
  test.significant = false;  // only held-out data can make an effect significant
  return test;
}

}  // namespace rotorid::internal

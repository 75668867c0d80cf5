#include "diagnosis/linearization.h"

#include <ceres/jet.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/parallel_for.h"
#include "diagnosis/statistics.h"
#include "refine/effect_rows.h"
#include "rotorid/core/error.h"
#include "rotorid/ident/identify.h"
#include "rotorid/model/parameters.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/refine/effect_model.h"

namespace rotorid::internal {

namespace {

// Column of W that a named parameter multiplies in this flight, or -1.
int ColumnOf(const std::string& name, const ProcessedFlight& flight) {
  for (int k = 0; k < kNumRotorCoefficients; ++k)
    if (name == kRotorCoefficientNames[k]) return k;
  for (int k = 0; k < kNumBodyParameters; ++k)
    if (name == BodyParameterName(flight, k)) return kNumRotorCoefficients + k;
  return -1;
}

// (J^T J)^+ from the Gram matrix J^T J, with the columns equilibrated first, so that the
// pseudo-inverse threshold is relative to each column's own scale.
Eigen::MatrixXd NormalInverse(const Eigen::MatrixXd& gram) {
  const Eigen::Index n = gram.cols();
  if (n == 0) return Eigen::MatrixXd(0, 0);
  Eigen::VectorXd inverse_norm(n);
  for (Eigen::Index c = 0; c < n; ++c) {
    const double norm = std::sqrt(std::max(gram(c, c), 0.0));
    inverse_norm[c] = norm > 0.0 ? 1.0 / norm : 0.0;
  }
  const Eigen::MatrixXd normal = inverse_norm.asDiagonal() * gram * inverse_norm.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normal);
  const Eigen::VectorXd values = eigen.eigenvalues();
  const double threshold = 1e-12 * std::max(values.maxCoeff(), 1e-300);
  Eigen::VectorXd inverse_values(n);
  for (Eigen::Index k = 0; k < n; ++k) inverse_values[k] = values[k] > threshold ? 1.0 / values[k] : 0.0;
  const Eigen::MatrixXd pinv = eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose();
  return inverse_norm.asDiagonal() * pinv * inverse_norm.asDiagonal();
}

}  // namespace

FlightResidual ResidualOf(const ProcessedFlight& flight, const std::map<std::string, double>& parameters,
                          const Effects& effects) {
  const Eigen::MatrixXd w = BuildIdimMatrixWithEffects(flight, effects);
  const Eigen::VectorXd chi_t = FlightChiT(flight, parameters);
  const Eigen::Index rows = w.rows() / kNumWrenchComponents;
  FlightResidual out;
  out.residual.resize(rows, kNumWrenchComponents);
  out.rotor_wrench.resize(rows, kNumWrenchComponents);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (int j = 0; j < kNumWrenchComponents; ++j) {
      const Eigen::Index i = kNumWrenchComponents * r + j;
      out.residual(r, j) = w.row(i).dot(chi_t);
      out.rotor_wrench(r, j) = -(w(i, 0) * chi_t[0] + w(i, 1) * chi_t[1]);
    }
  return out;
}

std::vector<std::string> EstimatedParameterNames(const IdentificationResult& linear) {
  std::vector<std::string> names;
  for (int k = 0; k < linear.system.num_parameters(); ++k)
    if (linear.solution.essential[k] || PredictsWithProfiled(linear.solution, k))
      names.push_back(linear.system.parameter_names[k]);
  return names;
}

std::vector<std::string> EffectLabels(EffectKind kind, const Vehicle& vehicle) {
  return kind->Labels(kind->Dimension(vehicle));
}

namespace {

// What a linearisation gathers over its flights beside the rows themselves: each scored component's
// scaled residual series (for the autocorrelation factor) and each effect column's signature in
// physical units, in the scored components and in the others.
struct LinearizationSums {
  std::vector<std::vector<Eigen::VectorXd>> component_series =
      std::vector<std::vector<Eigen::VectorXd>>(kNumWrenchComponents);
  Eigen::VectorXd signature_scored, signature_unscored;
};

// One flight's rows at the linearisation point: the residual and the rotor wrench per component
// (rows) and row sample (columns), and the kept row samples' parameter Jacobian (unscaled) written
// into out->parameter_jacobian at `offset`.
struct FlightRows {
  Eigen::MatrixXd rho;
  Eigen::MatrixXd rotor_wrench;
};
FlightRows ParameterRows(const ProcessedFlight& flight, const EffectRows& values, const Eigen::VectorXd& chi_t,
                         const std::vector<std::string>& free_parameters, int stride, Eigen::Index offset,
                         EffectLinearization* out) {
  const Eigen::Index p = static_cast<Eigen::Index>(free_parameters.size());
  const int samples = flight.num_rows_samples();
  FlightRows rows{Eigen::MatrixXd(kNumWrenchComponents, samples), Eigen::MatrixXd(kNumWrenchComponents, samples)};
  std::vector<int> column_of(static_cast<size_t>(p));
  for (Eigen::Index c = 0; c < p; ++c) column_of[static_cast<size_t>(c)] = ColumnOf(free_parameters[c], flight);
  const EffectRows::PassValues<double> pass = values.Pass<double>();
  for (int r = 0; r < samples; ++r) {
    const Eigen::Matrix<double, 6, kNumIdimColumns> w = values.Rows<double>(r, pass);
    rows.rho.col(r) = w * chi_t;
    rows.rotor_wrench.col(r) = w.leftCols<2>() * chi_t.head<2>();
    if (r % stride != 0) continue;
    for (Eigen::Index c = 0; c < p; ++c)
      if (const int column = column_of[static_cast<size_t>(c)]; column >= 0)
        out->parameter_jacobian.block<kNumWrenchComponents, 1>(offset + kNumWrenchComponents * (r / stride), c) =
            w.col(column);
  }
  return rows;
}

// Per-component scale of one flight's rows: the residual's RMS in this flight; unmodelled components
// (no rotor term) get no weight (an infinite scale) and are noted in out->unscored_components.
Eigen::Matrix<double, kNumWrenchComponents, 1> ComponentScales(const FlightRows& rows,
                                                               std::array<bool, kNumWrenchComponents>* scored,
                                                               EffectLinearization* out, LinearizationSums* sums) {
  const Eigen::Index samples = rows.rho.cols();
  Eigen::Matrix<double, kNumWrenchComponents, 1> scale;
  for (int j = 0; j < kNumWrenchComponents; ++j) {
    double sum = 0.0, rotor_sum = 0.0;
    for (Eigen::Index r = 0; r < samples; ++r) {
      sum += rows.rho(j, r) * rows.rho(j, r);
      rotor_sum += std::pow(rows.rotor_wrench(j, r), 2);
    }
    const double rms = std::sqrt(sum / static_cast<double>(std::max<Eigen::Index>(1, samples)));
    scale[j] = rms > 0.0 ? rms : 1.0;
    (*scored)[static_cast<size_t>(j)] = !(j >= 2 && rotor_sum == 0.0);
    if (!(*scored)[static_cast<size_t>(j)]) {
      scale[j] = std::numeric_limits<double>::infinity();
      if (std::find(out->unscored_components.begin(), out->unscored_components.end(), j) ==
          out->unscored_components.end())
        out->unscored_components.push_back(j);
    } else {
      out->scored_rows += samples;
      sums->component_series[j].push_back(rows.rho.row(j).transpose() / scale[j]);
    }
  }
  return scale;
}

// The effect columns of one flight's kept row samples at `offset`: d rho / d effect by the
// refinement's own Jets (EffectRows), then scaled as the residual. Where an effect acts is measured in
// physical units, forces times the arm (N m): an unscored component's residual is no scale for it
// (with kd, I_zz and the products discarded, Mz's residual is almost empty).
void EffectColumnsOfFlight(const ProcessedFlight& flight, const EffectRows& model, const Eigen::VectorXd& chi_t,
                           int stride, Eigen::Index kept, Eigen::Index offset,
                           const Eigen::Matrix<double, kNumWrenchComponents, 1>& scale,
                           const std::array<bool, kNumWrenchComponents>& scored, int num_threads,
                           EffectLinearization* out, LinearizationSums* sums) {
  const Eigen::Index e = static_cast<Eigen::Index>(out->labels.size());
  const double arm = flight.vehicle.MeanArm() > 0.0 ? flight.vehicle.MeanArm() : 1.0;
  const size_t coordinates = model.coordinates().size();
  std::vector<EffectRows::PassValues<WideImuJet>> passes;
  for (size_t first = 0; first < coordinates; first += kWideImuJetSize) passes.push_back(model.Pass<WideImuJet>(first));
  // The Jets of the kept row samples, in parallel: each writes its own rows, unscaled.
  ParallelFor(static_cast<int>(kept), num_threads, [&](int k) {
    for (const EffectRows::PassValues<WideImuJet>& jet_pass : passes) {
      const Eigen::Matrix<WideImuJet, 6, kNumIdimColumns> jet_rows = model.Rows<WideImuJet>(stride * k, jet_pass);
      for (int j = 0; j < kNumWrenchComponents; ++j) {
        WideImuJet rho_jet(0.0);
        for (int c = 0; c < kNumIdimColumns; ++c) rho_jet += jet_rows(j, c) * chi_t[c];
        for (size_t c = jet_pass.first; c < jet_pass.last; ++c)
          out->effect_jacobian(offset + kNumWrenchComponents * k + j, static_cast<Eigen::Index>(c)) =
              rho_jet.v[c - jet_pass.first];
      }
    }
  });
  for (Eigen::Index k = 0; k < kept; ++k)
    for (int j = 0; j < kNumWrenchComponents; ++j)
      for (Eigen::Index column = 0; column < e; ++column) {
        double& derivative = out->effect_jacobian(offset + kNumWrenchComponents * k + j, column);
        const double signature = std::pow(derivative * (j < 3 ? arm : 1.0), 2);
        (scored[static_cast<size_t>(j)] ? sums->signature_scored : sums->signature_unscored)[column] += signature;
        derivative /= scale[j];
      }
}

// One flight's rows of the linearisation at `offset`; returns the number of rows written.
Eigen::Index AddFlightRows(const ProcessedFlight& flight, const std::map<std::string, double>& parameters,
                           const std::vector<std::string>& free_parameters, const Effects& effects,
                           const std::vector<EffectKind>& kinds, const std::vector<EffectKind>& rotor_kinds, int stride,
                           Eigen::Index offset, int num_threads, EffectLinearization* out, LinearizationSums* sums) {
  const Eigen::VectorXd chi_t = FlightChiT(flight, parameters);
  const EffectiveRotor rotor = EffectiveRotorAtRows(flight, effects, rotor_kinds);
  // The rows' values as BuildIdimMatrixWithEffects gives them (no free coordinate), one row
  // sample at a time: the residual of every row sample, without the flight's W.
  const EffectRows values(&flight, effects, {}, &rotor);
  const FlightRows rows = ParameterRows(flight, values, chi_t, free_parameters, stride, offset, out);
  std::array<bool, kNumWrenchComponents> scored{};
  const Eigen::Matrix<double, kNumWrenchComponents, 1> scale = ComponentScales(rows, &scored, out, sums);
  const Eigen::Index kept = (flight.num_rows_samples() + stride - 1) / stride;
  for (Eigen::Index k = 0; k < kept; ++k)
    for (int j = 0; j < kNumWrenchComponents; ++j) {
      const Eigen::Index i = offset + kNumWrenchComponents * k + j;
      out->row_component[i] = j;
      out->residual[i] = rows.rho(j, stride * k) / scale[j];
      out->parameter_jacobian.row(i) /= scale[j];
    }
  const EffectRows model(&flight, effects, kinds, &rotor);
  EffectColumnsOfFlight(flight, model, chi_t, stride, kept, offset, scale, scored, num_threads, out, sums);
  return kNumWrenchComponents * kept;
}

// The normal equations of the scaled rows, the autocorrelation factor and where the effects act.
// `weight`: all / kept row samples, so that the kept rows stand for all.
void FinishLinearization(const LinearizationSums& sums, double weight, EffectLinearization* out) {
  out->effect_unscored_share =
      sums.signature_unscored.cwiseQuotient((sums.signature_scored + sums.signature_unscored).cwiseMax(1e-300));
  double factor = 0.0;
  int scored_components = 0;
  for (int j = 0; j < kNumWrenchComponents; ++j) {
    if (sums.component_series[j].empty()) continue;
    factor += AutocorrelationFactor(sums.component_series[j]);
    ++scored_components;
  }
  out->autocorrelation_factor = scored_components > 0 ? factor / scored_components : 1.0;
  Eigen::MatrixXd j(out->residual.size(), out->parameter_jacobian.cols() + out->effect_jacobian.cols());
  j << out->parameter_jacobian, out->effect_jacobian;
  out->gram = weight * (j.transpose() * j);
  out->gram_residual = weight * (j.transpose() * out->residual);
  out->residual_ssr = weight * out->residual.squaredNorm();
}

}  // namespace

EffectLinearization LinearizeEffects(const std::vector<ProcessedFlight>& flights,
                                     const std::map<std::string, double>& parameters,
                                     const std::vector<std::string>& free_parameters, const Effects& given,
                                     const std::vector<EffectKind>& kinds, int max_row_samples, int num_threads) {
  // The rows' Jets take a value of every free effect: per-rotor ones absent from `given` at zero.
  Effects effects = given;
  for (EffectKind kind : kinds) effects.Set(kind, given.Get(kind, flights.front().vehicle));
  EffectLinearization out;
  out.kinds = kinds;
  const bool kd_free = std::find(free_parameters.begin(), free_parameters.end(), "kd") != free_parameters.end();
  for (EffectKind kind : kinds) out.held_directions.push_back(HeldDirections(kind, flights.front().vehicle, kd_free));
  for (size_t k = 0; k < kinds.size(); ++k)
    for (const std::string& label : EffectLabels(kinds[k], flights.front().vehicle)) {
      out.labels.push_back(label);
      out.column_kind.push_back(static_cast<int>(k));
    }
  Eigen::Index all_samples = 0;
  for (const ProcessedFlight& f : flights) all_samples += f.num_rows_samples();
  // An even stride over each flight's row samples; the kept ones, per flight, are ceil(n / stride).
  const int stride = max_row_samples > 0 && all_samples > max_row_samples
                         ? static_cast<int>((all_samples + max_row_samples - 1) / max_row_samples)
                         : 1;
  Eigen::Index kept_samples = 0;
  for (const ProcessedFlight& f : flights) kept_samples += (f.num_rows_samples() + stride - 1) / stride;
  const Eigen::Index total_rows = kNumWrenchComponents * kept_samples;
  const Eigen::Index e = static_cast<Eigen::Index>(out.labels.size());
  out.residual.resize(total_rows);
  out.parameter_jacobian.setZero(total_rows, static_cast<Eigen::Index>(free_parameters.size()));
  out.effect_jacobian.setZero(total_rows, e);
  out.row_component.resize(total_rows);
  LinearizationSums sums;
  sums.signature_scored = sums.signature_unscored = Eigen::VectorXd::Zero(e);
  std::vector<EffectKind> rotor_kinds;
  for (EffectKind kind : kinds)
    if (kind->stage() == EffectStage::kRotorSignal) rotor_kinds.push_back(kind);
  Eigen::Index offset = 0;
  for (const ProcessedFlight& flight : flights)
    offset += AddFlightRows(flight, parameters, free_parameters, effects, kinds, rotor_kinds, stride, offset,
                            num_threads, &out, &sums);
  // The kept rows stand for all: sums over them scaled by all / kept row samples.
  FinishLinearization(
      sums, static_cast<double>(all_samples) / static_cast<double>(std::max<Eigen::Index>(1, kept_samples)), &out);
  return out;
}

EffectSubsetFit FitEffectSubset(const EffectLinearization& linearization, const std::vector<EffectKind>& subset) {
  const Eigen::Index p = linearization.parameter_jacobian.cols(), n = linearization.scored_rows;
  std::vector<Eigen::Index> all(static_cast<size_t>(p));  // columns of the Gram matrix: chi, then the subset's
  for (Eigen::Index c = 0; c < p; ++c) all[static_cast<size_t>(c)] = c;
  EffectSubsetFit fit;
  for (size_t c = 0; c < linearization.labels.size(); ++c) {
    const EffectKind kind = linearization.kinds[linearization.column_kind[c]];
    if (std::find(subset.begin(), subset.end(), kind) == subset.end()) continue;
    all.push_back(p + static_cast<Eigen::Index>(c));
    fit.labels.push_back(linearization.labels[c]);
    fit.column_kind.push_back(kind);
  }
  const Eigen::Index e = static_cast<Eigen::Index>(fit.labels.size());
  // A zero-sum effect (per-rotor thrust scales) moves within sum = 0, as the refinement pins it: its
  // columns are projected onto that subspace (their sum is kt's and kd's columns), and so are its
  // step and covariance (the pseudo-inverse's part along the all-ones direction is arbitrary). A held
  // coordinate (an IMU lever arm's z) does not move at all: its column is projected out.
  Eigen::MatrixXd projector = Eigen::MatrixXd::Identity(p + e, p + e);
  for (Eigen::Index c = 0; c < e;) {
    Eigen::Index end = c;
    while (end < e && fit.column_kind[end] == fit.column_kind[c]) ++end;
    const EffectKind kind = fit.column_kind[c];
    if (kind->info().zero_sum) projector.block(p + c, p + c, end - c, end - c).array() -= 1.0 / (end - c);
    for (int k : kind->info().held_coordinates)
      if (c + k < end) projector(p + c + k, p + c + k) = 0.0;
    // A held direction (centred, so orthogonal to the zero-sum one) is projected out as well.
    const size_t k = static_cast<size_t>(std::find(linearization.kinds.begin(), linearization.kinds.end(), kind) -
                                         linearization.kinds.begin());
    if (k < linearization.held_directions.size() && linearization.held_directions[k].rows() == end - c) {
      const Eigen::MatrixXd& held = linearization.held_directions[k];
      projector.block(p + c, p + c, end - c, end - c) -= held * held.transpose();
    }
    c = end;
  }
  const Eigen::MatrixXd gram = projector * linearization.gram(all, all) * projector;
  const Eigen::VectorXd gradient = projector * linearization.gram_residual(all);

  const Eigen::MatrixXd covariance_unit = projector * NormalInverse(gram) * projector;
  const Eigen::MatrixXd chi_inverse = NormalInverse(gram.topLeftCorner(p, p));
  const Eigen::VectorXd chi_gradient = gradient.head(p);
  const double ssr = linearization.residual_ssr;
  const double removed = gradient.dot(covariance_unit * gradient) - chi_gradient.dot(chi_inverse * chi_gradient);
  fit.predicted_shrink = ssr > 0.0 ? std::max(0.0, removed) / ssr : 0.0;
  fit.step = -(covariance_unit * gradient).tail(e);
  const double sigma2 = ssr / std::max<double>(1.0, static_cast<double>(n - p - e));
  const Eigen::MatrixXd effect_cov =
      covariance_unit.bottomRightCorner(e, e) * sigma2 * linearization.autocorrelation_factor;
  fit.std = effect_cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::VectorXd inverse_std = fit.std.unaryExpr([](double s) { return s > 0.0 ? 1.0 / s : 0.0; });
  fit.correlation = inverse_std.asDiagonal() * effect_cov * inverse_std.asDiagonal();
  fit.effective_samples = static_cast<double>(n) / linearization.autocorrelation_factor;
  // Signatures with chi projected out, E - P M with M = (P^T P)^+ P^T E, from the Gram blocks.
  const Eigen::MatrixXd chi_effect = gram.topRightCorner(p, e);
  const Eigen::MatrixXd m = chi_inverse * chi_effect;
  const Eigen::VectorXd projected_dot_r = gradient.tail(e) - m.transpose() * chi_gradient;
  const Eigen::MatrixXd projected_gram = gram.bottomRightCorner(e, e) - chi_effect.transpose() * m -
                                         m.transpose() * chi_effect + m.transpose() * gram.topLeftCorner(p, p) * m;
  fit.residual_correlation.resize(e);
  const double r_norm = std::sqrt(ssr);
  for (Eigen::Index c = 0; c < e; ++c) {
    const double norm = std::sqrt(std::max(projected_gram(c, c), 0.0)) * r_norm;
    fit.residual_correlation[c] = norm > 0.0 ? projected_dot_r[c] / norm : 0.0;
  }
  return fit;
}

Eigen::VectorXd EffectColumns(const EffectSubsetFit& fit, EffectKind kind, const Eigen::VectorXd& per_column) {
  Eigen::VectorXd out(std::count(fit.column_kind.begin(), fit.column_kind.end(), kind));
  int k = 0;
  for (size_t c = 0; c < fit.column_kind.size(); ++c)
    if (fit.column_kind[c] == kind) out[k++] = per_column[static_cast<Eigen::Index>(c)];
  return out;
}

}  // namespace rotorid::internal

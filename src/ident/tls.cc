#include "rotorid/ident/tls.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "rotorid/core/error.h"
#include "rotorid/model/parameters.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/signal/autocorrelation.h"

namespace rotorid {

const char* TlsMethodName(TlsMethod method) { return method == TlsMethod::kPaper ? "paper" : "noise-aware"; }

TlsMethod ParseTlsMethod(const std::string& name) {
  if (name == "paper") return TlsMethod::kPaper;
  if (name == "noise-aware" || name == "default") return TlsMethod::kNoiseAware;
  throw Error("unknown method '" + name + "'; use 'noise-aware' (default) or 'paper'");
}

std::string TlsOptions::Validate() const {
  if (!(r_sigma > 1.0)) return "r_sigma must be greater than 1";
  if (!(max_rel_std_pct > 0.0)) return "the %sigma limit for essential parameters must be positive";
  if (max_iterations < 1) return "max_iterations must be at least 1";
  return {};
}

int IdimLayout::Column(const std::string& name) const {
  const auto it = std::find(parameter_names.begin(), parameter_names.end(), name);
  return it == parameter_names.end() ? -1 : static_cast<int>(it - parameter_names.begin());
}

int IdimLayout::SystemColumn(int f, int k) const {
  if (k < kNumRotorCoefficients) return k;
  if (k < kNumRotorCoefficients + kNumBodyParameters) return flight_body_columns[f][k - kNumRotorCoefficients];
  return num_parameters();
}

void IdimLayout::PlaceFlightRows(int f, const Eigen::MatrixXd& wf, Eigen::Index first_row, Eigen::MatrixXd* w) const {
  for (int k = 0; k < kNumIdimColumns; ++k) w->block(first_row, SystemColumn(f, k), wf.rows(), 1) = wf.col(k);
}

namespace {

// Configurations, parameter names and each flight's body columns: per configuration the first
// moments of its labels in the order they first appear (one unlabelled set when the flights share
// it), then its inertia.
void LayOutColumns(const std::vector<ProcessedFlight>& flights, IdimSystem* system) {
  std::map<std::string, int> config_index;
  std::map<std::string, const Vehicle*> config_vehicle;
  for (const ProcessedFlight& f : flights) {
    auto [it, inserted] = config_index.emplace(f.vehicle.name, static_cast<int>(system->config_names.size()));
    if (inserted) {
      system->config_names.push_back(f.vehicle.name);
      config_vehicle[f.vehicle.name] = &f.vehicle;
    } else if (config_vehicle[f.vehicle.name]->mass_kg != f.vehicle.mass_kg) {
      throw Error("vehicle name '" + f.vehicle.name +
                  "' is used with two different masses; give each configuration its own name");
    }
    system->flight_config.push_back(it->second);
    system->flight_weight.push_back(f.weight);
    system->flight_source.push_back(f.source);
  }
  system->parameter_names.assign(kRotorCoefficientNames.begin(), kRotorCoefficientNames.end());
  system->flight_body_columns.resize(flights.size());
  for (int c = 0; c < static_cast<int>(system->config_names.size()); ++c) {
    std::map<std::string, int> label_column;  // first first-moment column of each label
    std::vector<size_t> members;
    for (size_t f = 0; f < flights.size(); ++f) {
      if (system->flight_config[f] != c) continue;
      members.push_back(f);
      auto [it, inserted] = label_column.emplace(flights[f].first_moment_label, system->num_parameters());
      if (inserted)
        for (int k = 0; k < 3; ++k) system->parameter_names.push_back(BodyParameterName(flights[f], k));
      for (int k = 0; k < 3; ++k) system->flight_body_columns[f][k] = it->second + k;
    }
    if (label_column.count("") && label_column.size() > 1)
      throw Error("configuration '" + system->config_names[c] +
                  "': some flights have their own first moment and others share one");
    const int inertia = system->num_parameters();
    for (int k = 3; k < kNumBodyParameters; ++k) {
      system->parameter_names.push_back(BodyParameterName(flights[members.front()], k));
      for (size_t f : members) system->flight_body_columns[f][k] = inertia + k - 3;
    }
  }
}

}  // namespace

IdimSystem BuildIdimSystem(const std::vector<ProcessedFlight>& flights) {
  if (flights.empty()) throw Error("no flights to identify from");
  IdimSystem system;
  LayOutColumns(flights, &system);
  const int p = system.num_parameters();
  int total_rows = 0;
  for (const ProcessedFlight& f : flights) total_rows += 6 * f.num_rows_samples();
  system.w = Eigen::MatrixXd::Zero(total_rows, p + 1);
  system.row_group.reserve(total_rows);
  system.row_sample.reserve(total_rows);
  int row = 0;
  for (int f = 0; f < static_cast<int>(flights.size()); ++f) {
    // Row sample by row sample into the system's columns: no flight-sized copy beside W.
    for (int r = 0; r < flights[f].num_rows_samples(); ++r) {
      const Eigen::Matrix<double, 6, kNumIdimColumns> rows = IdimRowsOfRowSample(flights[f], r);
      for (int k = 0; k < kNumIdimColumns; ++k)
        system.w.block<6, 1>(row + 6 * r, system.SystemColumn(f, k)) = rows.col(k);
    }
    for (int i = 0; i < 6 * flights[f].num_rows_samples(); ++i) {
      system.row_group.push_back(6 * f + i % 6);
      system.row_sample.push_back(i / 6);
    }
    row += 6 * flights[f].num_rows_samples();
    for (const Eigen::MatrixXd& cov : IdimNoiseCovariance(flights[f])) {
      Eigen::MatrixXd mapped = Eigen::MatrixXd::Zero(p + 1, p + 1);
      for (int a = 0; a < kNumIdimColumns; ++a)
        for (int b = 0; b < kNumIdimColumns; ++b)
          mapped(system.SystemColumn(f, a), system.SystemColumn(f, b)) += cov(a, b);
      system.group_noise_cov.push_back(mapped);
    }
  }
  return system;
}

void RelativeErrorSums::Add(const Eigen::Ref<const Eigen::MatrixXd>& w, const Eigen::VectorXd& chi_t) {
  for (Eigen::Index i = 0; i < w.rows(); ++i) {
    const double rho = w.row(i).dot(chi_t);
    const double rotor = w(i, 0) * chi_t[0] + w(i, 1) * chi_t[1];
    residual_sq[i % 6] += rho * rho;
    rotor_sq[i % 6] += rotor * rotor;
  }
}

void RelativeErrorSums::Add(const RelativeErrorSums& other) {
  for (int j = 0; j < 6; ++j) {
    residual_sq[j] += other.residual_sq[j];
    rotor_sq[j] += other.rotor_sq[j];
  }
}

bool PredictsWithProfiled(const TlsSolution& solution, int k) {
  return k >= kNumRotorCoefficients && solution.Profiled(k) && solution.profiled_chi[k] > 0.0;
}

Eigen::VectorXd PredictionChi(const TlsSolution& solution) {
  Eigen::VectorXd chi = solution.chi;
  for (Eigen::Index k = 0; k < chi.size(); ++k) {
    if (solution.PredictsWithinRange(static_cast<int>(k)))
      chi[k] = solution.within_range_chi[k];
    else if (PredictsWithProfiled(solution, static_cast<int>(k)))
      chi[k] = solution.profiled_chi[k];
  }
  return chi;
}

std::vector<std::optional<double>> RelativeErrorSums::Pct() const {
  std::vector<std::optional<double>> out(6);
  for (int j = 0; j < 6; ++j)
    if (rotor_sq[j] > 0.0) out[j] = 100.0 * std::sqrt(residual_sq[j] / rotor_sq[j]);
  return out;
}

std::vector<std::optional<double>> RelativeErrorPct(const Eigen::MatrixXd& w, const Eigen::VectorXd& chi_t) {
  RelativeErrorSums sums;
  sums.Add(w, chi_t);
  return sums.Pct();
}

namespace {

// Below this, the unit solution vector's last entry cannot fix the scale.
constexpr double kScaleLost = 1e-3;

// Result of one solve on a fixed set of free columns.
struct CoreSolve {
  Eigen::VectorXd chi_t;       // over `columns` (free parameters then the last column), last = 1
  Eigen::MatrixXd covariance;  // over the free parameters
  Eigen::VectorXd row_weight;
  Eigen::MatrixXd metric;  // over `columns`
  Eigen::VectorXd singular_values;
  double sigma_w = 0.0;
  double scale_entry = 1.0;
  // Unit solution vector (equilibrated columns for noise-aware, raw for paper): when its last entry
  // vanishes, its large entries name the parameters that are confounded with each other.
  Eigen::VectorXd direction;
  int iterations = 0;
};

Eigen::MatrixXd SelectColumns(const Eigen::MatrixXd& w, const std::vector<int>& columns) {
  Eigen::MatrixXd out(w.rows(), columns.size());
  for (size_t k = 0; k < columns.size(); ++k) out.col(k) = w.col(columns[k]);
  return out;
}

Eigen::MatrixXd SelectBlock(const Eigen::MatrixXd& m, const std::vector<int>& columns) {
  Eigen::MatrixXd out(columns.size(), columns.size());
  for (size_t a = 0; a < columns.size(); ++a)
    for (size_t b = 0; b < columns.size(); ++b) out(a, b) = m(columns[a], columns[b]);
  return out;
}

// Smallest generalized eigenvector of (R^T R, metric): minimises |R x|^2 / (x^T metric x); scaled so
// that its last entry is 1. `scale_entry` measures how well the last entry is determined.
// `effective_metric` receives the metric actually used (with the small regularisation), so that
// the refinement minimises exactly the same criterion.
Eigen::VectorXd GeneralizedTls(const Eigen::MatrixXd& r, const Eigen::MatrixXd& metric, double* scale_entry,
                               Eigen::VectorXd* singular_values, Eigen::MatrixXd* effective_metric = nullptr,
                               Eigen::VectorXd* direction = nullptr) {
  const int n = static_cast<int>(r.cols());
  // Equilibrate columns so that the conditioning of R does not depend on units.
  const Eigen::VectorXd norms = r.colwise().norm().transpose().cwiseMax(1e-300);
  const Eigen::MatrixXd r_eq = r * norms.cwiseInverse().asDiagonal();
  Eigen::MatrixXd metric_eq = norms.cwiseInverse().asDiagonal() * metric * norms.cwiseInverse().asDiagonal();
  // A vanishing metric (noise-free data) falls back to TLS on equilibrated columns.
  double mean_diagonal = 0.0;
  for (int k = 0; k < n; ++k) mean_diagonal += metric_eq(k, k) / n;
  for (int k = 0; k < n; ++k) metric_eq(k, k) += 1e-9 * std::max(mean_diagonal, 1.0) + 1e-12;
  // x^T R^T R x / x^T G x with G = L L^T: y = L^T x, minimise |R L^-T y|^2 / |y|^2 -> SVD.
  if (effective_metric) *effective_metric = norms.asDiagonal() * metric_eq * norms.asDiagonal();
  const Eigen::LLT<Eigen::MatrixXd> llt(metric_eq);
  const Eigen::MatrixXd l = llt.matrixL();
  const Eigen::MatrixXd b = l.triangularView<Eigen::Lower>().solve(r_eq.transpose()).transpose();  // R L^-T
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(b, Eigen::ComputeFullV);
  if (singular_values) *singular_values = svd.singularValues();
  const Eigen::VectorXd y = svd.matrixV().col(n - 1);
  Eigen::VectorXd x_eq = l.transpose().triangularView<Eigen::Upper>().solve(y);
  x_eq.normalize();
  *scale_entry = std::abs(x_eq[n - 1]);
  if (direction) *direction = x_eq;
  Eigen::VectorXd x = norms.cwiseInverse().asDiagonal() * x_eq;
  return x / x[n - 1];
}

std::vector<int> ComponentCounts(const IdimSystem& system) {
  std::vector<int> counts(system.num_groups(), 0);
  for (int g : system.row_group) ++counts[g];
  return counts;
}

// R factors of each group's rows (W_g = Q_g R_g) over all columns, computed once: every re-weighting
// and column subset afterwards works exactly on these small matrices, since the weights are constant
// within a group and ||W_g x|| = ||R_g x||. This keeps a 1 h log's many fixed-point iterations and
// essential-parameter steps from re-factoring a million-row matrix.
struct GroupFactors {
  std::vector<Eigen::MatrixXd> r;
  std::vector<int> counts;
};

GroupFactors FactorGroups(const IdimSystem& system) {
  GroupFactors out;
  out.counts = ComponentCounts(system);
  const int groups = system.num_groups(), cols = static_cast<int>(system.w.cols());
  std::vector<std::vector<int>> rows_of(groups);
  for (int i = 0; i < static_cast<int>(system.row_group.size()); ++i) rows_of[system.row_group[i]].push_back(i);
  out.r.resize(groups);
  for (int g = 0; g < groups; ++g) {
    Eigen::MatrixXd gathered(rows_of[g].size(), cols);
    for (size_t k = 0; k < rows_of[g].size(); ++k) gathered.row(k) = system.w.row(rows_of[g][k]);
    if (gathered.rows() >= cols) {
      Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(gathered);
      out.r[g] = qr.matrixQR().topRows(cols).triangularView<Eigen::Upper>();
    } else {
      out.r[g] = gathered;
    }
  }
  return out;
}

// R (n x n) of the row-weighted matrix restricted to `columns`: the QR of the stacked
// sqrt(weight_g) R_g[:, columns].
Eigen::MatrixXd StackedR(const GroupFactors& factors, const std::vector<int>& columns,
                         const std::vector<double>& group_weight) {
  const int n = static_cast<int>(columns.size());
  int rows = 0;
  for (const Eigen::MatrixXd& r : factors.r) rows += static_cast<int>(r.rows());
  Eigen::MatrixXd stacked(std::max(rows, n), n);
  stacked.setZero();
  int row = 0;
  for (size_t g = 0; g < factors.r.size(); ++g) {
    const double scale = std::sqrt(group_weight[g]);
    for (int k = 0; k < n; ++k) stacked.block(row, k, factors.r[g].rows(), 1) = scale * factors.r[g].col(columns[k]);
    row += static_cast<int>(factors.r[g].rows());
  }
  Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(stacked);
  return qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
}

// ||W_g[:, columns] x||^2 per group.
std::vector<double> GroupSquaredNorms(const GroupFactors& factors, const std::vector<int>& columns,
                                      const Eigen::VectorXd& x) {
  Eigen::VectorXd full = Eigen::VectorXd::Zero(factors.r.empty() ? 0 : factors.r[0].cols());
  for (size_t k = 0; k < columns.size(); ++k) full[columns[k]] = x[k];
  std::vector<double> out(factors.r.size());
  for (size_t g = 0; g < factors.r.size(); ++g) out[g] = (factors.r[g] * full).squaredNorm();
  return out;
}

Eigen::VectorXd RowWeights(const IdimSystem& system, const std::vector<double>& group_weight) {
  Eigen::VectorXd weight(system.row_group.size());
  for (size_t i = 0; i < system.row_group.size(); ++i) weight[i] = group_weight[system.row_group[i]];
  return weight;
}

// The paper: TLS by SVD, weighted by component, statistics of eq. (18)-(22).
CoreSolve SolvePaper(const IdimSystem& system, const GroupFactors& factors, const std::vector<int>& columns,
                     const TlsOptions& options) {
  const int rows = static_cast<int>(system.w.rows()), n = static_cast<int>(columns.size());
  const int groups = system.num_groups();
  std::vector<double> group_weight(groups);
  for (int g = 0; g < groups; ++g) group_weight[g] = std::pow(system.flight_weight[IdimSystem::Flight(g)], 2);
  CoreSolve out;
  auto solve = [&]() {
    const Eigen::MatrixXd r = StackedR(factors, columns, group_weight);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd v = svd.matrixV().col(n - 1);
    out.scale_entry = std::abs(v[n - 1]);
    out.direction = v;
    out.chi_t = v / v[n - 1];
    out.singular_values = svd.singularValues();
    return std::make_pair(r, svd);
  };
  auto [r, svd] = solve();
  out.iterations = 1;
  if (options.weight_by_component) {
    const std::vector<double> sum_sq = GroupSquaredNorms(factors, columns, out.chi_t);
    for (int g = 0; g < groups; ++g) {
      // A group without error (noise-free data) keeps its weight instead of an infinite one.
      const double scale = factors.r[g].norm() / std::sqrt(std::max(1, factors.counts[g]));
      const double sigma = std::sqrt(sum_sq[g] / std::max(1, factors.counts[g] - 1));
      if (sigma > 1e-9 * scale) group_weight[g] /= sigma * sigma;
    }
    std::tie(r, svd) = solve();
    out.iterations = 2;
  }
  // Statistics (eq. 19-21): sigma_W, and the covariance from the nearest rank-deficient matrix.
  const double s_min = svd.singularValues()[n - 1];
  out.sigma_w = s_min / std::sqrt(std::max(1, rows - n));
  const Eigen::MatrixXd r_bar = r - s_min * svd.matrixU().col(n - 1) * svd.matrixV().col(n - 1).transpose();
  const Eigen::MatrixXd w_bar = r_bar.leftCols(n - 1);
  const double chi_sq = out.chi_t.head(n - 1).squaredNorm();
  out.covariance = out.sigma_w * out.sigma_w * (1.0 + chi_sq) *
                   (w_bar.transpose() * w_bar).ldlt().solve(Eigen::MatrixXd::Identity(n - 1, n - 1));
  out.row_weight = RowWeights(system, group_weight);
  out.metric = Eigen::MatrixXd::Identity(n, n);
  return out;
}

// Newey-West (Bartlett) lag: twice the first lag at which the whitened residual's autocorrelation
// falls below 0.1 (searched up to 200 samples), so the covariance accounts for the filter's and the
// model error's memory.
int AutocorrelationLag(const Eigen::VectorXd& r, const IdimSystem& system) {
  constexpr Eigen::Index kMaxLag = 200;
  Eigen::Index lag_max = 0;
  for (int j = 0; j < 6; ++j) {
    std::vector<double> series;
    for (Eigen::Index i = j; i < r.size(); i += 6)
      if (IdimSystem::Flight(system.row_group[i]) == 0) series.push_back(r[i]);
    const Eigen::Index n = static_cast<Eigen::Index>(series.size());
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(series.data(), n);
    if (n < 20 || !(x.squaredNorm() > 0.0)) continue;
    lag_max = std::max(lag_max, FirstLagBelow({x}, 0.1, std::min(n / 10, kMaxLag)));
  }
  return static_cast<int>(std::max<Eigen::Index>(2, 2 * lag_max));
}

// Bound on how far the fixed point may lower a group's residual variance below the full model's
// unweighted start.
constexpr double kMaxVarianceDrop = 0.1;

// rotorid's default: errors-in-variables TLS with the noise metric, iterated to a fixed point of the
// row weights and equation-error variances; sandwich covariance robust to autocorrelation.
CoreSolve SolveNoiseAware(const IdimSystem& system, const GroupFactors& factors, const std::vector<int>& columns,
                          const TlsOptions& options, std::vector<double>* start_var) {
  const int rows = static_cast<int>(system.w.rows()), n = static_cast<int>(columns.size());
  const int groups = system.num_groups();
  const std::vector<int>& counts = factors.counts;
  std::vector<Eigen::MatrixXd> group_cov(groups);
  for (int g = 0; g < groups; ++g) group_cov[g] = SelectBlock(system.group_noise_cov[g], columns);

  CoreSolve out;
  // Start: TLS on equilibrated columns with unit row weights.
  std::vector<double> group_weight(groups, 1.0);
  {
    const Eigen::MatrixXd r = StackedR(factors, columns, group_weight);
    const Eigen::VectorXd norms = r.colwise().norm().transpose().cwiseMax(1e-300);
    out.chi_t = GeneralizedTls(r, norms.cwiseAbs2().asDiagonal(), &out.scale_entry, &out.singular_values, nullptr,
                               &out.direction);
  }
  Eigen::MatrixXd metric = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd r;
  for (int it = 1; it <= options.max_iterations; ++it) {
    const std::vector<double> sum_sq = GroupSquaredNorms(factors, columns, out.chi_t);
    metric.setZero();
    for (int g = 0; g < groups; ++g) {
      if (counts[g] == 0) continue;
      const double rotor_sq = std::pow(out.chi_t[0], 2) * factors.r[g].col(columns[0]).squaredNorm();
      const double noise_var = out.chi_t.dot(group_cov[g] * out.chi_t) / counts[g];
      const double residual_var = sum_sq[g] / counts[g];
      const double floor = 1e-24 * (rotor_sq / counts[g]) + 1e-300;
      if ((*start_var)[g] < 0.0) (*start_var)[g] = std::max(residual_var, noise_var);
      // A group can shrink its residual to nothing by driving the parameters it alone determines to
      // zero (yaw on a weakly excited flight: kd, I_zz), or once they are discarded, by equating the
      // inertias of its last cross terms; its weight would then grow without bound (the degenerate
      // likelihood of per-group variances). A real fit does not lower a group's variance tenfold
      // from the unweighted start of the full model, so that bounds it.
      const double total_var = std::max({residual_var, noise_var, floor, kMaxVarianceDrop * (*start_var)[g]});
      const double equation_var = total_var - noise_var;
      const double user = system.flight_weight[IdimSystem::Flight(g)];
      group_weight[g] = user * user / total_var;
      metric += group_weight[g] * group_cov[g];
      metric(n - 1, n - 1) += group_weight[g] * counts[g] * equation_var;
    }
    r = StackedR(factors, columns, group_weight);
    const Eigen::VectorXd previous = out.chi_t;
    out.chi_t = GeneralizedTls(r, metric, &out.scale_entry, &out.singular_values, &out.metric, &out.direction);
    out.iterations = it;
    const double change =
        ((out.chi_t - previous).cwiseAbs().array() / (previous.cwiseAbs().array() + 1e-300)).maxCoeff();
    if (!(change > 1e-10)) break;
  }
  out.row_weight = RowWeights(system, group_weight);
  metric = out.metric;

  // Whitened residuals r_i = sqrt(lambda_i) (w_i . chi_t) / d, d^2 = chi_t^T N chi_t / rows, with
  // Jacobian J_i = sqrt(lambda_i) w_i / d - r_i c over the free parameters, c = (N chi_t) / (rows d^2);
  // sandwich covariance H^-1 S H^-1 with S by Newey-West over samples. H follows from R exactly;
  // the scores are streamed sample by sample.
  const double d_sq = std::max(out.chi_t.dot(metric * out.chi_t) / rows, 1e-300);
  const double d = std::sqrt(d_sq);
  const Eigen::VectorXd c = (metric * out.chi_t).head(n - 1) / (rows * d_sq);
  Eigen::VectorXd chi_full = Eigen::VectorXd::Zero(system.w.cols());
  for (int k = 0; k < n; ++k) chi_full[columns[k]] = out.chi_t[k];
  const Eigen::VectorXd sqrt_weight = out.row_weight.cwiseSqrt();
  const Eigen::VectorXd resid = sqrt_weight.cwiseProduct(system.w * chi_full) / d;
  out.sigma_w = std::sqrt(resid.squaredNorm() / std::max(1, rows - (n - 1)));
  const Eigen::MatrixXd gram = (r.transpose() * r).topLeftCorner(n - 1, n - 1);
  const Eigen::VectorXd u = (r.transpose() * (r * out.chi_t)).head(n - 1) / d;
  const Eigen::MatrixXd h =
      gram / d_sq - (u * c.transpose() + c * u.transpose()) / d + resid.squaredNorm() * c * c.transpose();
  const int lag = AutocorrelationLag(resid, system);
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(n - 1, n - 1);
  int begin = 0;
  while (begin < rows) {
    const int flight = IdimSystem::Flight(system.row_group[begin]);
    int end = begin;
    while (end < rows && IdimSystem::Flight(system.row_group[end]) == flight) ++end;
    const int samples = (end - begin) / 6;
    Eigen::MatrixXd scores = Eigen::MatrixXd::Zero(n - 1, samples);
    for (int t = 0; t < samples; ++t) {
      double r_sq = 0.0;
      for (int i = begin + 6 * t; i < begin + 6 * t + 6; ++i) {
        const double weighted = sqrt_weight[i] * resid[i] / d;
        for (int k = 0; k < n - 1; ++k) scores(k, t) += weighted * system.w(i, columns[k]);
        r_sq += resid[i] * resid[i];
      }
      scores.col(t) -= r_sq * c;
    }
    s += BartlettLongRunSum(scores, lag);
    begin = end;
  }
  const Eigen::MatrixXd h_inv = h.ldlt().solve(Eigen::MatrixXd::Identity(n - 1, n - 1));
  out.covariance = h_inv * s * h_inv;
  return out;
}

}  // namespace

std::vector<int> CriterionColumns(const TlsSolution& solution) {
  std::vector<int> columns;
  for (int k = 0; k < static_cast<int>(solution.chi.size()); ++k)
    if (solution.essential[k] || solution.Profiled(k)) columns.push_back(k);
  columns.push_back(static_cast<int>(solution.chi.size()));
  return columns;
}

double MinimumTlsCriterionOfFactor(const Eigen::MatrixXd& r, const TlsSolution& solution) {
  const Eigen::MatrixXd metric = SelectBlock(solution.column_metric, CriterionColumns(solution));
  // Rayleigh quotient minimum = smallest generalized eigenvalue; evaluate it at its minimiser.
  double scale_entry = 0.0;
  Eigen::MatrixXd used_metric;
  const Eigen::VectorXd x = GeneralizedTls(r, metric, &scale_entry, nullptr, &used_metric);
  const double denominator = x.dot(metric * x);
  return denominator > 0.0 ? (r * x).squaredNorm() / denominator : 0.0;
}

double MinimumTlsCriterionOfColumns(Eigen::MatrixXd columns, const TlsSolution& solution) {
  columns.array().colwise() *= solution.row_weight.cwiseSqrt().array();
  const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(columns);
  const Eigen::Index n = columns.cols();
  return MinimumTlsCriterionOfFactor(qr.matrixQR().topRows(n).triangularView<Eigen::Upper>(), solution);
}

double MinimumTlsCriterion(const Eigen::MatrixXd& w, const TlsSolution& solution) {
  return MinimumTlsCriterionOfColumns(SelectColumns(w, CriterionColumns(solution)), solution);
}

namespace {

// The parameters SolveIdim estimates, before the selection: every one but options.fixed_zero.
std::vector<int> FreeParameters(const IdimSystem& system, const TlsOptions& options) {
  const int p = system.num_parameters();
  std::vector<int> free;
  for (int k = 0; k < p; ++k) {
    const bool fixed = std::find(options.fixed_zero.begin(), options.fixed_zero.end(), system.parameter_names[k]) !=
                       options.fixed_zero.end();
    if (!fixed) free.push_back(k);
  }
  for (const std::string& name : options.fixed_zero)
    if (std::find(system.parameter_names.begin(), system.parameter_names.end(), name) == system.parameter_names.end())
      throw Error("cannot fix unknown parameter '" + name + "'");
  if (free.empty()) throw Error("every parameter is fixed; nothing to identify");
  if (system.w.rows() <= p + 1)
    throw Error("too few rows (" + std::to_string(system.w.rows()) + ") for " + std::to_string(p) + " parameters");
  return free;
}

// The essential-parameter selection's state: the free columns, those discarded but kept in the
// criterion (TlsSolution::profiled: a parameter whose physics excludes 0 is not held there, since its
// signal would stay in the rows and move the parameters whose columns correlate with it), and the
// discarded list.
struct Selection {
  std::vector<int> free;
  std::vector<int> profiled;
  std::vector<DiscardedParameter> discarded;

  bool IsProfiled(int column) const { return std::find(profiled.begin(), profiled.end(), column) != profiled.end(); }

  // Discards free[index_in_free]: profiled (noise-aware, positive by physics) or out of the criterion.
  void Discard(DiscardedParameter dropped, int index_in_free, TlsMethod method) {
    const bool profile = method == TlsMethod::kNoiseAware && PositiveByPhysics(dropped.name);
    if (profile) dropped.reason += "; estimated beside the others, not held at 0 (its physics excludes 0)";
    discarded.push_back(dropped);
    if (profile)
      profiled.push_back(free[static_cast<size_t>(index_in_free)]);
    else
      free.erase(free.begin() + index_in_free);
  }

  // An exact dependency among parameters (a symmetric quad's kd and I_zz): drops the one with the
  // largest share of the null direction, naming its partner.
  void DropConfounded(const CoreSolve& core, const IdimSystem& system) {
    const int nf = static_cast<int>(free.size());
    int first = 0, second = -1;
    for (int k = 1; k < nf; ++k)
      if (std::abs(core.direction[k]) > std::abs(core.direction[first])) first = k;
    for (int k = 0; k < nf; ++k)
      if (k != first && (second < 0 || std::abs(core.direction[k]) > std::abs(core.direction[second]))) second = k;
    DiscardedParameter dropped;
    dropped.name = system.parameter_names[free[first]];
    dropped.rel_std_pct = std::numeric_limits<double>::infinity();
    dropped.std = std::numeric_limits<double>::infinity();
    dropped.most_correlated = second >= 0 ? system.parameter_names[free[second]] : "";
    dropped.correlation = 1.0;
    dropped.reason =
        "not identifiable: only a combination with " + dropped.most_correlated + " is determined by these flights";
    if (IsProfiled(free[first])) {  // discarded before for its %sigma: now it leaves the criterion
      profiled.erase(std::find(profiled.begin(), profiled.end(), free[first]));
      discarded.erase(std::find_if(discarded.begin(), discarded.end(),
                                   [&](const DiscardedParameter& d) { return d.name == dropped.name; }));
    }
    discarded.push_back(dropped);
    free.erase(free.begin() + first);
  }

  // Drops the worst free parameter by the selection rule (EssentialSelectionDrops); false when none.
  bool DropWorst(const CoreSolve& core, const IdimSystem& system, const TlsOptions& options) {
    const int nf = static_cast<int>(free.size());
    Eigen::VectorXd rel(nf);
    for (int k = 0; k < nf; ++k)
      rel[k] = IsProfiled(free[k]) ? -1.0
                                   : 100.0 * std::sqrt(std::max(core.covariance(k, k), 0.0)) /
                                         std::max(std::abs(core.chi_t[k]), 1e-300);
    const int worst = EssentialSelectionDrops(rel, options);
    if (worst < 0) return false;
    Discard(DiscardedOf(system.parameter_names, free, core.chi_t, core.covariance, worst, rel[worst]), worst,
            options.method);
    return true;
  }
};

// The solution of the selection's last solve.
TlsSolution SolutionOf(const IdimSystem& system, const TlsOptions& options, const Selection& selection,
                       const CoreSolve& core) {
  const int p = system.num_parameters();
  const std::vector<int>& free = selection.free;
  const int nf = static_cast<int>(free.size());
  TlsSolution solution;
  solution.method = options.method;
  solution.discarded = selection.discarded;
  solution.chi = Eigen::VectorXd::Zero(p);
  solution.essential.assign(p, false);
  solution.covariance = Eigen::MatrixXd::Zero(p, p);
  solution.profiled.assign(p, false);
  solution.profiled_chi = Eigen::VectorXd::Zero(p);
  solution.profiled_std = Eigen::VectorXd::Zero(p);
  for (int a = 0; a < nf; ++a) {
    if (selection.IsProfiled(free[a])) {
      solution.profiled[free[a]] = true;
      solution.profiled_chi[free[a]] = core.chi_t[a];
      solution.profiled_std[free[a]] = std::sqrt(std::max(core.covariance(a, a), 0.0));
      continue;
    }
    solution.chi[free[a]] = core.chi_t[a];
    solution.essential[free[a]] = true;
    for (int b = 0; b < nf; ++b)
      if (!selection.IsProfiled(free[b])) solution.covariance(free[a], free[b]) = core.covariance(a, b);
  }
  SetStdFromCovariance(system.parameter_names, &solution);
  solution.row_weight = core.row_weight;
  solution.column_metric = Eigen::MatrixXd::Zero(p + 1, p + 1);
  std::vector<int> columns = free;
  columns.push_back(p);
  for (int a = 0; a <= nf; ++a)
    for (int b = 0; b <= nf; ++b) solution.column_metric(columns[a], columns[b]) = core.metric(a, b);
  solution.sigma_w = core.sigma_w;
  solution.singular_values = core.singular_values;
  solution.scale_entry = core.scale_entry;
  solution.iterations = core.iterations;
  return solution;
}

// Is the result usable? The scale and kt; a negative kd is a warning.
void JudgeUsable(TlsSolution* solution) {
  auto fail = [&](const std::string& message) {
    solution->usable = false;
    if (solution->message.empty()) solution->message = message;
  };
  if (solution->scale_entry < kScaleLost) {
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.1e", solution->scale_entry);
    fail("scale lost: the solution vector's last entry is " + std::string(buffer) +
         " (near 0), so these flights cannot fix the parameters' scale; typical causes are a systematic force "
         "error (accelerometer bias, IMU misalignment) or a thrust that barely varies");
  }
  if (!solution->essential[0] || !(solution->chi[0] > 0.0))
    fail("kt could not be identified (value " + std::to_string(solution->chi[0]) +
         "); the flights do not excite the thrust enough or the scale is lost");
  if (solution->essential[1] && !(solution->chi[1] > 0.0))
    solution->warnings.push_back("kd came out negative: check the rotors' spin directions in the vehicle file");
}

}  // namespace

int EssentialSelectionDrops(const Eigen::VectorXd& rel_std_pct, const TlsOptions& options) {
  if (!options.select_essential) return -1;
  int worst = -1, candidates = 0;
  double smallest = std::numeric_limits<double>::infinity();
  for (Eigen::Index k = 0; k < rel_std_pct.size(); ++k) {
    if (rel_std_pct[k] < 0.0) continue;
    ++candidates;
    smallest = std::min(smallest, rel_std_pct[k]);
    if (worst < 0 || rel_std_pct[k] > rel_std_pct[worst]) worst = static_cast<int>(k);
  }
  if (worst < 0 || rel_std_pct.size() <= 1) return -1;
  const bool keep = options.method == TlsMethod::kPaper ? rel_std_pct[worst] / smallest < options.r_sigma
                                                        : rel_std_pct[worst] <= options.max_rel_std_pct;
  return keep ? -1 : worst;
}

DiscardedParameter DiscardedOf(const std::vector<std::string>& names, const std::vector<int>& columns,
                               const Eigen::VectorXd& chi, const Eigen::MatrixXd& covariance, int dropped,
                               double rel_std_pct) {
  DiscardedParameter d;
  d.name = names[static_cast<size_t>(columns[static_cast<size_t>(dropped)])];
  d.rel_std_pct = rel_std_pct;
  d.reason = "its %sigma exceeds the limit";
  d.value = chi[dropped];
  d.std = std::sqrt(std::max(covariance(dropped, dropped), 0.0));
  for (int k = 0; k < static_cast<int>(columns.size()); ++k) {
    if (k == dropped) continue;
    const double denom = std::sqrt(covariance(k, k) * covariance(dropped, dropped));
    const double corr = denom > 0.0 ? covariance(k, dropped) / denom : 0.0;
    if (std::abs(corr) > std::abs(d.correlation)) {
      d.correlation = corr;
      d.most_correlated = names[static_cast<size_t>(columns[static_cast<size_t>(k)])];
    }
  }
  return d;
}

void SetStdFromCovariance(const std::vector<std::string>& names, TlsSolution* solution) {
  const Eigen::Index p = solution->covariance.rows();
  solution->std = solution->covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  solution->rel_std_pct = Eigen::VectorXd::Zero(p);
  for (Eigen::Index k = 0; k < p; ++k)
    if (solution->chi[k] != 0.0) solution->rel_std_pct[k] = 100.0 * solution->std[k] / std::abs(solution->chi[k]);
  // A discarded parameter keeps the %sigma it had when it was dropped (0 would read as exactly known);
  // its std stays 0 beside its value 0, and DiscardedParameter::std holds the one at the drop.
  for (const DiscardedParameter& d : solution->discarded) {
    const auto it = std::find(names.begin(), names.end(), d.name);
    if (it != names.end()) solution->rel_std_pct[it - names.begin()] = d.rel_std_pct;
  }
}

TlsSolution SolveIdim(const IdimSystem& system, const TlsOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  Selection selection;
  selection.free = FreeParameters(system, options);
  for (const std::string& name : options.discarded_from_start) {
    const auto it = std::find_if(selection.free.begin(), selection.free.end(),
                                 [&](int k) { return system.parameter_names[k] == name; });
    if (it == selection.free.end()) throw Error("cannot discard '" + name + "': not a free parameter of these flights");
    DiscardedParameter dropped;
    dropped.name = name;
    dropped.reason = "held discarded";
    selection.Discard(dropped, static_cast<int>(it - selection.free.begin()), options.method);
  }
  const GroupFactors factors = FactorGroups(system);
  // Per group, set by the first (full-model) noise-aware solve; -1 until then.
  std::vector<double> start_var(system.num_groups(), -1.0);
  CoreSolve core;
  while (true) {
    std::vector<int> columns = selection.free;
    columns.push_back(system.num_parameters());
    core = options.method == TlsMethod::kPaper ? SolvePaper(system, factors, columns, options)
                                               : SolveNoiseAware(system, factors, columns, options, &start_var);
    if (!options.select_essential || selection.free.size() <= 1) break;
    if (core.scale_entry < kScaleLost) {
      selection.DropConfounded(core, system);
      continue;
    }
    if (!selection.DropWorst(core, system, options)) break;
  }
  TlsSolution solution = SolutionOf(system, options, selection, core);
  JudgeUsable(&solution);
  return solution;
}

}  // namespace rotorid

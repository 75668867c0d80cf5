#include "rotorid/refine/refine.h"

#include <ceres/ceres.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>

#include "refine/grid_search.h"
#include "refine/idim_residual.h"
#include "rotorid/core/error.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/refine/effect_model.h"

namespace rotorid {

std::string RefineOptions::Validate() const {
  if (robust_loss != "none" && robust_loss != "huber" && robust_loss != "cauchy")
    return "robust loss must be none, huber or cauchy, got '" + robust_loss + "'";
  if (!(robust_scale > 0.0)) return "robust loss scale must be positive";
  if (criterion != "anchored" && criterion != "tls") return "criterion must be anchored or tls, got '" + criterion + "'";
  if (!(delay_search_max_s > delay_search_min_s)) return "delay search range is empty";
  if (!(delay_search_step_s > 0.0)) return "delay search step must be positive";
  if (max_iterations < 1) return "max_iterations must be at least 1";
  for (EffectKind kind : AllEffects())
    if (kind->info().lower_bound == 0.0 && (initial.Get(kind).array() < 0.0).any())
      return "initial " + kind->parameter_name() + " must not be negative";
  if (num_threads < 1) return "num_threads must be at least 1";
  return {};
}

bool RefineOptions::Enabled(EffectKind kind) const {
  return std::find(effects.begin(), effects.end(), kind) != effects.end();
}

std::map<std::string, double> NamedParameters(const IdimSystem& system, const Eigen::VectorXd& chi) {
  std::map<std::string, double> values;
  for (int k = 0; k < system.num_parameters(); ++k) values[system.parameter_names[k]] = chi[k];
  return values;
}

std::vector<std::optional<double>> RelativeErrorWithEffects(const std::vector<ProcessedFlight>& flights,
                                                            const std::map<std::string, double>& parameters,
                                                            const Effects& effects) {
  std::vector<double> residual_sq(6, 0.0), rotor_sq(6, 0.0);
  for (const ProcessedFlight& f : flights) {
    const Eigen::MatrixXd w = BuildIdimMatrixWithEffects(f, effects);
    const Eigen::VectorXd chi_t = FlightChiT(f.vehicle, parameters);
    for (Eigen::Index i = 0; i < w.rows(); ++i) {
      const double rho = w.row(i).dot(chi_t), rotor = w(i, 0) * chi_t[0] + w(i, 1) * chi_t[1];
      residual_sq[i % 6] += rho * rho;
      rotor_sq[i % 6] += rotor * rotor;
    }
  }
  std::vector<std::optional<double>> out(6);
  for (int j = 0; j < 6; ++j)
    if (rotor_sq[j] > 0.0) out[j] = 100.0 * std::sqrt(residual_sq[j] / rotor_sq[j]);
  return out;
}

namespace {

// System rows of all flights with the effects applied, in the layout of the linear system.
Eigen::MatrixXd SystemRowsWithEffects(const IdentificationResult& linear, const Effects& effects) {
  const IdimSystem& system = linear.system;
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(system.w.rows(), system.w.cols());
  const int p = system.num_parameters();
  int row = 0;
  for (int f = 0; f < system.num_flights(); ++f) {
    const Eigen::MatrixXd wf = BuildIdimMatrixWithEffects(linear.flights[f], effects);
    const int c0 = IdimSystem::ConfigColumn(system.flight_config[f]);
    w.block(row, 0, wf.rows(), 2) = wf.leftCols(2);
    w.block(row, c0, wf.rows(), kNumBodyParameters) = wf.middleCols(2, kNumBodyParameters);
    w.block(row, p, wf.rows(), 1) = wf.rightCols(1);
    row += static_cast<int>(wf.rows());
  }
  return w;
}

}  // namespace

double EffectCriterion(const IdentificationResult& linear, const Effects& effects) {
  return MinimumTlsCriterion(SystemRowsWithEffects(linear, effects), linear.solution);
}

namespace {

using internal::CriterionContext;
using internal::IdimResidualBlock;
using internal::RotorSignalCache;

constexpr int kRowSamplesPerBlock = 64;

std::string TerminationName(ceres::TerminationType type) {
  switch (type) {
    case ceres::CONVERGENCE:
      return "convergence";
    case ceres::NO_CONVERGENCE:
      return "no convergence (iteration limit)";
    case ceres::FAILURE:
      return "failure";
    case ceres::USER_SUCCESS:
      return "user success";
    case ceres::USER_FAILURE:
      return "user failure";
  }
  return "unknown";
}

// Variance inflation of a mean over autocorrelated residuals: 1 + 2 sum_l (1 - l/(L+1)) rho_l,
// averaged over the wrench components (Bartlett window, lag as in the TLS statistics).
double AutocorrelationFactor(const Eigen::VectorXd& residuals) {
  double factor_sum = 0.0;
  int components = 0;
  for (int c = 0; c < 6; ++c) {
    std::vector<double> x;
    for (Eigen::Index i = c; i < residuals.size(); i += 6) x.push_back(residuals[i]);
    const int n = static_cast<int>(x.size());
    double c0 = 0.0;
    for (double v : x) c0 += v * v;
    if (n < 20 || c0 <= 0.0) continue;
    int cut = 1;
    std::vector<double> rho(1, 1.0);
    for (; cut < std::min(n / 10, 200); ++cut) {
      double ck = 0.0;
      for (int t = 0; t + cut < n; ++t) ck += x[t] * x[t + cut];
      rho.push_back(ck / c0);
      if (ck / c0 < 0.1) break;
    }
    const int lag = std::min(2 * cut, n / 10);
    double factor = 1.0;
    for (int l = 1; l <= lag; ++l) {
      double ck = 0.0;
      for (int t = 0; t + l < n; ++t) ck += x[t] * x[t + l];
      factor += 2.0 * (1.0 - static_cast<double>(l) / (lag + 1)) * ck / c0;
    }
    factor_sum += std::max(factor, 1.0);
    ++components;
  }
  return components > 0 ? factor_sum / components : 1.0;
}

}  // namespace

namespace {

// The problem's Jacobian with respect to `blocks`, dense. Ceres returns it in tangent coordinates
// (chi's SubsetManifold drops the fixed entries), so a block with a manifold has its tangent size
// in columns.
Eigen::MatrixXd DenseJacobian(ceres::Problem* problem, const std::vector<const double*>& blocks) {
  ceres::Problem::EvaluateOptions evaluate;
  for (const double* b : blocks) evaluate.parameter_blocks.push_back(const_cast<double*>(b));
  ceres::CRSMatrix crs;
  problem->Evaluate(evaluate, nullptr, nullptr, nullptr, &crs);
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) jac(r, crs.cols[k]) = crs.values[k];
  return jac;
}

// The parameters taking part in the (numerical) null space of the Jacobian, in tangent
// coordinates with equilibrated columns: what the flights cannot tell apart.
std::vector<std::string> NullSpaceParameters(ceres::Problem* problem, const std::vector<const double*>& blocks,
                                             const IdimSystem& system, const std::vector<int>& free,
                                             const std::vector<std::string>& effect_labels) {
  // A column scaling makes the SVD see directions, not units.
  const Eigen::MatrixXd tangent_jac = DenseJacobian(problem, blocks);
  std::vector<std::string> labels;
  for (int k : free) labels.push_back(system.parameter_names[k]);
  labels.insert(labels.end(), effect_labels.begin(), effect_labels.end());
  CHECK_EQ(static_cast<Eigen::Index>(labels.size()), tangent_jac.cols());
  const Eigen::VectorXd norms = tangent_jac.colwise().norm().transpose().cwiseMax(1e-300);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(tangent_jac * norms.cwiseInverse().asDiagonal(), Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  std::vector<std::string> names;
  for (Eigen::Index j = 0; j < sv.size(); ++j) {
    if (sv[j] > 1e-7 * sv[0]) continue;
    const Eigen::VectorXd v = svd.matrixV().col(j);
    for (Eigen::Index k = 0; k < v.size(); ++k)
      if (std::abs(v[k]) > 0.2 && std::find(names.begin(), names.end(), labels[k]) == names.end())
        names.push_back(labels[k]);
  }
  return names;
}

// Effect coordinates that the discarded parameters (held at zero by the essential selection) would
// explain almost entirely: the value found for them rests on those parameters being zero. An IMU
// lever arm along the thrust axis, say, is exactly the first moment ms_z / m in the force rows, and
// a multirotor's specific force along z keeps ms_z out of the moment rows. Each entry names the
// coordinate, the parameter and the share of the coordinate's column that parameter's explains.
// A share of 0.8 is a variance inflation factor of 5, the usual mark of a harmful collinearity.
constexpr double kRestingOnDiscardedShare = 0.8;
struct RestingOnDiscarded {
  std::string coordinate, parameter;
  double explained = 0.0;
};
std::vector<RestingOnDiscarded> EffectsRestingOnDiscarded(ceres::Problem* problem, double* chi_block,
                                                          const std::vector<double*>& effect_blocks,
                                                          const IdimSystem& system, const std::vector<int>& fixed,
                                                          const std::vector<std::string>& effect_labels) {
  if (fixed.empty() || effect_blocks.empty()) return {};
  const int p = system.num_parameters();
  // Every chi column, the fixed ones included: drop the subset manifold for this evaluation.
  std::vector<const double*> blocks = {chi_block};
  blocks.insert(blocks.end(), effect_blocks.begin(), effect_blocks.end());
  problem->SetManifold(chi_block, nullptr);
  const Eigen::MatrixXd jac = DenseJacobian(problem, blocks);
  problem->SetManifold(chi_block, new ceres::SubsetManifold(p, fixed));
  CHECK_EQ(static_cast<Eigen::Index>(p + effect_labels.size()), jac.cols());
  Eigen::MatrixXd discarded(jac.rows(), static_cast<Eigen::Index>(fixed.size()));
  for (size_t k = 0; k < fixed.size(); ++k) {
    const double norm = jac.col(fixed[k]).norm();
    discarded.col(static_cast<Eigen::Index>(k)) = norm > 0.0 ? Eigen::VectorXd(jac.col(fixed[k]) / norm)
                                                             : Eigen::VectorXd::Zero(jac.rows());
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(discarded);
  std::vector<RestingOnDiscarded> found;
  for (size_t e = 0; e < effect_labels.size(); ++e) {
    const Eigen::VectorXd column = jac.col(p + static_cast<Eigen::Index>(e));
    const double norm = column.norm();
    if (norm == 0.0) continue;
    const Eigen::VectorXd unit = column / norm;
    const Eigen::VectorXd coefficients = qr.solve(unit);
    const double explained = 1.0 - (discarded * coefficients - unit).squaredNorm();
    if (explained < kRestingOnDiscardedShare) continue;
    Eigen::Index strongest = 0;
    coefficients.cwiseAbs().maxCoeff(&strongest);
    found.push_back({effect_labels[e], system.parameter_names[fixed[static_cast<size_t>(strongest)]], explained});
  }
  return found;
}

// Pins the sum of a zero-sum effect's values: their mean is a linear parameter's (a common thrust
// factor is kt's), so the rows cannot fix it and only the TLS normalisation pulls on it, weakly;
// 100 x the square root of the row count outweighs that pull (sums below 1e-6 on the flights
// tested) and keeps the problem well conditioned.
class ZeroSumResidual : public ceres::CostFunction {
 public:
  ZeroSumResidual(int size, double weight) : weight_(weight) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(size);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int size = parameter_block_sizes()[0];
    residuals[0] = weight_ * Eigen::Map<const Eigen::VectorXd>(parameters[0], size).sum();
    if (jacobians && jacobians[0]) std::fill(jacobians[0], jacobians[0] + size, weight_);
    return true;
  }

 private:
  double weight_;
};

// The unit a free effect's parameter block is in: effects whose realistic size is far below 1
// (coefficients of 1e-5) are solved in units of that size, so that their Jacobian columns are
// comparable with chi's scaled ones and ceres::Covariance sees a well-conditioned matrix; the others
// in SI units, as they always were.
double RefineScale(EffectKind kind) {
  const DrawRange& draw = kind->info().draw;
  const double typical = std::max(std::abs(draw.low), std::abs(draw.high)) * draw.to_si;
  return typical > 0.0 && typical < 1e-3 ? typical : 1.0;
}

// The bounds a refinement keeps an effect in: its physical range, or for a grid-searched effect
// the search range.
std::pair<double, double> RefineBounds(EffectKind kind, const RefineOptions& options) {
  if (kind->info().grid_searched) return {options.delay_search_min_s, options.delay_search_max_s};
  return {kind->info().lower_bound, kind->info().upper_bound};
}

// One Ceres pass: the rows of `linear`'s flights with effects, the criterion (lambda, N) of `tls`,
// started at tls.chi and `start`. Fills chi, effects, their covariance and the solver report.
RefineResult SolveEffects(const IdentificationResult& linear, const TlsSolution& tls, const Effects& start,
                          const RefineOptions& options) {
  const IdimSystem& system = linear.system;
  const int p = system.num_parameters();
  RefineResult result;
  result.enabled = options.effects;

  CriterionContext context;
  context.metric = tls.column_metric;
  context.total_rows = static_cast<double>(system.w.rows());
  context.num_parameters = p;
  context.chi_scale.resize(p);
  for (int k = 0; k < p; ++k) context.chi_scale[k] = std::max({std::abs(tls.chi[k]), tls.std[k], 1e-12});
  Eigen::VectorXd scaled_chi = tls.chi.cwiseQuotient(context.chi_scale);
  // One parameter block per enabled effect, in registry order; the others stay at their start.
  const Vehicle& vehicle = linear.flights.front().vehicle;
  internal::EffectBlocks effect_blocks;
  effect_blocks.fixed = start;
  for (EffectKind kind : AllEffects())
    if (options.Enabled(kind)) effect_blocks.free.push_back(kind);
  std::vector<Eigen::VectorXd> effect_values;
  for (EffectKind kind : effect_blocks.free) {
    effect_blocks.scale.push_back(RefineScale(kind));
    Eigen::VectorXd v = start.Get(kind);
    if (v.size() == 0) v = Eigen::VectorXd::Zero(kind->Dimension(vehicle));
    if (v.size() != kind->Dimension(vehicle))
      throw Error(kind->parameter_name() + " takes " + std::to_string(kind->Dimension(vehicle)) +
                  " value(s) for this vehicle, got " + std::to_string(v.size()));
    effect_values.push_back(v / effect_blocks.scale.back());
  }

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<std::unique_ptr<RotorSignalCache>> caches;
  std::vector<internal::RotorMomentAnchor> anchors;
  anchors.reserve(static_cast<size_t>(system.num_flights()));
  const Eigen::VectorXd sqrt_weight = tls.row_weight.cwiseSqrt();
  std::vector<double*> blocks_of_residual = {scaled_chi.data()};
  for (Eigen::VectorXd& v : effect_values) blocks_of_residual.push_back(v.data());
  int row = 0;
  for (int f = 0; f < system.num_flights(); ++f) {
    const ProcessedFlight& flight = linear.flights[f];
    const bool anchored = options.criterion == "anchored";
    if (anchored) anchors.push_back(internal::AnchorRotorMoments(flight, system, f, row, tls.chi));
    caches.push_back(std::make_unique<RotorSignalCache>(&flight, &effect_blocks, anchored ? &anchors.back() : nullptr));
    for (int first = 0; first < flight.num_rows_samples(); first += kRowSamplesPerBlock) {
      const int count = std::min(kRowSamplesPerBlock, flight.num_rows_samples() - first);
      ceres::LossFunction* loss = nullptr;
      if (options.robust_loss == "huber") loss = new ceres::HuberLoss(options.robust_scale);
      if (options.robust_loss == "cauchy") loss = new ceres::CauchyLoss(options.robust_scale);
      problem.AddResidualBlock(
          new IdimResidualBlock(&flight, caches.back().get(), &context, &effect_blocks, system.flight_config[f], first,
                                count, sqrt_weight.segment(row + 6 * first, 6 * count)),
          loss, blocks_of_residual);
    }
    row += 6 * flight.num_rows_samples();
  }
  // Discarded (non-essential) parameters stay at zero, as in the TLS step.
  std::vector<int> fixed, free;
  for (int k = 0; k < p; ++k) (tls.essential[k] ? free : fixed).push_back(k);
  if (free.empty()) {
    problem.SetParameterBlockConstant(scaled_chi.data());
  } else if (!fixed.empty()) {
    problem.SetManifold(scaled_chi.data(), new ceres::SubsetManifold(p, fixed));
  }
  for (size_t b = 0; b < effect_blocks.free.size(); ++b) {
    const auto [lower, upper] = RefineBounds(effect_blocks.free[b], options);
    for (Eigen::Index a = 0; a < effect_values[b].size(); ++a) {
      problem.SetParameterLowerBound(effect_values[b].data(), static_cast<int>(a), lower / effect_blocks.Scale(b));
      problem.SetParameterUpperBound(effect_values[b].data(), static_cast<int>(a), upper / effect_blocks.Scale(b));
    }
    if (effect_blocks.free[b]->info().zero_sum)
      problem.AddResidualBlock(
          new ZeroSumResidual(static_cast<int>(effect_values[b].size()), 100.0 * std::sqrt(context.total_rows)), nullptr,
          effect_values[b].data());
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-12;
  solver_options.gradient_tolerance = 1e-14;
  solver_options.parameter_tolerance = 1e-12;
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  const auto t0 = std::chrono::steady_clock::now();
  ceres::Solve(solver_options, &problem, &summary);
  result.solver.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result.solver.iterations = static_cast<int>(summary.iterations.size()) - 1;
  result.solver.initial_cost = summary.initial_cost;
  result.solver.final_cost = summary.final_cost;
  result.solver.termination = TerminationName(summary.termination_type);
  result.solver.message = summary.message;
  result.solver.full_report = summary.FullReport();
  if (!summary.IsSolutionUsable()) throw Error("refinement failed: " + summary.message);

  const Eigen::VectorXd chi = scaled_chi.cwiseProduct(context.chi_scale);
  result.effects = effect_blocks.At(blocks_of_residual.data(), vehicle);

  result.refined = tls;
  result.refined.chi = chi;
  result.refined.covariance.setZero();
  result.refined.std.setZero();
  result.refined.rel_std_pct.setZero();

  // Residuals at the solution, for the noise scale and the autocorrelation factor.
  std::vector<double> residual_values;
  double cost = 0.0;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, &residual_values, nullptr, nullptr);
  const Eigen::VectorXd residuals = Eigen::Map<const Eigen::VectorXd>(residual_values.data(), residual_values.size());
  result.autocorrelation_factor = AutocorrelationFactor(residuals);
  std::vector<std::string> effect_labels;
  std::vector<double*> effect_block_pointers;
  for (size_t b = 0; b < effect_blocks.free.size(); ++b) {
    const std::vector<std::string> labels = effect_blocks.free[b]->Labels(static_cast<int>(effect_values[b].size()));
    effect_labels.insert(effect_labels.end(), labels.begin(), labels.end());
    effect_block_pointers.push_back(effect_values[b].data());
  }
  // A report for people: fits that skip the covariance (diagnosis folds, ablation) skip it too.
  if (!free.empty() && options.compute_covariance)
    for (const RestingOnDiscarded& r :
         EffectsRestingOnDiscarded(&problem, scaled_chi.data(), effect_block_pointers, system, fixed, effect_labels)) {
      result.resting_on_discarded.push_back(r.coordinate + " ~ " + r.parameter);
      char share[32];
      std::snprintf(share, sizeof share, "%.1f %%", 100.0 * r.explained);
      result.warnings.push_back(r.coordinate + " is confounded with " + r.parameter +
                                ", which the essential selection holds at 0 (it explains " + share +
                                " of its effect on the rows): its value assumes " + r.parameter + " = 0");
    }

  if (options.compute_covariance) {
    std::vector<const double*> blocks;
    if (!free.empty()) blocks.push_back(scaled_chi.data());
    for (const Eigen::VectorXd& v : effect_values) blocks.push_back(v.data());
    std::vector<std::pair<const double*, const double*>> pairs;
    for (size_t a = 0; a < blocks.size(); ++a)
      for (size_t b = a; b < blocks.size(); ++b) pairs.emplace_back(blocks[a], blocks[b]);
    ceres::Covariance::Options covariance_options;
    covariance_options.algorithm_type = ceres::DENSE_SVD;
    covariance_options.null_space_rank = 0;
    ceres::Covariance covariance(covariance_options);
    // Whitened residuals have unit variance only if the noise model is right: scale by the
    // observed residual variance and by the autocorrelation factor.
    const double dof = std::max(1.0, static_cast<double>(residuals.size()) - problem.NumParameters());
    const double scale = std::max(2.0 * cost / dof, 1e-300) * result.autocorrelation_factor;
    if (!blocks.empty() && covariance.Compute(pairs, &problem)) {
      int dim = 0;
      for (const double* b : blocks) dim += problem.ParameterBlockTangentSize(b);
      Eigen::MatrixXd full(dim, dim);
      covariance.GetCovarianceMatrixInTangentSpace(blocks, full.data());
      full *= scale;
      result.has_covariance = true;
      const int offset = static_cast<int>(free.size());
      for (int a = 0; a < offset; ++a)
        for (int b = 0; b < offset; ++b)
          result.refined.covariance(free[a], free[b]) =
              full(a, b) * context.chi_scale[free[a]] * context.chi_scale[free[b]];
      const int effect_dim = dim - offset;
      const Eigen::MatrixXd effect_cov = full.block(offset, offset, effect_dim, effect_dim);
      int e = 0;
      for (size_t b = 0; b < effect_blocks.free.size(); ++b) {
        const Eigen::Index size = effect_values[b].size();
        result.effects_std.Set(effect_blocks.free[b], effect_blocks.Scale(b) *
                                                          effect_cov.diagonal().segment(e, size).cwiseMax(0.0).cwiseSqrt());
        e += static_cast<int>(size);
      }
      result.effect_labels = effect_labels;
      const Eigen::VectorXd sd = effect_cov.diagonal().cwiseMax(1e-300).cwiseSqrt();
      result.effect_correlation = sd.cwiseInverse().asDiagonal() * effect_cov * sd.cwiseInverse().asDiagonal();
    } else if (!blocks.empty()) {
      result.rank_deficient = true;
      result.confounded = NullSpaceParameters(&problem, blocks, linear.system, free, effect_labels);
      std::string names;
      for (const std::string& n : result.confounded) names += (names.empty() ? "" : ", ") + n;
      result.warnings.push_back(
          "the refined parameters are not jointly identifiable from these flights (rank-deficient "
          "Jacobian); confounded: " +
          names + ". Their std is not reported.");
    }
  }
  result.refined.std = result.refined.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int k = 0; k < p; ++k)
    if (chi[k] != 0.0) result.refined.rel_std_pct[k] = 100.0 * result.refined.std[k] / std::abs(chi[k]);
  return result;
}

// The enabled effects whose estimate ended on a non-zero bound of their physical range.
std::vector<EffectKind> EffectsOnBound(const RefineResult& result, const RefineOptions& options) {
  std::vector<EffectKind> bounded;
  for (EffectKind kind : options.effects) {
    const auto [lower, upper] = RefineBounds(kind, options);
    const double margin = 1e-9 * (upper - lower);
    bool on_bound = false;
    for (double v : result.effects.Get(kind))
      on_bound = on_bound || (lower != 0.0 && v <= lower + margin) || (upper != 0.0 && v >= upper - margin);
    if (on_bound) bounded.push_back(kind);
  }
  return bounded;
}

}  // namespace

double CoarseDelaySearch(const IdentificationResult& linear, const RefineOptions& options, EffectKind kind) {
  const std::vector<double> grid =
      internal::SearchGrid(options.delay_search_min_s, options.delay_search_max_s, options.delay_search_step_s);
  const std::vector<double> criterion =
      internal::CriterionOverGrid(linear, options.initial, kind, grid, options.num_threads);
  return grid[std::min_element(criterion.begin(), criterion.end()) - criterion.begin()];
}

RefineResult Refine(const IdentificationResult& linear, const RefineOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  for (EffectKind kind : options.effects)
    for (const ProcessedFlight& flight : linear.flights)
      if (const std::string why = kind->Unavailable(flight.inputs()); !why.empty())
        throw Error(flight.source + ": " + why);
  Effects start = options.initial;
  const double linear_criterion = EffectCriterion(linear, Effects{});
  if (options.coarse_delay_search)
    for (EffectKind kind : options.effects)
      if (kind->info().grid_searched) start.Set(kind, CoarseDelaySearch(linear, options, kind));
  RefineResult result = SolveEffects(linear, linear.solution, start, options);
  if (options.reselect_essential && !options.effects.empty()) {
    // The TLS weights and equation-error variances of the linear step were fitted to the residual of
    // the uncorrected rows (a delay inflates the yaw equation's error, say), and its essential set
    // to their precision. Re-run the TLS, weights and selection included, on the rows corrected by
    // the estimated effects, and refine again from there, until the effects settle.
    Effects previous = result.effects;
    for (int pass = 2; pass <= 4; ++pass) {
      IdentificationResult restarted = linear;
      restarted.system.w = SystemRowsWithEffects(linear, result.effects);
      TlsSolution reselected = SolveIdim(restarted.system, linear.options.tls);
      if (!reselected.usable) break;
      restarted.solution = reselected;
      RefineOptions next = options;
      next.coarse_delay_search = false;
      RefineResult candidate = SolveEffects(restarted, reselected, result.effects, next);
      candidate.reselected = reselected;
      result = std::move(candidate);
      // Settled when no effect coordinate moved by more than a tenth of its std (without a
      // covariance: by more than the effect's settle tolerance).
      bool settled = true;
      for (EffectKind kind : options.effects) {
        const Eigen::VectorXd change = (result.effects.Get(kind) - previous.Get(kind)).cwiseAbs();
        const Eigen::VectorXd std_dev = result.effects_std.Get(kind);
        for (Eigen::Index k = 0; k < change.size(); ++k) {
          const double tolerance =
              k < std_dev.size() && std_dev[k] > 0.0 ? 0.1 * std_dev[k] : kind->info().settle_tolerance;
          settled = settled && change[k] <= tolerance + 1e-12;
        }
      }
      if (settled) break;
      previous = result.effects;
    }
  }
  // Estimates on a bound are not estimates.
  result.on_bound = EffectsOnBound(result, options);
  for (EffectKind kind : result.on_bound)
    result.warnings.push_back(kind->parameter_name() +
                              " ended on the bound of its physical range: these flights do not determine it "
                              "(or the residual has a cause outside the modelled effects); do not trust it");
  result.linear_criterion = linear_criterion;
  result.refined_criterion = EffectCriterion(linear, result.effects);
  result.relative_error_pct =
      RelativeErrorWithEffects(linear.flights, NamedParameters(linear.system, result.refined.chi), result.effects);
  // Confounded effects: say how much.
  for (int a = 0; a < result.effect_correlation.rows(); ++a)
    for (int b = a + 1; b < result.effect_correlation.cols(); ++b)
      if (std::abs(result.effect_correlation(a, b)) > 0.9)
        result.warnings.push_back(result.effect_labels[a] + " and " + result.effect_labels[b] +
                                  " are strongly correlated (" + std::to_string(result.effect_correlation(a, b)) +
                                  "): these flights separate them poorly");
  return result;
}

}  // namespace rotorid

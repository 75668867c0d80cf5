#include "rotorid/refine/refine.h"

#include <ceres/ceres.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <numeric>

#include "refine/consistent_chi.h"
#include "refine/grid_search.h"
#include "refine/idim_residual.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/ident/body_consistency.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/refine/effect_model.h"
#include "rotorid/signal/autocorrelation.h"

namespace rotorid {

std::vector<double> DelaySearch::Grid() const { return internal::SearchGrid(min_s, max_s, step_s); }

std::string DelaySearch::Validate() const {
  if (!(max_s > min_s)) return "delay search range is empty (max must exceed min)";
  if (!(step_s > 0.0)) return "delay search step must be positive";
  if ((max_s - min_s) / step_s > 5000) return "delay search grid has more than 5000 points; use a larger step";
  return {};
}

std::string RefineOptions::Validate() const {
  if (robust_loss != "none" && robust_loss != "huber" && robust_loss != "cauchy")
    return "robust loss must be none, huber or cauchy, got '" + robust_loss + "'";
  if (!(robust_scale > 0.0)) return "robust loss scale must be positive";
  if (criterion != "anchored" && criterion != "tls")
    return "criterion must be anchored or tls, got '" + criterion + "'";
  if (const std::string problem = delay_search.Validate(); !problem.empty()) return problem;
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

std::map<std::string, double> NamedParameters(const IdimLayout& system, const Eigen::VectorXd& chi) {
  std::map<std::string, double> values;
  for (int k = 0; k < system.num_parameters(); ++k) values[system.parameter_names[k]] = chi[k];
  return values;
}

std::vector<std::optional<double>> RelativeErrorWithEffects(const std::vector<ProcessedFlight>& flights,
                                                            const std::map<std::string, double>& parameters,
                                                            const Effects& effects) {
  RelativeErrorSums sums;
  for (const ProcessedFlight& f : flights) sums.Add(BuildIdimMatrixWithEffects(f, effects), FlightChiT(f, parameters));
  return sums.Pct();
}

namespace {

// System rows of all flights with the effects applied, in the layout of the linear system.
Eigen::MatrixXd SystemRowsWithEffects(const IdentificationResult& linear, const Effects& effects) {
  std::vector<int> every_column(static_cast<size_t>(linear.system.num_parameters()) + 1);
  std::iota(every_column.begin(), every_column.end(), 0);
  return internal::SystemColumnsWithEffects(linear, effects, every_column);
}

}  // namespace

double EffectCriterion(const IdentificationResult& linear, const Effects& effects) {
  return MinimumTlsCriterionOfColumns(
      internal::SystemColumnsWithEffects(linear, effects, CriterionColumns(linear.solution)), linear.solution);
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

// Variance inflation of the refinement's noise scale by autocorrelated residuals, averaged over the
// wrench components (their rows interleaved six by six), the first lag searched up to 200 samples
// as in the TLS statistics.
double ComponentAutocorrelationFactor(const Eigen::VectorXd& residuals) {
  double factor_sum = 0.0;
  int components = 0;
  for (int c = 0; c < 6; ++c) {
    const Eigen::Index n = residuals.size() > c ? (residuals.size() - c + 5) / 6 : 0;
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd, 0, Eigen::InnerStride<6>>(residuals.data() + c, n);
    if (n < 20 || !(x.squaredNorm() > 0.0)) continue;
    factor_sum += AutocorrelationFactor({x}, 200);
    ++components;
  }
  return components > 0 ? factor_sum / components : 1.0;
}

}  // namespace

namespace {

// The factor R (upper triangular, R^T R = J^T J) of the problem's Jacobian J with respect to
// `blocks`, in tangent coordinates. J is evaluated a few residual blocks at a time, each piece folded
// into R by a Householder QR of [R; piece], so that J itself is never held (it is rows x columns:
// 200 MB on a 1 h log). R has J's singular values and right singular vectors and J's column norms,
// and a least-squares fit between J's columns is the same fit between R's: all that the covariance
// and the confounding checks below need.
constexpr int kResidualBlocksPerJacobianPiece = 64;
Eigen::MatrixXd JacobianFactor(ceres::Problem* problem, const std::vector<double*>& blocks,
                               const std::vector<ceres::ResidualBlockId>& residual_blocks, int num_threads) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  evaluate.num_threads = num_threads;
  int columns = 0;
  for (const double* b : blocks) columns += problem->ParameterBlockTangentSize(b);
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(columns, columns);
  for (size_t first = 0; first < residual_blocks.size(); first += kResidualBlocksPerJacobianPiece) {
    const size_t last = std::min(residual_blocks.size(), first + kResidualBlocksPerJacobianPiece);
    evaluate.residual_blocks.assign(residual_blocks.begin() + static_cast<std::ptrdiff_t>(first),
                                    residual_blocks.begin() + static_cast<std::ptrdiff_t>(last));
    ceres::CRSMatrix crs;
    problem->Evaluate(evaluate, nullptr, nullptr, nullptr, &crs);
    CHECK_EQ(crs.num_cols, columns);
    Eigen::MatrixXd stacked = Eigen::MatrixXd::Zero(columns + crs.num_rows, columns);
    stacked.topRows(columns) = r;
    for (int row = 0; row < crs.num_rows; ++row)
      for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k) stacked(columns + row, crs.cols[k]) = crs.values[k];
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked);
    r = qr.matrixQR().topRows(columns).triangularView<Eigen::Upper>();
  }
  return r;
}

// The Jacobian's factor at the solution over every chi coordinate (the discarded ones too; none when
// chi is held) and then the free effects' coordinates: one evaluation for the covariance (its free
// columns) and the check of effects resting on discarded parameters (all of them).
struct SolutionJacobian {
  Eigen::MatrixXd factor;
  Eigen::VectorXd gradient;  // of the cost, in the factor's columns
  int chi_columns = 0;
};

// The parameters taking part in the (numerical) null space of the Jacobian `factor` (in tangent
// coordinates, labelled), with equilibrated columns: what the flights cannot tell apart.
std::vector<std::string> NullSpaceParameters(const Eigen::MatrixXd& factor, const std::vector<std::string>& labels) {
  // A column scaling makes the SVD see directions, not units.
  CHECK_EQ(static_cast<Eigen::Index>(labels.size()), factor.cols());
  const Eigen::VectorXd norms = factor.colwise().norm().transpose().cwiseMax(1e-300);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(factor * norms.cwiseInverse().asDiagonal(), Eigen::ComputeThinV);
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
std::vector<RestingOnDiscarded> EffectsRestingOnDiscarded(const SolutionJacobian& jacobian, const IdimLayout& system,
                                                          const std::vector<int>& fixed,
                                                          const std::vector<std::string>& effect_labels) {
  if (fixed.empty() || effect_labels.empty()) return {};
  const int p = system.num_parameters();
  const Eigen::MatrixXd& factor = jacobian.factor;
  CHECK_EQ(jacobian.chi_columns, p);
  CHECK_EQ(static_cast<Eigen::Index>(p + effect_labels.size()), factor.cols());
  Eigen::MatrixXd discarded(factor.rows(), static_cast<Eigen::Index>(fixed.size()));
  for (size_t k = 0; k < fixed.size(); ++k) {
    const double norm = factor.col(fixed[k]).norm();
    discarded.col(static_cast<Eigen::Index>(k)) =
        norm > 0.0 ? Eigen::VectorXd(factor.col(fixed[k]) / norm) : Eigen::VectorXd::Zero(factor.rows());
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(discarded);
  std::vector<RestingOnDiscarded> found;
  for (size_t e = 0; e < effect_labels.size(); ++e) {
    const Eigen::VectorXd column = factor.col(p + static_cast<Eigen::Index>(e));
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

// Pins linear combinations of an effect block's values to targets, A x - b with the weights in A
// and b: the sum of a zero-sum effect's values and the coordinates an effect holds. A penalty rather
// than a manifold keeps every block's tangent space its ambient one, which the covariance and
// Jacobian code below assume.
class PinResidual : public ceres::CostFunction {
 public:
  PinResidual(Eigen::MatrixXd weighted_combinations, Eigen::VectorXd weighted_targets)
      : combinations_(std::move(weighted_combinations)), targets_(std::move(weighted_targets)) {
    set_num_residuals(static_cast<int>(combinations_.rows()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(combinations_.cols()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::VectorXd> x(parameters[0], combinations_.cols());
    Eigen::Map<Eigen::VectorXd>(residuals, combinations_.rows()) = combinations_ * x - targets_;
    if (jacobians && jacobians[0])
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          jacobians[0], combinations_.rows(), combinations_.cols()) = combinations_;
    return true;
  }

 private:
  Eigen::MatrixXd combinations_;
  Eigen::VectorXd targets_;
};

// The pins of one effect block (in its solver units, started at `start`; `rows` residual rows in the
// problem), or null when it has none.
// - A zero-sum effect's sum: the mean is a linear parameter's (a common thrust factor is kt's), so
//   the rows cannot fix it and only the TLS normalisation pulls on it, weakly; 100 x sqrt(rows)
//   outweighs that pull (sums below 1e-6 on the flights tested) and keeps the problem well
//   conditioned.
// - Each held coordinate at its start value: the rows pull on it hard (the lever arm's z is ms_z's
//   column), and the drift falls with the weight squared: 100 x sqrt(rows) left 0.06 mm of an IMU
//   lever arm's z on configuration B, 1e4 x sqrt(rows) leaves 1e-5 of that.
// - Each held direction (HeldDirections) at 0, with the held coordinates' weight.
PinResidual* EffectPins(EffectKind kind, const Eigen::VectorXd& start, double rows,
                        const Eigen::MatrixXd& held_directions) {
  const Eigen::Index size = start.size();
  const std::vector<int>& held = kind->info().held_coordinates;
  const Eigen::Index pins =
      (kind->info().zero_sum ? 1 : 0) + static_cast<Eigen::Index>(held.size()) + held_directions.cols();
  if (pins == 0 || size == 0) return nullptr;
  Eigen::MatrixXd combinations = Eigen::MatrixXd::Zero(pins, size);
  Eigen::VectorXd targets = Eigen::VectorXd::Zero(pins);
  Eigen::Index pin = 0;
  if (kind->info().zero_sum) combinations.row(pin++).setConstant(100.0 * std::sqrt(rows));
  const double weight = 1e4 * std::sqrt(rows);
  for (int k : held) {
    CHECK_LT(k, size) << kind->name() << ": held coordinate out of range";
    combinations(pin, k) = weight;
    targets[pin++] = weight * start[k];
  }
  for (Eigen::Index d = 0; d < held_directions.cols(); ++d)
    combinations.row(pin++) = weight * held_directions.col(d).transpose();
  return new PinResidual(std::move(combinations), std::move(targets));
}

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
  if (kind->info().grid_searched) return {options.delay_search.min_s, options.delay_search.max_s};
  return {kind->info().lower_bound, kind->info().upper_bound};
}

// The Ceres problem of one pass and the storage its parameter blocks and residual blocks point
// into: built in place and never moved. The problem is declared last, so it goes first.
struct EffectProblem {
  CriterionContext context;
  internal::EffectBlocks effect_blocks;
  Eigen::VectorXd scaled_chi;                  // chi in units of context.chi_scale
  std::vector<Eigen::VectorXd> effect_values;  // per free effect, in units of its RefineScale
  std::vector<Eigen::MatrixXd> held_directions;  // per free effect (HeldDirections)
  std::vector<double*> blocks_of_residual;     // scaled_chi, then each free effect's block
  std::vector<int> fixed, free;                // chi coordinates held at 0 / estimated
  std::vector<internal::ChartedBody> charts;   // the bodies kept physical (RefineOptions::consistent_bodies)
  BodyConstraint constraint;
  std::vector<std::unique_ptr<RotorSignalCache>> caches;
  std::vector<internal::RotorMomentAnchor> anchors;
  std::vector<ceres::ResidualBlockId> residual_blocks;
  std::unique_ptr<ceres::Problem> problem;
};

// Whether the yaw torque's scale kd is among the parameters `tls` estimates.
bool KdFree(const IdimLayout& system, const TlsSolution& tls) {
  const auto kd = std::find(system.parameter_names.begin(), system.parameter_names.end(), "kd");
  return kd != system.parameter_names.end() && tls.essential[static_cast<size_t>(kd - system.parameter_names.begin())];
}

// The parameter blocks: chi scaled by max(|chi|, std), one block per enabled effect in registry
// order started at `start` (the other effects stay fixed at their start).
void SetUpParameterBlocks(const std::vector<ProcessedFlight>& flights, const IdimLayout& system, const TlsSolution& tls,
                          const Effects& start, const RefineOptions& options, EffectProblem* ep) {
  const int p = system.num_parameters();
  ep->context.metric = tls.column_metric;
  ep->context.total_rows = static_cast<double>(system.row_group.size());
  ep->context.num_parameters = p;
  ep->context.chi_scale.resize(p);
  // The profiled parameters start at their estimate (TlsSolution::profiled).
  const bool profiled = tls.profiled_chi.size() == p;
  Eigen::VectorXd start_chi = profiled ? tls.chi + tls.profiled_chi : tls.chi;
  const Eigen::VectorXd start_std = profiled ? tls.std + tls.profiled_std : tls.std;
  for (int k = 0; k < p; ++k) (tls.essential[k] || tls.Profiled(k) ? ep->free : ep->fixed).push_back(k);
  if (options.consistent_bodies && !ep->free.empty()) {
    BodyConstraint& constraint = ep->constraint;
    ep->charts = internal::ChartBodies(system, ConfigurationMasses(flights), ep->fixed, start_chi, &constraint.notes);
    for (const internal::ChartedBody& body : ep->charts) constraint.charted.push_back(body.name);
    constraint.start_distance_std =
        internal::ProjectStartOntoCharts(ep->charts, tls, &start_chi, &constraint.start_moved);
  }
  for (int k = 0; k < p; ++k) ep->context.chi_scale[k] = std::max({std::abs(start_chi[k]), start_std[k], 1e-12});
  ep->scaled_chi = start_chi.cwiseQuotient(ep->context.chi_scale);
  const Vehicle& vehicle = flights.front().vehicle;
  ep->effect_blocks.fixed = start;
  for (EffectKind kind : AllEffects())
    if (options.Enabled(kind)) ep->effect_blocks.free.push_back(kind);
  for (EffectKind kind : ep->effect_blocks.free) {
    ep->effect_blocks.scale.push_back(RefineScale(kind));
    Eigen::VectorXd v = start.Get(kind);
    if (v.size() == 0) v = Eigen::VectorXd::Zero(kind->Dimension(vehicle));
    if (v.size() != kind->Dimension(vehicle))
      throw Error(kind->parameter_name() + " takes " + std::to_string(kind->Dimension(vehicle)) +
                  " value(s) for this vehicle, got " + std::to_string(v.size()));
    ep->effect_values.push_back(v / ep->effect_blocks.scale.back());
  }
  ep->blocks_of_residual = {ep->scaled_chi.data()};
  for (Eigen::VectorXd& v : ep->effect_values) ep->blocks_of_residual.push_back(v.data());
  const bool kd_free = KdFree(system, tls);
  for (EffectKind kind : ep->effect_blocks.free) ep->held_directions.push_back(HeldDirections(kind, vehicle, kd_free));
}

// The anchored criterion's anchor of each flight at tls.chi (none for the TLS criterion), from the
// flights' rows with `effects` (those the TLS `tls` was solved on).
std::vector<internal::RotorMomentAnchor> AnchorFlights(const std::vector<ProcessedFlight>& flights,
                                                       const Effects& effects, const IdimLayout& system,
                                                       const TlsSolution& tls, const RefineOptions& options) {
  std::vector<internal::RotorMomentAnchor> anchors;
  if (options.criterion != "anchored") return anchors;
  for (int f = 0; f < system.num_flights(); ++f)
    anchors.push_back(internal::AnchorRotorMoments(flights[f], effects, system, f, tls.chi));
  return anchors;
}

// The rows of every flight, in blocks of kRowSamplesPerBlock row samples, weighted as the TLS
// weighted them; with the anchored criterion each flight's moment rows divided by its anchor's gain.
void AddRowResiduals(const std::vector<ProcessedFlight>& flights, const IdimLayout& system, const TlsSolution& tls,
                     const RefineOptions& options, EffectProblem* ep) {
  const Eigen::VectorXd sqrt_weight = tls.row_weight.cwiseSqrt();
  int row = 0;
  for (int f = 0; f < system.num_flights(); ++f) {
    const ProcessedFlight& flight = flights[f];
    ep->caches.push_back(std::make_unique<RotorSignalCache>(&flight, &ep->effect_blocks,
                                                            ep->anchors.empty() ? nullptr : &ep->anchors[f]));
    for (int first = 0; first < flight.num_rows_samples(); first += kRowSamplesPerBlock) {
      const int count = std::min(kRowSamplesPerBlock, flight.num_rows_samples() - first);
      ceres::LossFunction* loss = nullptr;
      if (options.robust_loss == "huber") loss = new ceres::HuberLoss(options.robust_scale);
      if (options.robust_loss == "cauchy") loss = new ceres::CauchyLoss(options.robust_scale);
      ep->residual_blocks.push_back(
          ep->problem->AddResidualBlock(new IdimResidualBlock(&flight, ep->caches.back().get(), &ep->context,
                                                              &ep->effect_blocks, system.flight_body_columns[f], first,
                                                              count, sqrt_weight.segment(row + 6 * first, 6 * count)),
                                        loss, ep->blocks_of_residual));
    }
    row += 6 * flight.num_rows_samples();
  }
}

// The chi block's manifold: the charts of its bodies (and the held coordinates), else the held
// coordinates' subset; null when every coordinate is free and no body is charted.
ceres::Manifold* ChiManifold(const EffectProblem& ep) {
  if (!ep.charts.empty())
    return new internal::ConsistentChiManifold(ep.context.num_parameters, ep.fixed, ep.charts, ep.context.chi_scale);
  return ep.fixed.empty() ? nullptr : new ceres::SubsetManifold(ep.context.num_parameters, ep.fixed);
}

// Discarded (non-essential) parameters stay at zero, as in the TLS step (the profiled ones are
// estimated there and here: TlsSolution::profiled); effects within their bounds; a zero-sum
// effect's sum and the held coordinates pinned.
void ConstrainParameters(const RefineOptions& options, EffectProblem* ep) {
  if (ep->free.empty()) {
    ep->problem->SetParameterBlockConstant(ep->scaled_chi.data());
  } else if (ceres::Manifold* manifold = ChiManifold(*ep)) {
    ep->problem->SetManifold(ep->scaled_chi.data(), manifold);
  }
  for (size_t b = 0; b < ep->effect_blocks.free.size(); ++b) {
    const auto [lower, upper] = RefineBounds(ep->effect_blocks.free[b], options);
    double* values = ep->effect_values[b].data();
    for (Eigen::Index a = 0; a < ep->effect_values[b].size(); ++a) {
      ep->problem->SetParameterLowerBound(values, static_cast<int>(a), lower / ep->effect_blocks.Scale(b));
      ep->problem->SetParameterUpperBound(values, static_cast<int>(a), upper / ep->effect_blocks.Scale(b));
    }
    if (PinResidual* pins =
            EffectPins(ep->effect_blocks.free[b], ep->effect_values[b], ep->context.total_rows, ep->held_directions[b]))
      ep->residual_blocks.push_back(ep->problem->AddResidualBlock(pins, nullptr, values));
  }
}

// Ceres keeps a bounded coordinate in its box by projecting each step onto it. When the data push a
// coordinate against its bound, the projected step loses that part of the predicted decrease, the
// trust region's gain ratio stays near 0.01 however small the step, and the solver creeps and stops
// short: a gyro bias against its 0.2 rad/s bound on a real Crazyflie flight used every pass's 20
// iterations and ended at a cost 35 above the constrained optimum, which 5 iterations reach now. So
// the solve keeps an active set: once a coordinate has stayed on its bound for kStepsOnBound
// successful steps it is held there and the rest solved; a held coordinate whose gradient points
// back into the box is released.
class EffectBounds {
 public:
  EffectBounds(const RefineOptions& options, EffectProblem* ep) : ep_(ep) {
    for (size_t b = 0; b < ep->effect_blocks.free.size(); ++b) {
      const auto [lower, upper] = RefineBounds(ep->effect_blocks.free[b], options);
      lower_.push_back(lower / ep->effect_blocks.Scale(b));
      upper_.push_back(upper / ep->effect_blocks.Scale(b));
      held_.emplace_back();
      steps_on_bound_.push_back(Eigen::VectorXi::Zero(ep->effect_values[b].size()));
    }
  }

  // After a successful step: holds every coordinate not held yet that has sat on a bound after
  // kStepsOnBound successive steps (a coordinate starting on its bound of 0, a lag say, is often
  // clipped at the first step and leaves the bound once the others have moved); false when none is.
  bool HoldNewContacts() {
    bool any = false;
    for (size_t b = 0; b < held_.size(); ++b)
      for (Eigen::Index a = 0; a < ep_->effect_values[b].size(); ++a) {
        int& steps = steps_on_bound_[b][a];
        steps = OnBound(b, a) ? steps + 1 : 0;
        if (steps >= kStepsOnBound && !Held(b, a)) {
          held_[b].push_back(static_cast<int>(a));
          any = true;
        }
      }
    return any;
  }

  // Releases the held coordinates whose gradient `gradient` (over every free effect coordinate, in
  // block order) points into the box; false when every held coordinate stays.
  bool ReleaseInward(const std::vector<double>& gradient) {
    bool any = false;
    size_t offset = 0;
    for (size_t b = 0; b < held_.size(); ++b) {
      std::vector<int> kept;
      for (int a : held_[b]) {
        const double g = gradient[offset + static_cast<size_t>(a)];
        const double v = ep_->effect_values[b][a];
        const bool stays = (v <= lower_[b] && g >= 0.0) || (v >= upper_[b] && g <= 0.0);
        if (stays) kept.push_back(a);
        if (!stays) steps_on_bound_[b][a] = 0;  // held again only after kStepsOnBound more steps there
        any = any || !stays;
      }
      held_[b] = kept;
      offset += static_cast<size_t>(ep_->effect_values[b].size());
    }
    return any;
  }

  // Sets the held coordinates constant in the problem (a block all held, or a subset manifold), or
  // frees them all again.
  void Apply(bool hold) {
    for (size_t b = 0; b < held_.size(); ++b) {
      double* values = ep_->effect_values[b].data();
      const int size = static_cast<int>(ep_->effect_values[b].size());
      if (held_[b].empty()) continue;
      if (!hold) {
        ep_->problem->SetParameterBlockVariable(values);
        ep_->problem->SetManifold(values, nullptr);
      } else if (static_cast<int>(held_[b].size()) == size) {
        ep_->problem->SetParameterBlockConstant(values);
      } else {
        ep_->problem->SetManifold(values, new ceres::SubsetManifold(size, held_[b]));
      }
    }
  }

  bool AnyHeld() const {
    return std::any_of(held_.begin(), held_.end(), [](const std::vector<int>& h) { return !h.empty(); });
  }
  // Each coordinate can be held and released once or twice before the set settles.
  int MaxSolves() const {
    Eigen::Index coordinates = 0;
    for (const Eigen::VectorXd& v : ep_->effect_values) coordinates += v.size();
    return 2 * static_cast<int>(coordinates) + 2;
  }

 private:
  bool OnBound(size_t b, Eigen::Index a) const {
    const double v = ep_->effect_values[b][a];
    return v <= lower_[b] || v >= upper_[b];
  }
  bool Held(size_t b, Eigen::Index a) const {
    return std::find(held_[b].begin(), held_[b].end(), static_cast<int>(a)) != held_[b].end();
  }

  static constexpr int kStepsOnBound = 3;
  EffectProblem* ep_;
  std::vector<double> lower_, upper_;  // per free effect, in its solver units
  std::vector<std::vector<int>> held_;
  std::vector<Eigen::VectorXi> steps_on_bound_;
};

// Ends a solve after a successful step that put a free coordinate on its bound.
class BoundContactCallback : public ceres::IterationCallback {
 public:
  explicit BoundContactCallback(EffectBounds* bounds) : bounds_(bounds) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0 || !summary.step_is_successful) return ceres::SOLVER_CONTINUE;
    return bounds_->HoldNewContacts() ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  EffectBounds* bounds_;
};

// Ends the first pass of a refinement that re-selects the essential set once its steps are small
// and Ceres' model of the cost keeps overestimating the curvature: the ratio of actual to predicted
// decrease stays near 2 (1.84 on a 90 s simulated log with every effect, 1.98 on real Crazyflie
// flights: a curvature 6-50 times too high in some direction, presumably where the TLS criterion's
// curvature A - lambda N is far below the Gauss-Newton model's A), and each step then shrinks the
// cost change by 0.7 or less, for 28-83 steps. That pass only starts the passes that follow, whose
// TLS weights come from the rows with its effects; they settle as before (refine with every effect,
// 90 s: 38 -> 13 iterations, the result within 1e-5 std; real jana01/04/06: the criterion within
// 0.2 %, values within 0.45 std along their 0.99-correlated pairs). A final pass keeps its slow steps.
class SlowStartPassCallback : public ceres::IterationCallback {
 public:
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    const bool slow = summary.iteration > 0 && summary.step_is_successful &&
                      summary.relative_decrease > kOverestimatedCurvatureRatio &&
                      summary.cost_change < kSmallStep * summary.cost;
    slow_steps_ = slow ? slow_steps_ + 1 : 0;
    stopped_ = slow_steps_ >= 2;
    return stopped_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }
  bool stopped() const { return stopped_; }

 private:
  // A ratio of 1.5 means the model's curvature is 4 times too high (ratio = 2 - 1/that factor).
  static constexpr double kOverestimatedCurvatureRatio = 1.5;
  static constexpr double kSmallStep = 1e-4;  // relative cost change
  int slow_steps_ = 0;
  bool stopped_ = false;
};

// The gradient of the cost over every free effect coordinate (block order), nothing held.
std::vector<double> EffectGradient(EffectProblem* ep, int num_threads) {
  ceres::Problem::EvaluateOptions evaluate;
  for (Eigen::VectorXd& v : ep->effect_values) evaluate.parameter_blocks.push_back(v.data());
  evaluate.num_threads = num_threads;
  double cost = 0.0;
  std::vector<double> gradient;
  ep->problem->Evaluate(evaluate, &cost, nullptr, &gradient, nullptr);
  return gradient;
}

// Solves the problem with the active set above and records the solver's report (iterations and time
// over every solve of it); throws when the solution is unusable. The iteration limit is the total.
// A `start_pass` (SlowStartPassCallback) also ends in the slow regime.
void SolveEffectProblem(const RefineOptions& options, bool start_pass, EffectProblem* ep, RefineResult* result) {
  ceres::Solver::Options solver_options;
  // The normal equations of the tall, narrow Jacobian (rows x 20-30 columns): J^T J by a symmetric
  // rank update is several times cheaper than a QR of J, and Ceres' QR also copies J (200 MB on a
  // 1 h log). The steps differ in round-off only; the solution within the tolerances below.
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  // A relative cost change of 1e-8 per step (Ceres' default: 1e-6): stopping there moved no refined
  // parameter or effect by more than 0.02 of its std against 1e-10, and 1e-10 none by more than
  // 1e-3 against 1e-12 (refine and diagnose JSON, the simulated recovery studies, the real
  // Crazyflie refinements; no verdict changed).
  solver_options.function_tolerance = 1e-8;
  solver_options.gradient_tolerance = 1e-14;
  solver_options.parameter_tolerance = 1e-12;
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  // The effects have bounds, so every trust-region step is followed by Ceres' projected Armijo line
  // search. Its default cubic interpolation evaluates the gradient (the whole Jacobian) at each trial
  // step; bisection needs only the cost there (a quarter of a refinement's time was that Jacobian).
  // The search is the same backtracking, and a full step is accepted on the same test.
  solver_options.line_search_interpolation_type = ceres::BISECTION;
  EffectBounds bounds(options, ep);
  BoundContactCallback contact(&bounds);
  solver_options.callbacks.push_back(&contact);
  SlowStartPassCallback slow;
  if (start_pass) solver_options.callbacks.push_back(&slow);
  solver_options.update_state_every_iteration = true;  // the callback reads the effects' values
  int iterations = 0;
  result->solver.seconds = 0.0;
  ceres::Solver::Summary summary;
  for (int solve = 0; solve < bounds.MaxSolves(); ++solve) {
    solver_options.max_num_iterations = std::max(1, options.max_iterations - iterations);
    bounds.Apply(true);
    const auto t0 = std::chrono::steady_clock::now();
    ceres::Solve(solver_options, ep->problem.get(), &summary);
    result->solver.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (solve == 0) result->solver.initial_cost = summary.initial_cost;
    iterations += static_cast<int>(summary.iterations.size()) - 1;
    LOG(INFO) << "refinement solve: " << summary.iterations.size() - 1 << " iterations ("
              << summary.num_residual_evaluations << " cost and " << summary.num_jacobian_evaluations
              << " Jacobian evaluations), " << TerminationName(summary.termination_type);
    if (!summary.IsSolutionUsable()) break;
    if (slow.stopped()) break;
    const bool contact_ended_it = summary.termination_type == ceres::USER_SUCCESS;
    bounds.Apply(false);
    if (iterations >= options.max_iterations) break;
    if (contact_ended_it) continue;  // hold the new contacts and go on
    if (!bounds.AnyHeld() || !bounds.ReleaseInward(EffectGradient(ep, options.num_threads))) break;
  }
  bounds.Apply(false);
  result->solver.iterations = iterations;
  result->solver.final_cost = summary.final_cost;
  result->solver.termination = slow.stopped() ? "start pass: ended where its steps were slow"
                               : summary.termination_type == ceres::USER_SUCCESS
                                   ? "no convergence (iteration limit)"
                                   : TerminationName(summary.termination_type);
  result->solver.message = summary.message;
  result->solver.full_report = summary.FullReport();
  if (!summary.IsSolutionUsable()) throw Error("refinement failed: " + summary.message);
}

// Labels of the free effects' coordinates, in block order.
std::vector<std::string> FreeEffectLabels(const EffectProblem& ep) {
  std::vector<std::string> labels;
  for (size_t b = 0; b < ep.effect_blocks.free.size(); ++b) {
    const std::vector<std::string> block =
        ep.effect_blocks.free[b]->Labels(static_cast<int>(ep.effect_values[b].size()));
    labels.insert(labels.end(), block.begin(), block.end());
  }
  return labels;
}

// The Jacobian's factor at the solution (SolutionJacobian). The discarded chi coordinates'
// columns come from the chi block without its subset manifold, restored afterwards.
SolutionJacobian FactorSolutionJacobian(EffectProblem* ep, int num_threads) {
  SolutionJacobian jacobian;
  std::vector<double*> blocks;
  if (!ep->free.empty()) {
    blocks.push_back(ep->scaled_chi.data());
    jacobian.chi_columns = ep->context.num_parameters;
  }
  for (Eigen::VectorXd& v : ep->effect_values) blocks.push_back(v.data());
  if (blocks.empty()) return jacobian;
  const bool has_manifold = !ep->free.empty() && (!ep->fixed.empty() || !ep->charts.empty());
  if (has_manifold) ep->problem->SetManifold(ep->scaled_chi.data(), nullptr);
  jacobian.factor = JacobianFactor(ep->problem.get(), blocks, ep->residual_blocks, num_threads);
  if (!ep->charts.empty()) {
    ceres::Problem::EvaluateOptions evaluate;
    evaluate.parameter_blocks = blocks;
    evaluate.num_threads = num_threads;
    std::vector<double> gradient;
    ep->problem->Evaluate(evaluate, nullptr, nullptr, &gradient, nullptr);
    jacobian.gradient = Eigen::Map<const Eigen::VectorXd>(gradient.data(), static_cast<Eigen::Index>(gradient.size()));
  }
  if (has_manifold) ep->problem->SetManifold(ep->scaled_chi.data(), ChiManifold(*ep));
  return jacobian;
}

// Warns of effect coordinates whose value rests on a parameter the essential selection holds at 0.
void NoteEffectsRestingOnDiscarded(const EffectProblem& ep, const SolutionJacobian& jacobian, const IdimLayout& system,
                                   const std::vector<std::string>& effect_labels, RefineResult* result) {
  for (const RestingOnDiscarded& r : EffectsRestingOnDiscarded(jacobian, system, ep.fixed, effect_labels)) {
    result->resting_on_discarded.push_back(r.coordinate + " ~ " + r.parameter);
    result->warnings.push_back(r.coordinate + " is confounded with " + r.parameter +
                               ", which the essential selection holds at 0 (it explains " +
                               FormatValue("%.1f %%", 100.0 * r.explained) +
                               " of its effect on the rows): its value assumes " + r.parameter + " = 0");
  }
}

// Two scalar effects of one unit that trade against each other (correlation below -0.9, e.g. a
// delay and a motor lag: their phase lags add) are fixed by the data only in their sum: "; what the
// data fix is delay_s + motor_tau_s = 62.9 +- 3.1 ms". Empty for other pairs.
std::string WhatATradingPairFixes(const RefineResult& result, int a, int b) {
  const double correlation = result.effect_correlation(a, b);
  const auto scalar_effect = [&](const std::string& label) -> EffectKind {
    for (EffectKind kind : result.enabled)
      if (kind->parameter_name() == label && kind->FixedDimension() == 1) return kind;
    return nullptr;
  };
  const EffectKind first = scalar_effect(result.effect_labels[a]);
  const EffectKind second = scalar_effect(result.effect_labels[b]);
  if (!first || !second || !(correlation < -0.9) || first->info().unit != second->info().unit) return "";
  const double std_a = result.effects_std.Scalar(first), std_b = result.effects_std.Scalar(second);
  const double sum = result.effects.Scalar(first) + result.effects.Scalar(second);
  const double sum_std = std::sqrt(std::max(0.0, std_a * std_a + std_b * std_b + 2.0 * correlation * std_a * std_b));
  const double scale = first->info().display_scale;
  const std::string& unit = first->info().display_unit.empty() ? first->info().unit : first->info().display_unit;
  return "; what the data fix is " + first->parameter_name() + " + " + second->parameter_name() + " = " +
         FormatValue("%.3g", scale * sum) + " +- " + FormatValue("%.2g", scale * sum_std) + " " + unit;
}

// The distance of the unconstrained optimum from the solution on the charts, in the solution's std: the
// Gauss-Newton step from it with the charts lifted, -H^-1 g (H = J^T J = V S^2 V^T over the free chi
// and effect coordinates, g the cost's gradient over the free chi coordinates; an effect's own gradient,
// at a bound, is left out), whose length in the metric of the covariance scale H^-1 is
// sqrt(g^T H^-1 g / scale). At an optimum inside the charts g is 0: the constrained estimate is the
// unconstrained one.
void NoteUnconstrainedDistance(const EffectProblem& ep, const IdimLayout& system,
                               const Eigen::JacobiSVD<Eigen::MatrixXd>& svd, double scale,
                               const Eigen::VectorXd& gradient, const Eigen::VectorXd& variance,
                               BodyConstraint* constraint) {
  const Eigen::VectorXd projected = svd.matrixV().transpose() * gradient;
  const Eigen::VectorXd step =
      -(svd.matrixV() * svd.singularValues().cwiseAbs2().cwiseInverse().asDiagonal() * projected);
  constraint->unconstrained_distance_std = std::sqrt(std::max(0.0, -gradient.dot(step)) / scale);
  double largest = 0.0;
  for (size_t a = 0; a < ep.free.size(); ++a) {
    const auto i = static_cast<Eigen::Index>(a);
    const double move = variance[i] > 0.0 ? std::abs(step[i]) / std::sqrt(variance[i]) : 0.0;
    if (move <= largest) continue;
    largest = move;
    constraint->largest_move = system.parameter_names[ep.free[a]] + " " + ShortNumber(move) + " std";
  }
}

// The covariance of chi and the effects at the solution, scaled by the observed residual variance
// (`cost` over the degrees of freedom) and the autocorrelation factor; where the Jacobian is rank
// deficient, the confounded coordinates instead.
void ComputeRefinedCovariance(const EffectProblem& ep, const SolutionJacobian& jacobian, const IdimLayout& system,
                              double cost, Eigen::Index num_residuals, const std::vector<std::string>& effect_labels,
                              RefineResult* result) {
  if (jacobian.factor.size() == 0) return;
  // The tangent coordinates: the free chi coordinates, then every effect coordinate.
  std::vector<Eigen::Index> columns(ep.free.begin(), ep.free.end());
  std::vector<std::string> labels;
  for (int k : ep.free) labels.push_back(system.parameter_names[k]);
  labels.insert(labels.end(), effect_labels.begin(), effect_labels.end());
  for (Eigen::Index e = 0; e < static_cast<Eigen::Index>(effect_labels.size()); ++e)
    columns.push_back(jacobian.chi_columns + e);
  const Eigen::MatrixXd tangent = jacobian.factor(Eigen::all, columns);
  // As ceres::Covariance's DENSE_SVD with null_space_rank 0: rank deficient when a singular value is
  // below sqrt(1e-14) (its default min_reciprocal_condition_number) of the largest.
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(tangent, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  if (!(sv.size() > 0 && sv.minCoeff() >= std::sqrt(1e-14) * sv[0])) {
    result->rank_deficient = true;
    result->confounded = NullSpaceParameters(tangent, labels);
    const std::string names = Join(result->confounded);
    result->warnings.push_back(
        "the refined parameters are not jointly identifiable from these flights (rank-deficient "
        "Jacobian); confounded: " +
        names + ". Their std is not reported.");
    return;
  }
  // Whitened residuals have unit variance only if the noise model is right: scale by the
  // observed residual variance and by the autocorrelation factor.
  const double dof = std::max(1.0, static_cast<double>(num_residuals) - ep.problem->NumParameters());
  const double scale = std::max(2.0 * cost / dof, 1e-300) * result->autocorrelation_factor;
  const Eigen::Index dim = tangent.cols();
  const Eigen::MatrixXd full =
      scale * (svd.matrixV() * sv.cwiseAbs2().cwiseInverse().asDiagonal() * svd.matrixV().transpose());
  result->has_covariance = true;
  if (jacobian.gradient.size() > 0) {
    Eigen::VectorXd gradient = jacobian.gradient(columns);
    gradient.tail(gradient.size() - static_cast<Eigen::Index>(ep.free.size())).setZero();
    NoteUnconstrainedDistance(ep, system, svd, scale, gradient, full.diagonal(), &result->body_constraint);
  }
  const std::vector<int>& free = ep.free;
  const Eigen::VectorXd& chi_scale = ep.context.chi_scale;
  const int offset = static_cast<int>(free.size());
  const TlsSolution& refined = result->refined;
  for (int a = 0; a < offset; ++a)
    for (int b = 0; b < offset; ++b)
      if (!refined.Profiled(free[a]) && !refined.Profiled(free[b]))
        result->refined.covariance(free[a], free[b]) = full(a, b) * chi_scale[free[a]] * chi_scale[free[b]];
  const Eigen::Index effect_dim = dim - offset;
  const Eigen::MatrixXd effect_cov = full.block(offset, offset, effect_dim, effect_dim);
  Eigen::Index e = 0;
  for (size_t b = 0; b < ep.effect_blocks.free.size(); ++b) {
    const Eigen::Index size = ep.effect_values[b].size();
    Eigen::VectorXd std_dev =
        ep.effect_blocks.Scale(b) * effect_cov.diagonal().segment(e, size).cwiseMax(0.0).cwiseSqrt();
    for (int k : ep.effect_blocks.free[b]->info().held_coordinates) std_dev[k] = 0.0;  // not estimated
    result->effects_std.Set(ep.effect_blocks.free[b], std_dev);
    e += size;
  }
  result->effect_labels = effect_labels;
  const Eigen::VectorXd sd = effect_cov.diagonal().cwiseMax(1e-300).cwiseSqrt();
  result->effect_correlation = sd.cwiseInverse().asDiagonal() * effect_cov * sd.cwiseInverse().asDiagonal();
}

// One Ceres pass: the rows of the flights with effects, the criterion (lambda, N) of `tls` on a
// system of this layout, with its `anchors` (AnchorFlights), started at tls.chi and `start`. Fills
// chi, effects, their covariance and the solver report. A `start_pass` ends in the slow regime.
RefineResult SolveEffects(const std::vector<ProcessedFlight>& flights, const IdimLayout& system,
                          std::vector<internal::RotorMomentAnchor> anchors, const TlsSolution& tls,
                          const Effects& start, const RefineOptions& options, bool start_pass) {
  RefineResult result;
  result.enabled = options.effects;
  EffectProblem ep;
  ep.anchors = std::move(anchors);  // before the residual blocks, which point into it
  SetUpParameterBlocks(flights, system, tls, start, options, &ep);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ep.problem = std::make_unique<ceres::Problem>(problem_options);
  AddRowResiduals(flights, system, tls, options, &ep);
  ConstrainParameters(options, &ep);
  SolveEffectProblem(options, start_pass, &ep, &result);

  const Eigen::VectorXd chi = ep.scaled_chi.cwiseProduct(ep.context.chi_scale);
  result.effects = ep.effect_blocks.At(ep.blocks_of_residual.data(), flights.front().vehicle);
  result.refined = tls;
  result.refined.chi = chi;
  for (int k = 0; k < chi.size(); ++k)
    if (tls.Profiled(k)) {  // estimated, not reported
      result.refined.profiled_chi[k] = chi[k];
      result.refined.chi[k] = 0.0;
    }
  result.refined.covariance.setZero();
  result.refined.std.setZero();
  result.refined.rel_std_pct.setZero();

  // Residuals at the solution, for the noise scale and the autocorrelation factor.
  std::vector<double> residual_values;
  double cost = 0.0;
  ep.problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, &residual_values, nullptr, nullptr);
  const Eigen::VectorXd residuals = Eigen::Map<const Eigen::VectorXd>(residual_values.data(), residual_values.size());
  result.autocorrelation_factor = ComponentAutocorrelationFactor(residuals);
  const std::vector<std::string> effect_labels = FreeEffectLabels(ep);
  result.body_constraint = ep.constraint;
  // A report for people: fits that skip the covariance (diagnosis folds, ablation) skip it too.
  if (options.compute_covariance) {
    const SolutionJacobian jacobian = FactorSolutionJacobian(&ep, options.num_threads);
    if (!ep.free.empty()) NoteEffectsRestingOnDiscarded(ep, jacobian, system, effect_labels, &result);
    ComputeRefinedCovariance(ep, jacobian, system, cost, residuals.size(), effect_labels, &result);
  }
  SetStdFromCovariance(system.parameter_names, &result.refined);
  SetAllowedRanges(system, ConfigurationMasses(flights), &result.refined);
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
  const std::vector<double> grid = options.delay_search.Grid();
  const double best = internal::CoarseToFineGridMinimum(linear, options.initial, kind, grid, options.num_threads);
  LOG(INFO) << "coarse-to-fine search of " << kind->parameter_name() << " on a grid of " << grid.size()
            << " values: " << best;
  return best;
}

namespace {

constexpr int kMaxRefinePasses = 4;

bool SearchesDelayGrid(const RefineOptions& options) {
  return options.coarse_delay_search && std::any_of(options.effects.begin(), options.effects.end(),
                                                    [](EffectKind kind) { return kind->info().grid_searched; });
}

// The TLS re-selected on the rows corrected by the effects, but with the parameters that the linear
// step discarded and that come back with a sign their physics excludes (beyond 3 std) held
// discarded, as the linear step had them; `held` names those. On a flight with little yaw the yaw
// equation fixes kd / I_zz only, and the corrected rows can give both the wrong sign with a small
// first-order std (the independent simulator's ground-effect flight: kd -1.9e-9 +- 0.14e-9 and
// I_zz -0.0011, with their ratio right).
TlsSolution ReselectEssential(const IdimSystem& corrected, const IdentificationResult& linear, std::string* held) {
  TlsSolution reselected = SolveIdim(corrected, linear.options.tls);
  if (!reselected.usable) return reselected;
  TlsOptions holding = linear.options.tls;
  for (int k = 0; k < corrected.num_parameters(); ++k) {
    const std::string& name = corrected.parameter_names[k];
    if (linear.solution.essential[k] || !reselected.essential[k] || !PositiveByPhysics(name) ||
        reselected.chi[k] >= -3.0 * reselected.std[k])
      continue;
    holding.discarded_from_start.push_back(name);
    *held += (held->empty() ? "" : ", ") + name + " = " + ShortNumber(reselected.chi[k]) + " +- " +
             ShortNumber(reselected.std[k]);
  }
  return holding.discarded_from_start.size() == linear.options.tls.discarded_from_start.size()
             ? reselected
             : SolveIdim(corrected, holding);
}

// A refined estimate the charts held far from the unconstrained optimum, or a start far from every body,
// is a finding: the flights, or the model, put the parameters where no body is.
void NoteBodyConstraint(RefineResult* result) {
  const BodyConstraint& c = result->body_constraint;
  if (c.unconstrained_distance_std > kFarFromABodyStd)
    result->warnings.push_back(
        "physical_consistency: the unconstrained refined estimate lies " + ShortNumber(c.unconstrained_distance_std) +
        " std from the physically consistent one reported (most in " + c.largest_move +
        "): the flights or the model put the parameters where no body is (a first moment or inertia they do not fix, "
        "or an effect the model lacks)");
  if (c.start_distance_std > kFarFromABodyStd)
    result->warnings.push_back("physical_consistency: the TLS estimate that started the refinement is no body (" +
                               Join(c.start_moved) + " from the nearest one in its metric)");
}

}  // namespace

int RefineSteps(const RefineOptions& options) {
  const bool reselects = options.reselect_essential && !options.effects.empty();
  return (SearchesDelayGrid(options) ? 1 : 0) + (reselects ? kMaxRefinePasses : 1);
}

namespace {

// What a pass started from: the TLS (its weights, metric and essential set) and the effects of the
// rows that TLS was solved on (its anchors'). The layout is the linear system's throughout.
struct PassStart {
  TlsSolution tls;
  Effects rows_effects;
};

RefineResult SolvePass(const IdentificationResult& linear, const PassStart& pass, const Effects& start,
                       const RefineOptions& options, bool start_pass) {
  return SolveEffects(linear.flights, linear.system,
                      AnchorFlights(linear.flights, pass.rows_effects, linear.system, pass.tls, options), pass.tls,
                      start, options, start_pass);
}

// Settled when no effect coordinate moved by more than a tenth of its std (without a covariance: by
// more than the effect's settle tolerance).
bool EffectsSettled(const RefineResult& result, const Effects& previous, const RefineOptions& options) {
  for (EffectKind kind : options.effects) {
    const Eigen::VectorXd change = (result.effects.Get(kind) - previous.Get(kind)).cwiseAbs();
    const Eigen::VectorXd std_dev = result.effects_std.Get(kind);
    for (Eigen::Index k = 0; k < change.size(); ++k) {
      const double tolerance =
          k < std_dev.size() && std_dev[k] > 0.0 ? 0.1 * std_dev[k] : kind->info().settle_tolerance;
      if (change[k] > tolerance + 1e-12) return false;
    }
  }
  return true;
}

// The TLS weights and equation-error variances of the linear step were fitted to the residual of the
// uncorrected rows (a delay inflates the yaw equation's error, say), and its essential set to their
// precision. Re-runs the TLS, weights and selection included, on the rows corrected by the estimated
// effects, and refines again from there, until the effects settle. `result` is the first pass's;
// `pass` becomes the start of the pass whose result stands. Returns a warning, or empty.
std::string RefineReselected(const IdentificationResult& linear, const RefineOptions& options,
                             const std::function<void()>& step_done, RefineResult* result, PassStart* pass) {
  RefineOptions next = options;
  next.coarse_delay_search = false;
  Effects previous = result->effects;
  std::string held;  // of the pass whose result stands
  for (int pass_number = 2; pass_number <= kMaxRefinePasses; ++pass_number) {
    IdimSystem corrected{linear.system, SystemRowsWithEffects(linear, result->effects)};
    std::string pass_held;
    PassStart candidate_start{ReselectEssential(corrected, linear, &pass_held), result->effects};
    corrected.w = Eigen::MatrixXd();  // the pass needs its layout only; the rows are 100 MB on a 1 h log
    if (!candidate_start.tls.usable) {
      // No reselected pass follows: the loosely solved first pass is the result, so finish it.
      if (pass_number == 2) *result = SolvePass(linear, *pass, result->effects, next, /*start_pass=*/false);
      break;
    }
    RefineResult candidate = SolvePass(linear, candidate_start, result->effects, next, /*start_pass=*/false);
    candidate.reselected = candidate_start.tls;
    *result = std::move(candidate);
    *pass = std::move(candidate_start);
    held = pass_held;
    step_done();
    if (EffectsSettled(*result, previous, options)) break;
    previous = result->effects;
  }
  if (held.empty()) return {};
  return "the re-selection on the rows corrected by the effects brought back " + held +
         ", which the linear step discarded, with a sign their physics excludes: held discarded, as in the linear "
         "step (these flights fix their ratios, not their scale)";
}

// One rule for the essential parameters of both blocks (EssentialSelectionDrops, noise-aware): a refined
// essential parameter whose physics excludes 0 (kd, the inertia's diagonal) and whose refined %sigma
// breaks the selection's rule is discarded as the selection discards it: estimated beside the others
// (profiled), predicted with, not reported. The refinement estimated it already, and the others'
// covariance is their marginal one: relabelling moves no value. A first moment or a product of
// inertia would be held at 0 instead, which changes the model (on jana04 by PWM the cascade dropped
// ms_x and ms_y and Table III's Mx rose 27 -> 94 %): those stay essential with their refined std, and
// the check refined_identifiable names them.
void ApplyEssentialRule(const IdentificationResult& linear, RefineResult* result) {
  if (!result->has_covariance || linear.options.tls.method != TlsMethod::kNoiseAware) return;
  TlsSolution& refined = result->refined;
  const std::vector<std::string>& names = linear.system.parameter_names;
  if (refined.profiled.size() != refined.essential.size()) return;
  while (true) {
    std::vector<int> essential;
    for (int k = 0; k < linear.system.num_parameters(); ++k)
      if (refined.essential[k]) essential.push_back(k);
    Eigen::VectorXd rel(static_cast<Eigen::Index>(essential.size()));
    for (size_t a = 0; a < essential.size(); ++a) {
      const int k = essential[a];
      rel[static_cast<Eigen::Index>(a)] = k != 0 && PositiveByPhysics(names[k]) ? refined.rel_std_pct[k] : -1.0;
    }
    const int worst = EssentialSelectionDrops(rel, linear.options.tls);
    if (worst < 0) break;
    const int k = essential[static_cast<size_t>(worst)];
    DiscardedParameter dropped = DiscardedOf(names, essential, refined.chi(essential),
                                             refined.covariance(essential, essential), worst, rel[worst]);
    dropped.reason =
        "its refined %sigma exceeds the limit; estimated beside the others, not held at 0 (its "
        "physics excludes 0)";
    refined.discarded.push_back(dropped);
    refined.essential[k] = false;
    refined.profiled[k] = true;
    refined.profiled_chi[k] = refined.chi[k];
    refined.profiled_std[k] = refined.std[k];
    refined.chi[k] = 0.0;
    refined.covariance.row(k).setZero();
    refined.covariance.col(k).setZero();
    SetStdFromCovariance(names, &refined);
    LOG(INFO) << "refined block: " << names[k] << " discarded at " << dropped.rel_std_pct << " % relative std";
  }
  SetAllowedRanges(linear.system, ConfigurationMasses(linear.flights), &refined);
}

// The warnings of a finished refinement: estimates on a bound, pinned spin patterns, estimates relative
// to an unstated reference, confounded pairs.
void AddRefineWarnings(const IdentificationResult& linear, const RefineOptions& options, RefineResult* result) {
  // Estimates on a bound are not estimates.
  result->on_bound = EffectsOnBound(*result, options);
  for (EffectKind kind : result->on_bound)
    result->warnings.push_back(kind->parameter_name() +
                               " ended on the bound of its physical range: these flights do not determine it "
                               "(or the residual has a cause outside the modelled effects); do not trust it");
  // Coordinates of one effect whose pins (its held directions) tie them: their correlation is the pins'.
  std::vector<std::string> pinned_prefixes;
  for (EffectKind kind : options.effects)
    if (HeldDirections(kind, linear.flights.front().vehicle, KdFree(linear.system, result->refined)).cols() > 0) {
      pinned_prefixes.push_back(kind->parameter_name() + "_");
      result->warnings.push_back(kind->parameter_name() +
                                 ": the rotors' spin pattern of its values (sum of spin x value) "
                                 "is held at 0: kd is not estimated, and without the yaw torque that pattern shows "
                                 "only as a roll-pitch coupling (X layout: what I_xy does) or as roll against pitch "
                                 "gain (+ layout: what I_xx / I_yy do)");
    }
  // Estimates relative to a known value the vehicle file leaves out (rotor_drag's k_f and the IMU's height).
  for (EffectKind kind : result->enabled)
    for (const ProcessedFlight& flight : linear.flights) {
      const std::string reads = kind->UnstatedReference(result->effects.Get(kind), flight.vehicle);
      if (!reads.empty()) {
        result->warnings.push_back(reads);
        break;
      }
    }
  const auto tied_by_pins = [&](int a, int b) {
    return std::any_of(pinned_prefixes.begin(), pinned_prefixes.end(), [&](const std::string& prefix) {
      return result->effect_labels[a].rfind(prefix, 0) == 0 && result->effect_labels[b].rfind(prefix, 0) == 0;
    });
  };
  // Confounded effects: say how much, and what the data fix instead.
  for (int a = 0; a < result->effect_correlation.rows(); ++a)
    for (int b = a + 1; b < result->effect_correlation.cols(); ++b)
      if (std::abs(result->effect_correlation(a, b)) > 0.9 && !tied_by_pins(a, b))
        result->warnings.push_back(result->effect_labels[a] + " and " + result->effect_labels[b] +
                                   " are strongly correlated (" + std::to_string(result->effect_correlation(a, b)) +
                                   "): these flights separate them poorly" + WhatATradingPairFixes(*result, a, b));
}

}  // namespace

RefineResult Refine(const IdentificationResult& linear, const RefineOptions& options, const StepProgress& progress) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  for (EffectKind kind : options.effects)
    for (const ProcessedFlight& flight : linear.flights)
      if (const std::string why = kind->Unavailable(flight.inputs()); !why.empty())
        throw Error(flight.source + ": " + why);
  Effects start = options.initial;
  const int total_steps = RefineSteps(options);
  int steps_done = 0;
  const std::function<void()> step_done = [&]() {
    if (progress) progress(++steps_done, total_steps);
  };
  if (SearchesDelayGrid(options)) {
    for (EffectKind kind : options.effects)
      if (kind->info().grid_searched) start.Set(kind, CoarseDelaySearch(linear, options, kind));
    step_done();
  }
  const bool reselects = options.reselect_essential && !options.effects.empty();
  PassStart pass{linear.solution, Effects{}};
  RefineResult result = SolvePass(linear, pass, start, options, /*start_pass=*/reselects);
  step_done();
  const std::string held = reselects ? RefineReselected(linear, options, step_done, &result, &pass) : "";
  if (progress && steps_done < total_steps) progress(total_steps, total_steps);
  // With no effect the refinement is the TLS, whose selection stands (the refined covariance, from the
  // Jacobian of the whitened rows, differs from the TLS's by some % of itself: a product of inertia the
  // TLS kept under 10 % read 11.3 % on a 30 s flight).
  if (!options.effects.empty()) ApplyEssentialRule(linear, &result);
  if (!held.empty()) result.warnings.push_back(held);
  NoteBodyConstraint(&result);
  AddRefineWarnings(linear, options, &result);
  result.linear_criterion = EffectCriterion(linear, Effects{});
  result.refined_criterion = EffectCriterion(linear, result.effects);
  result.relative_error_pct = RelativeErrorWithEffects(
      linear.flights, NamedParameters(linear.system, PredictionChi(result.refined)), result.effects);
  return result;
}

}  // namespace rotorid

#include "refine/grid_search.h"

#include <Eigen/QR>
#include <algorithm>
#include <optional>

#include "core/parallel_for.h"
#include "rotorid/core/error.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/refine/effect_model.h"
#include "rotorid/refine/refine.h"

namespace rotorid::internal {

std::vector<double> SearchGrid(double min, double max, double step) {
  std::vector<double> grid;
  for (double value = min; value <= max + 1e-12; value += step) grid.push_back(value);
  return grid;
}

Eigen::MatrixXd SystemColumnsWithEffects(const IdentificationResult& linear, const Effects& effects,
                                         const std::vector<int>& columns) {
  const IdimSystem& system = linear.system;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(system.num_rows(), static_cast<Eigen::Index>(columns.size()));
  Eigen::Index row = 0;
  for (int f = 0; f < system.num_flights(); ++f) {
    const Eigen::MatrixXd wf = BuildIdimMatrixWithEffects(linear.flights[f], effects);
    for (Eigen::Index k = 0; k < wf.cols(); ++k) {
      const auto at = std::find(columns.begin(), columns.end(), system.SystemColumn(f, static_cast<int>(k)));
      if (at != columns.end()) out.col(at - columns.begin()).segment(row, wf.rows()) = wf.col(k);
    }
    row += wf.rows();
  }
  return out;
}

namespace {

// The criterion along the grid of a rotor-signal effect (the delay). Such an effect moves only the
// rotor columns (kt, kd) and, when a rotor-wrench effect acts, the known column (its extra wrench
// follows the rotor speeds); the body columns come from the IMU alone. So the weighted fixed columns
// B are factored once, B = Q_B [R_B; 0], and per grid value only the changing columns A are:
// [R_B, Q_B^T A; 0, R of (I - Q_B Q_B^T) A] has the Gram matrix of the weighted [B A], which is all
// that MinimumTlsCriterionOfFactor needs (columns put back in the criterion's order). The same
// criterion as EffectCriterion to round-off, for a QR of the changing columns per grid value
// instead of one of all columns, and rows built once.
class RotorSignalGrid {
 public:
  RotorSignalGrid(const IdentificationResult& linear, const Effects& base, EffectKind kind)
      : linear_(linear), base_(base), kind_(kind) {
    const TlsSolution& solution = linear.solution;
    const int known = static_cast<int>(solution.chi.size());
    Effects trial = base;
    trial.Set(kind, 0.0);
    wrench_acts_ = !ActingEffects(trial, EffectStage::kRotorWrench).kinds.empty();
    for (int column : CriterionColumns(solution)) {
      const bool changes = column < kNumRotorCoefficients || (wrench_acts_ && column == known);
      (changes ? changing_ : fixed_).push_back(column);
    }
    sqrt_weight_ = solution.row_weight.cwiseSqrt();
    FactorFixedColumns(sqrt_weight_.asDiagonal() * SystemColumnsWithEffects(linear, trial, fixed_));
  }

  double Criterion(double value) const {
    Effects trial = base_;
    trial.Set(kind_, value);
    const Eigen::Index n_fixed = static_cast<Eigen::Index>(fixed_.size());
    const Eigen::Index n_changing = static_cast<Eigen::Index>(changing_.size());
    Eigen::MatrixXd changing =
        sqrt_weight_.asDiagonal() *
        (wrench_acts_ ? SystemColumnsWithEffects(linear_, trial, changing_) : RotorColumns(trial));
    changing.noalias() -= reflectors_ * (block_factor_.transpose() * (reflectors_.transpose() * changing));  // Q_B^T A
    Eigen::Ref<Eigen::MatrixXd> rest = changing.bottomRows(changing.rows() - n_fixed);
    const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> rest_qr(rest);  // in place: no copy of the rows
    // The factor in the order [fixed, changing], then its columns back in the criterion's order.
    Eigen::MatrixXd factor = Eigen::MatrixXd::Zero(n_fixed + n_changing, n_fixed + n_changing);
    factor.topLeftCorner(n_fixed, n_fixed) = fixed_r_;
    factor.topRightCorner(n_fixed, n_changing) = changing.topRows(n_fixed);
    factor.bottomRightCorner(n_changing, n_changing) =
        rest_qr.matrixQR().topRows(n_changing).triangularView<Eigen::Upper>();
    const std::vector<int> columns = CriterionColumns(linear_.solution);
    Eigen::MatrixXd ordered(factor.rows(), factor.cols());
    for (Eigen::Index k = 0; k < factor.cols(); ++k) {
      const int column = k < n_fixed ? fixed_[static_cast<size_t>(k)] : changing_[static_cast<size_t>(k - n_fixed)];
      ordered.col(std::find(columns.begin(), columns.end(), column) - columns.begin()) = factor.col(k);
    }
    return MinimumTlsCriterionOfFactor(ordered, linear_.solution);
  }

 private:
  // The changing columns without a rotor-wrench effect: the rotor columns (kt, kd) of every flight's
  // rows with `effects`, -D_k at the effective rotor speeds as IdimRows writes them, without the
  // body columns that IMU-only work would build for nothing.
  Eigen::MatrixXd RotorColumns(const Effects& effects) const {
    Eigen::MatrixXd out(linear_.system.num_rows(), static_cast<Eigen::Index>(changing_.size()));
    Eigen::Index row = 0;
    for (const ProcessedFlight& flight : linear_.flights) {
      const Eigen::MatrixXd rotor_speed = EffectiveRotorSpeedAtRows(flight, effects);
      Eigen::VectorXd speed(rotor_speed.cols());
      for (int r = 0; r < flight.num_rows_samples(); ++r, row += 6) {
        speed = rotor_speed.row(r).transpose();
        const Eigen::Matrix<double, 6, kNumRotorCoefficients> columns = -RotorRegressor<double>(speed, flight.vehicle);
        for (size_t k = 0; k < changing_.size(); ++k)
          out.block<6, 1>(row, static_cast<Eigen::Index>(k)) = columns.col(changing_[k]);
      }
    }
    return out;
  }

  // B = Q_B [R_B; 0] by Householder QR, kept as R_B and Q_B = I - V T V^T in the compact WY form
  // (LAPACK's larft): Q_B^T A is then two products over the rows, one pass each through V and A,
  // where applying the reflectors one by one passes through A once per reflector (on a 1 h log A is
  // 70 MB, and that was a third of the grid's time).
  void FactorFixedColumns(Eigen::MatrixXd columns) {
    const Eigen::Index k = columns.cols();
    const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(columns);  // in place
    fixed_r_ = qr.matrixQR().topRows(k).triangularView<Eigen::Upper>();
    const Eigen::VectorXd tau = qr.hCoeffs();
    for (Eigen::Index j = 0; j < k; ++j) {  // V: the reflectors, unit lower trapezoidal
      columns.col(j).head(j).setZero();
      columns(j, j) = 1.0;
    }
    const Eigen::MatrixXd gram = columns.transpose() * columns;  // V^T V
    block_factor_ = Eigen::MatrixXd::Zero(k, k);
    for (Eigen::Index i = 0; i < k; ++i) {
      block_factor_(i, i) = tau[i];
      if (i == 0) continue;
      const Eigen::VectorXd product = block_factor_.topLeftCorner(i, i) * gram.col(i).head(i);  // T upper so far
      block_factor_.col(i).head(i) = -tau[i] * product;
    }
    reflectors_ = std::move(columns);
  }

  const IdentificationResult& linear_;
  const Effects& base_;
  EffectKind kind_;
  bool wrench_acts_ = false;
  std::vector<int> fixed_, changing_;  // criterion columns; changing_ are rotor columns, then the known one
  Eigen::VectorXd sqrt_weight_;
  Eigen::MatrixXd fixed_r_, reflectors_, block_factor_;  // R_B, V, T
};

// The criterion at any values of `kind`: the rotor-signal grid's factor built once for all of them.
class GridCriterion {
 public:
  GridCriterion(const IdentificationResult& linear, const Effects& base, EffectKind kind, int threads)
      : linear_(linear), base_(base), kind_(kind), threads_(threads) {
    if (kind->stage() == EffectStage::kRotorSignal) rotor_grid_.emplace(linear, base, kind);
  }

  std::vector<double> At(const std::vector<double>& values) const {
    std::vector<double> criterion(values.size(), 0.0);
    ParallelFor(static_cast<int>(values.size()), threads_, [&](int i) {
      const double value = values[static_cast<size_t>(i)];
      if (rotor_grid_) {
        criterion[static_cast<size_t>(i)] = rotor_grid_->Criterion(value);
        return;
      }
      Effects trial = base_;
      trial.Set(kind_, value);
      criterion[static_cast<size_t>(i)] = EffectCriterion(linear_, trial);
    });
    return criterion;
  }

 private:
  const IdentificationResult& linear_;
  const Effects& base_;
  EffectKind kind_;
  int threads_;
  std::optional<RotorSignalGrid> rotor_grid_;
};

}  // namespace

std::vector<double> CriterionOverGrid(const IdentificationResult& linear, const Effects& base, EffectKind kind,
                                      const std::vector<double>& grid, int threads) {
  return GridCriterion(linear, base, kind, threads).At(grid);
}

double CoarseToFineGridMinimum(const IdentificationResult& linear, const Effects& base, EffectKind kind,
                               const std::vector<double>& grid, int threads) {
  constexpr size_t kStride = 3;
  if (grid.empty()) throw Error("internal: empty search grid");
  const GridCriterion criterion_at(linear, base, kind, threads);
  std::vector<size_t> indices;
  for (size_t k = 0; k < grid.size(); k += kStride) indices.push_back(k);
  if (indices.back() + 1 != grid.size()) indices.push_back(grid.size() - 1);
  const auto values_at = [&grid](const std::vector<size_t>& at) {
    std::vector<double> values;
    for (size_t k : at) values.push_back(grid[k]);
    return values;
  };
  std::vector<double> criterion = criterion_at.At(values_at(indices));
  const size_t coarse_best = indices[std::min_element(criterion.begin(), criterion.end()) - criterion.begin()];
  std::vector<size_t> around;
  for (size_t k = coarse_best >= kStride - 1 ? coarse_best - (kStride - 1) : 0;
       k <= std::min(grid.size() - 1, coarse_best + kStride - 1); ++k)
    if (std::find(indices.begin(), indices.end(), k) == indices.end()) around.push_back(k);
  const std::vector<double> around_criterion = criterion_at.At(values_at(around));
  indices.insert(indices.end(), around.begin(), around.end());
  criterion.insert(criterion.end(), around_criterion.begin(), around_criterion.end());
  size_t best = 0;
  for (size_t j = 1; j < indices.size(); ++j)
    if (criterion[j] < criterion[best] || (criterion[j] == criterion[best] && indices[j] < indices[best])) best = j;
  return grid[indices[best]];
}

}  // namespace rotorid::internal

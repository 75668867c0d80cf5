#include "refine/idim_residual.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

#include "refine/effect_rows.h"
#include "rotorid/ident/identify.h"
#include "rotorid/ident/tls.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/refine/refine.h"

namespace rotorid::internal {

Effects EffectBlocks::At(double const* const* parameters, const Vehicle& vehicle) const {
  Effects effects = fixed;
  for (size_t j = 0; j < free.size(); ++j)
    effects.Set(free[j], Scale(j) * Eigen::Map<const Eigen::VectorXd>(parameters[1 + j], free[j]->Dimension(vehicle)));
  return effects;
}

namespace {

// M_c - mean(M_c) at the row samples for the anchored components, from the rotor speeds there.
Eigen::MatrixXd CentredRotorMoments(const RotorMomentAnchor& anchor, const Eigen::MatrixXd& speed) {
  Eigen::MatrixXd moments = speed.cwiseAbs2() * anchor.unit.transpose();  // rows x 6
  moments.rowwise() -= moments.colwise().mean();
  return moments;
}

}  // namespace

RotorMomentAnchor AnchorRotorMoments(const ProcessedFlight& flight, const Effects& effects, const IdimLayout& system,
                                     int index, const Eigen::VectorXd& chi) {
  RotorMomentAnchor anchor;
  const int rotors = flight.vehicle.num_rotors();
  anchor.unit = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, rotors);
  for (int i = 0; i < rotors; ++i) {
    const Eigen::VectorXd one = Eigen::VectorXd::Unit(rotors, i);
    const Eigen::Matrix<double, 6, kNumRotorCoefficients> d = RotorRegressor<double>(one, flight.vehicle);
    anchor.unit.col(i) = d.col(0) * chi[0] + d.col(1) * chi[1];
  }
  anchor.unit.topRows<3>().setZero();  // the force rows are anchored by the mass
  const Eigen::MatrixXd moments = CentredRotorMoments(anchor, EffectiveRotorAtRows(flight, Effects{}, {}).speed);
  const int samples = flight.num_rows_samples();
  Eigen::VectorXd chi_t(chi.size() + 1);
  chi_t << chi, 1.0;
  const Eigen::VectorXd flight_chi = FlightChiT(flight, NamedParameters(system, chi));  // in the flight's columns
  const EffectiveRotor rotor = EffectiveRotorAtRows(flight, effects, {});
  const EffectRows rows(&flight, effects, {}, &rotor);
  const EffectRows::PassValues<double> pass = rows.Pass<double>();
  std::array<double, 6> residual{};
  for (int s = 0; s < samples; ++s) {
    const Eigen::Matrix<double, 6, kNumIdimColumns> w = rows.Rows<double>(s, pass);
    for (int c = 3; c < 6; ++c) residual[c] += std::pow(w.row(c).dot(flight_chi), 2);
  }
  Eigen::VectorXd rotor_t = Eigen::VectorXd::Zero(chi_t.size());
  rotor_t.head<kNumRotorCoefficients>() = chi.head<kNumRotorCoefficients>();
  for (int c = 3; c < 6; ++c) {
    anchor.power[c] = moments.col(c).squaredNorm();
    // Per-row variances at the start: the residual, the noise model's share of it, and the rotor
    // signal's part of that.
    const double mean_residual = residual[c] / std::max(samples, 1);
    const Eigen::MatrixXd& noise_cov = system.group_noise_cov[static_cast<size_t>(6 * index + c)];
    const double noise = std::max(chi_t.dot(noise_cov * chi_t), 0.0) / std::max(samples, 1);
    const double rotor_noise = std::clamp(rotor_t.dot(noise_cov * rotor_t) / std::max(samples, 1), 0.0, noise);
    const double scaling = std::max(mean_residual - noise, 0.0) + rotor_noise;
    const double total = std::max(mean_residual, noise);
    anchor.share[c] = total > 0.0 ? std::clamp(scaling / total, 0.0, 1.0) : 1.0;
  }
  LOG(INFO) << "anchored criterion, " << flight.source << ": share of the residual that scales with the rotor moment "
            << "Mx " << anchor.share[3] << ", My " << anchor.share[4] << ", Mz " << anchor.share[5];
  return anchor;
}

std::shared_ptr<const RotorSignalCache::State> RotorSignalCache::Get(const Effects& effects) const {
  std::vector<double> key_values;
  for (EffectKind kind : EffectsOfStage(EffectStage::kRotorSignal)) {
    const Eigen::VectorXd v = effects.Get(kind);
    key_values.insert(key_values.end(), v.data(), v.data() + v.size());
  }
  const Eigen::VectorXd key = Eigen::Map<const Eigen::VectorXd>(key_values.data(), key_values.size());
  std::lock_guard<std::mutex> lock(mutex_);
  if (!state_ || state_->key.size() != key.size() || state_->key != key) {
    std::vector<EffectKind> free;
    for (EffectKind kind : blocks_->free)
      if (kind->stage() == EffectStage::kRotorSignal) free.push_back(kind);
    auto state = std::make_shared<State>();
    state->key = key;
    state->rotor = EffectiveRotorAtRows(*flight_, effects, free);
    if (anchor_) SetGains(state.get());
    state_ = state;
  }
  return state_;
}

IdimResidualBlock::IdimResidualBlock(const ProcessedFlight* flight, const RotorSignalCache* rotor,
                                     const CriterionContext* context, const EffectBlocks* blocks,
                                     const std::array<int, kNumBodyParameters>& body_columns, int first, int count,
                                     Eigen::VectorXd sqrt_weight)
    : flight_(flight),
      rotor_(rotor),
      context_(context),
      blocks_(blocks),
      body_columns_(body_columns),
      first_(first),
      count_(count),
      sqrt_weight_(std::move(sqrt_weight)) {
  set_num_residuals(6 * count);
  mutable_parameter_block_sizes()->push_back(context->num_parameters);
  for (EffectKind kind : blocks->free) mutable_parameter_block_sizes()->push_back(kind->Dimension(flight->vehicle));
}

// g_c = sqrt(P_c / P_c(no effects)), P_c = sum_s (M_c(s) - mean)^2, and
// d g_c / d theta = sum_s (M_c(s) - mean) d M_c(s) / d theta / (g_c P_c(no effects)) (the mean's
// derivative drops out against the centred sum), d M_c / d theta = sum_i u_ci 2 Omega_i d Omega_i;
// h_c = sqrt(1 - s_c + s_c g_c^2), d h_c = s_c g_c d g_c / h_c.
void RotorSignalCache::SetGains(State* state) const {
  const Eigen::MatrixXd& speed = state->rotor.speed;
  const Eigen::MatrixXd moments = CentredRotorMoments(*anchor_, speed);
  const size_t coordinates = state->rotor.derivative.size();
  state->gain_derivative = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, static_cast<Eigen::Index>(coordinates));
  for (int c = 0; c < 6; ++c) {
    if (!(anchor_->power[c] > 0.0)) continue;
    const double g = std::sqrt(moments.col(c).squaredNorm() / anchor_->power[c]);
    const double share = anchor_->share[c];
    state->gain[c] = std::sqrt(1.0 - share + share * g * g);
    if (!(g > 0.0) || !(state->gain[c] > 0.0)) continue;
    for (size_t d = 0; d < coordinates; ++d) {
      const Eigen::VectorXd moment_derivative =
          (2.0 * speed.cwiseProduct(state->rotor.derivative[d])) * anchor_->unit.row(c).transpose();
      const double dg = moments.col(c).dot(moment_derivative) / (g * anchor_->power[c]);
      state->gain_derivative(c, static_cast<Eigen::Index>(d)) = share * g * dg / state->gain[c];
    }
  }
}

// What every pass shares: the criterion's scale, chi and the effect-laden rows.
struct IdimResidualBlock::Point {
  Eigen::VectorXd n_chi;
  double d = 0.0, d_sq = 0.0;
  Eigen::Matrix<double, kNumIdimColumns, 1> flight_chi;
  std::shared_ptr<const RotorSignalCache::State> rotor;
  std::unique_ptr<EffectRows> rows;
};

template <typename T>
void IdimResidualBlock::EvaluatePass(const Point& point, size_t first_coordinate, double* residuals,
                                     double** jacobians) const {
  const int p = context_->num_parameters;
  const std::vector<EffectRows::Coordinate>& coordinates = point.rows->coordinates();
  size_t last_coordinate = first_coordinate;
  if constexpr (!std::is_same_v<T, double>)
    last_coordinate = std::min(coordinates.size(), first_coordinate + T::DIMENSION);
  const EffectRows::PassValues<T> pass = point.rows->Pass<T>(first_coordinate);
  for (int s = 0; s < count_; ++s) {
    const Eigen::Matrix<T, 6, kNumIdimColumns> rows = point.rows->Rows<T>(first_ + s, pass);
    for (int c = 0; c < 6; ++c) {
      const int out = 6 * s + c;
      const double gain = point.rotor->gain[c];
      const double scale = sqrt_weight_[out] / (point.d * gain);
      T e(0.0);
      for (int k = 0; k < kNumIdimColumns; ++k) e += rows(c, k) * point.flight_chi[k];
      if (first_coordinate == 0) residuals[out] = scale * ScalarPart(e);
      if (!jacobians) continue;
      if (first_coordinate == 0 && jacobians[0]) {
        double* j = jacobians[0] + static_cast<size_t>(out) * p;
        for (int k = 0; k < p; ++k) j[k] = -residuals[out] * point.n_chi[k] / (context_->total_rows * point.d_sq);
        j[0] += scale * ScalarPart(rows(c, 0));
        j[1] += scale * ScalarPart(rows(c, 1));
        for (int k = 0; k < kNumBodyParameters; ++k) j[body_columns_[k]] += scale * ScalarPart(rows(c, 2 + k));
        for (int k = 0; k < p; ++k) j[k] *= context_->chi_scale[k];
      }
      if constexpr (!std::is_same_v<T, double>)
        for (size_t k = first_coordinate; k < last_coordinate; ++k) {
          const EffectRows::Coordinate& coordinate = coordinates[k];
          double* j = jacobians[1 + coordinate.effect];
          if (!j) continue;
          const int size = parameter_block_sizes()[1 + coordinate.effect];
          double derivative = scale * e.v[k - first_coordinate];
          if (coordinate.rotor_derivative >= 0 && point.rotor->gain_derivative.cols() > 0)
            derivative -= scale * ScalarPart(e) * point.rotor->gain_derivative(c, coordinate.rotor_derivative) / gain;
          j[out * size + coordinate.index] = blocks_->Scale(static_cast<size_t>(coordinate.effect)) * derivative;
        }
    }
  }
}

bool IdimResidualBlock::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int p = context_->num_parameters;
  Eigen::VectorXd chi_t(p + 1);
  chi_t << Eigen::Map<const Eigen::VectorXd>(parameters[0], p).cwiseProduct(context_->chi_scale), 1.0;
  Point point;
  point.n_chi = context_->metric * chi_t;
  point.d_sq = chi_t.dot(point.n_chi) / context_->total_rows;
  if (!(point.d_sq > 0.0)) return false;
  point.d = std::sqrt(point.d_sq);
  point.flight_chi[0] = chi_t[0];
  point.flight_chi[1] = chi_t[1];
  for (int k = 0; k < kNumBodyParameters; ++k) point.flight_chi[kNumRotorCoefficients + k] = chi_t[body_columns_[k]];
  point.flight_chi[kNumIdimColumns - 1] = 1.0;
  const Effects effects = blocks_->At(parameters, flight_->vehicle);
  point.rotor = rotor_->Get(effects);
  point.rows = std::make_unique<EffectRows>(flight_, effects, blocks_->free, &point.rotor->rotor);
  const size_t coordinates = point.rows->coordinates().size();
  bool effect_jacobians = false;
  for (size_t b = 0; jacobians && b < blocks_->free.size(); ++b) effect_jacobians |= jacobians[1 + b] != nullptr;
  if (!effect_jacobians || coordinates == 0) {
    EvaluatePass<double>(point, 0, residuals, jacobians);
    return true;
  }
  // Passes of the widest Jet while more coordinates remain than the middle one holds, then the
  // narrowest that takes the rest (13 coordinates: 12 + 1 in a Jet of 4, not two Jets of 12).
  for (size_t first = 0; first < coordinates;) {
    const size_t remaining = coordinates - first;
    if (remaining <= static_cast<size_t>(kImuJetSize)) {
      EvaluatePass<ImuJet>(point, first, residuals, jacobians);
      first += kImuJetSize;
    } else if (remaining <= static_cast<size_t>(kMidImuJetSize)) {
      EvaluatePass<MidImuJet>(point, first, residuals, jacobians);
      first += kMidImuJetSize;
    } else {
      EvaluatePass<WideImuJet>(point, first, residuals, jacobians);
      first += kWideImuJetSize;
    }
  }
  return true;
}

}  // namespace rotorid::internal

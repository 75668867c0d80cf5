#include "refine/idim_residual.h"

#include <algorithm>

#include "rotorid/ident/tls.h"
#include "rotorid/model/rigid_body.h"

namespace rotorid::internal {

Effects EffectBlocks::At(double const* const* parameters, const Vehicle& vehicle) const {
  Effects effects = fixed;
  for (size_t j = 0; j < free.size(); ++j)
    effects.Set(free[j], Eigen::Map<const Eigen::VectorXd>(parameters[1 + j], free[j]->Dimension(vehicle)));
  return effects;
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
    state_ = state;
  }
  return state_;
}

IdimResidualBlock::IdimResidualBlock(const ProcessedFlight* flight, const RotorSignalCache* rotor,
                                     const CriterionContext* context, const EffectBlocks* blocks, int config, int first,
                                     int count, Eigen::VectorXd sqrt_weight)
    : flight_(flight),
      rotor_(rotor),
      context_(context),
      blocks_(blocks),
      config_(config),
      first_(first),
      count_(count),
      sqrt_weight_(std::move(sqrt_weight)) {
  set_num_residuals(6 * count);
  mutable_parameter_block_sizes()->push_back(context->num_parameters);
  for (EffectKind kind : blocks->free) mutable_parameter_block_sizes()->push_back(kind->Dimension(flight->vehicle));
}

// What every pass shares: the criterion's scale, chi, the effect values and the rotor signal.
struct IdimResidualBlock::Point {
  Effects effects;
  std::shared_ptr<const RotorSignalCache::State> rotor;
  Eigen::VectorXd n_chi;
  double d = 0.0, d_sq = 0.0;
  Eigen::Matrix<double, kNumIdimColumns, 1> flight_chi;
  // The free scalar coordinates: block (index into blocks_->free) and coordinate; the rotor-signal
  // ones also index the cached derivatives.
  struct Coordinate {
    int block, index, rotor_derivative;
  };
  std::vector<Coordinate> coordinates;
};

template <typename T>
void IdimResidualBlock::EvaluatePass(const Point& point, size_t first_coordinate, double* residuals,
                                     double** jacobians) const {
  constexpr bool kIsJet = !std::is_same_v<T, double>;
  const int p = context_->num_parameters;
  const int c0 = IdimSystem::ConfigColumn(config_);
  const EffectiveRotor& rotor = point.rotor->rotor;
  // The coordinates differentiated in this pass and their Jet slots.
  std::vector<std::pair<const Point::Coordinate*, int>> slots;
  if constexpr (kIsJet) {
    const size_t last = std::min(point.coordinates.size(), first_coordinate + T::DIMENSION);
    for (size_t c = first_coordinate; c < last; ++c)
      slots.emplace_back(&point.coordinates[c], static_cast<int>(c - first_coordinate));
  }
  // IMU effects: every one that acts (non-zero or free), in chain order.
  std::vector<EffectKind> chain;
  std::vector<Eigen::Matrix<T, Eigen::Dynamic, 1>> values;
  for (EffectKind kind : EffectsOfStage(EffectStage::kImuSensor)) {
    const auto it = std::find(blocks_->free.begin(), blocks_->free.end(), kind);
    if (it == blocks_->free.end() && point.effects.IsZero(kind)) continue;
    chain.push_back(kind);
    values.push_back(point.effects.Get(kind).cast<T>());
    if constexpr (kIsJet)
      for (const auto& [coordinate, slot] : slots)
        if (blocks_->free[coordinate->block] == kind) values.back()[coordinate->index].v[slot] = 1.0;
  }
  std::vector<const T*> parameters;
  for (const auto& v : values) parameters.push_back(v.data());

  const int rotors = flight_->vehicle.num_rotors();
  Eigen::Matrix<T, Eigen::Dynamic, 1> omega(rotors);
  for (int s = 0; s < count_; ++s) {
    const int row_sample = first_ + s;
    const int i = flight_->row_samples[row_sample];
    for (int k = 0; k < rotors; ++k) {
      omega[k] = T(rotor.speed(row_sample, k));
      if constexpr (kIsJet)
        for (const auto& [coordinate, slot] : slots)
          if (coordinate->rotor_derivative >= 0)
            omega[k].v[slot] = rotor.derivative[coordinate->rotor_derivative](row_sample, k);
    }
    ImuSample<T> imu = LoggedImu<T>(*flight_, i);
    CorrectImu<T>(chain, parameters, &imu);
    const Eigen::Matrix<T, 6, kNumIdimColumns> rows =
        IdimRows<T>(imu.angular_velocity, imu.angular_acceleration, imu.specific_force, omega, flight_->vehicle);
    for (int c = 0; c < 6; ++c) {
      const int out = 6 * s + c;
      const double scale = sqrt_weight_[out] / point.d;
      T e(0.0);
      for (int k = 0; k < kNumIdimColumns; ++k) e += rows(c, k) * point.flight_chi[k];
      const double e_value = ScalarPart(e);
      if (first_coordinate == 0) residuals[out] = scale * e_value;
      if (!jacobians) continue;
      if (first_coordinate == 0 && jacobians[0]) {
        double* j = jacobians[0] + static_cast<size_t>(out) * p;
        for (int k = 0; k < p; ++k) j[k] = -residuals[out] * point.n_chi[k] / (context_->total_rows * point.d_sq);
        j[0] += scale * ScalarPart(rows(c, 0));
        j[1] += scale * ScalarPart(rows(c, 1));
        for (int k = 0; k < kNumBodyParameters; ++k) j[c0 + k] += scale * ScalarPart(rows(c, 2 + k));
        for (int k = 0; k < p; ++k) j[k] *= context_->chi_scale[k];
      }
      if constexpr (kIsJet)
        for (const auto& [coordinate, slot] : slots) {
          double* j = jacobians[1 + coordinate->block];
          if (!j) continue;
          const int size = parameter_block_sizes()[1 + coordinate->block];
          j[out * size + coordinate->index] = scale * e.v[slot];
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
  const int c0 = IdimSystem::ConfigColumn(config_);
  point.flight_chi << chi_t[0], chi_t[1], chi_t.segment(c0, kNumBodyParameters), 1.0;
  point.effects = blocks_->At(parameters, flight_->vehicle);
  point.rotor = rotor_->Get(point.effects);
  int rotor_derivative = 0;
  for (size_t b = 0; b < blocks_->free.size(); ++b) {
    const bool on_rotor = blocks_->free[b]->stage() == EffectStage::kRotorSignal;
    for (int a = 0; a < parameter_block_sizes()[1 + b]; ++a)
      point.coordinates.push_back({static_cast<int>(b), a, on_rotor ? rotor_derivative++ : -1});
  }
  bool effect_jacobians = false;
  for (size_t b = 0; jacobians && b < blocks_->free.size(); ++b) effect_jacobians |= jacobians[1 + b] != nullptr;
  if (!effect_jacobians || point.coordinates.empty()) {
    EvaluatePass<double>(point, 0, residuals, jacobians);
  } else if (point.coordinates.size() <= kImuJetSize) {
    EvaluatePass<ImuJet>(point, 0, residuals, jacobians);
  } else {
    for (size_t first = 0; first < point.coordinates.size(); first += kWideImuJetSize)
      EvaluatePass<WideImuJet>(point, first, residuals, jacobians);
  }
  return true;
}

}  // namespace rotorid::internal

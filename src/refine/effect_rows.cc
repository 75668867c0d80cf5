#include "refine/effect_rows.h"

#include <ceres/jet.h>

#include <algorithm>

namespace rotorid::internal {

namespace {

template <typename T>
using VectorT = Eigen::Matrix<T, Eigen::Dynamic, 1>;

// The values of a stage's links as T, with the Jet slot of each coordinate in [first, last) seeded.
template <typename T>
std::vector<VectorT<T>> StageValues(const EffectChain& chain, const std::vector<int>& free_index,
                                    const std::vector<EffectRows::Coordinate>& coordinates, size_t first, size_t last) {
  std::vector<VectorT<T>> values;
  for (const Eigen::VectorXd& v : chain.values) values.push_back(v.cast<T>());
  if constexpr (!std::is_same_v<T, double>)
    for (size_t c = first; c < last; ++c)
      for (size_t j = 0; j < chain.kinds.size(); ++j)
        if (free_index[j] == coordinates[c].effect) values[j][coordinates[c].index].v[c - first] = 1.0;
  return values;
}

template <typename T>
std::vector<const T*> Pointers(const std::vector<VectorT<T>>& values) {
  std::vector<const T*> out;
  for (const auto& v : values) out.push_back(v.data());
  return out;
}

}  // namespace

EffectRows::EffectRows(const ProcessedFlight* flight, const Effects& effects, const std::vector<EffectKind>& free,
                       const EffectiveRotor* rotor)
    : flight_(flight), rotor_(rotor) {
  for (auto [stage, out] :
       {std::pair{EffectStage::kImuSensor, &imu_}, std::pair{EffectStage::kRotorWrench, &wrench_}}) {
    out->chain = ActingEffects(effects, stage, free);
    for (EffectKind kind : out->chain.kinds) {
      const auto it = std::find(free.begin(), free.end(), kind);
      out->free_index.push_back(it == free.end() ? -1 : static_cast<int>(it - free.begin()));
    }
  }
  for (EffectKind kind : imu_.chain.kinds) {
    const std::vector<FlightInput>& inputs = kind->info().inputs;
    imu_rates_ =
        imu_rates_ || std::find(inputs.begin(), inputs.end(), FlightInput::kSpecificForceRates) != inputs.end();
  }
  // EffectiveRotorAtRows lists the rotor-signal derivatives in chain order (the battery, first in
  // the chain, is last in the registry): each free rotor-signal effect's first one.
  std::vector<int> rotor_offset(free.size(), -1);
  int rotor_derivatives = 0;
  for (EffectKind kind : EffectsOfStage(EffectStage::kRotorSignal))
    if (const auto it = std::find(free.begin(), free.end(), kind); it != free.end()) {
      rotor_offset[static_cast<size_t>(it - free.begin())] = rotor_derivatives;
      rotor_derivatives += kind->Dimension(flight->vehicle);
    }
  for (size_t b = 0; b < free.size(); ++b)
    for (int a = 0; a < free[b]->Dimension(flight->vehicle); ++a)
      coordinates_.push_back({static_cast<int>(b), a, rotor_offset[b] < 0 ? -1 : rotor_offset[b] + a});
}

template <typename T>
EffectRows::PassValues<T> EffectRows::Pass(size_t first) const {
  PassValues<T> pass;
  pass.first = pass.last = first;
  if constexpr (!std::is_same_v<T, double>) pass.last = std::min(coordinates_.size(), first + T::DIMENSION);
  pass.imu = StageValues<T>(imu_.chain, imu_.free_index, coordinates_, first, pass.last);
  pass.wrench = StageValues<T>(wrench_.chain, wrench_.free_index, coordinates_, first, pass.last);
  pass.imu_pointers = Pointers(pass.imu);
  pass.wrench_pointers = Pointers(pass.wrench);
  return pass;
}

template <typename T>
Eigen::Matrix<T, 6, kNumIdimColumns> EffectRows::Rows(int row_sample, const PassValues<T>& pass) const {
  const int rotors = flight_->vehicle.num_rotors();
  const size_t first = pass.first, last = pass.last;
  VectorT<T> omega(rotors), omega_rate(rotors);
  for (int k = 0; k < rotors; ++k) {
    omega[k] = T(rotor_->speed(row_sample, k));
    omega_rate[k] = T(rotor_->acceleration(row_sample, k));
  }
  if constexpr (!std::is_same_v<T, double>)
    for (size_t c = first; c < last; ++c)
      if (const int d = coordinates_[c].rotor_derivative; d >= 0)
        for (int k = 0; k < rotors; ++k) {
          omega[k].v[c - first] = rotor_->derivative[d](row_sample, k);
          omega_rate[k].v[c - first] = rotor_->acceleration_derivative[d](row_sample, k);
        }
  const int i = flight_->row_samples[row_sample];
  ImuSample<T> imu = LoggedImu<T>(*flight_, i, imu_rates_);
  CorrectImu<T>(imu_.chain.kinds, pass.imu_pointers, &imu);
  Eigen::Matrix<T, 6, kNumIdimColumns> rows =
      IdimRows<T>(imu.angular_velocity, imu.angular_acceleration, imu.specific_force, omega, flight_->vehicle);
  if (wrench_.chain.kinds.empty()) return rows;
  RotorSample<T> sample = FlightRotorSample<T>(*flight_, i, omega, omega_rate, imu.angular_velocity);
  RotorWrenchTerms<T> terms(rotors);
  AddRotorWrench<T>(wrench_.chain.kinds, pass.wrench_pointers, sample, &terms);
  ApplyRotorWrenchTerms<T>(omega, flight_->vehicle, terms, &rows);
  return rows;
}

#define ROTORID_EFFECT_ROWS_OF(T)                                       \
  template EffectRows::PassValues<T> EffectRows::Pass<T>(size_t) const; \
  template Eigen::Matrix<T, 6, kNumIdimColumns> EffectRows::Rows<T>(int, const PassValues<T>&) const;
ROTORID_EFFECT_ROWS_OF(double)
ROTORID_EFFECT_ROWS_OF(ImuJet)
ROTORID_EFFECT_ROWS_OF(MidImuJet)
ROTORID_EFFECT_ROWS_OF(WideImuJet)
#undef ROTORID_EFFECT_ROWS_OF

}  // namespace rotorid::internal

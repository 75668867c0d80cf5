#include "refine/effect_rows.h"

#include <ceres/jet.h>

#include <algorithm>

namespace rotorid::internal {

EffectRows::EffectRows(const ProcessedFlight* flight, const Effects& effects, const std::vector<EffectKind>& free,
                       const EffectiveRotor* rotor)
    : flight_(flight), rotor_(rotor), imu_(ActingEffects(effects, EffectStage::kImuSensor, free)) {
  for (EffectKind kind : imu_.kinds)
    imu_free_.push_back(static_cast<int>(std::find(free.begin(), free.end(), kind) - free.begin()));
  for (int& f : imu_free_)
    if (f == static_cast<int>(free.size())) f = -1;
  int rotor_derivative = 0;
  for (size_t b = 0; b < free.size(); ++b) {
    const bool on_rotor = free[b]->stage() == EffectStage::kRotorSignal;
    for (int a = 0; a < free[b]->Dimension(flight->vehicle); ++a)
      coordinates_.push_back({static_cast<int>(b), a, on_rotor ? rotor_derivative++ : -1});
  }
}

template <typename T>
Eigen::Matrix<T, 6, kNumIdimColumns> EffectRows::Rows(int row_sample, size_t first) const {
  constexpr bool kIsJet = !std::is_same_v<T, double>;
  std::vector<Eigen::Matrix<T, Eigen::Dynamic, 1>> values;
  for (const Eigen::VectorXd& v : imu_.values) values.push_back(v.cast<T>());
  const int rotors = flight_->vehicle.num_rotors();
  Eigen::Matrix<T, Eigen::Dynamic, 1> omega(rotors);
  for (int k = 0; k < rotors; ++k) omega[k] = T(rotor_->speed(row_sample, k));
  if constexpr (kIsJet) {
    // The coordinates differentiated here, each with its Jet slot.
    const size_t last = std::min(coordinates_.size(), first + static_cast<size_t>(T::DIMENSION));
    for (size_t c = first; c < last; ++c) {
      const Coordinate& coordinate = coordinates_[c];
      const int slot = static_cast<int>(c - first);
      if (coordinate.rotor_derivative >= 0) {
        for (int k = 0; k < rotors; ++k)
          omega[k].v[slot] = rotor_->derivative[coordinate.rotor_derivative](row_sample, k);
        continue;
      }
      for (size_t j = 0; j < imu_.kinds.size(); ++j)
        if (imu_free_[j] == coordinate.effect) values[j][coordinate.index].v[slot] = 1.0;
    }
  }
  std::vector<const T*> parameters;
  for (const auto& v : values) parameters.push_back(v.data());
  ImuSample<T> imu = LoggedImu<T>(*flight_, flight_->row_samples[row_sample]);
  CorrectImu<T>(imu_.kinds, parameters, &imu);
  return IdimRows<T>(imu.angular_velocity, imu.angular_acceleration, imu.specific_force, omega, flight_->vehicle);
}

template Eigen::Matrix<double, 6, kNumIdimColumns> EffectRows::Rows<double>(int, size_t) const;
template Eigen::Matrix<ImuJet, 6, kNumIdimColumns> EffectRows::Rows<ImuJet>(int, size_t) const;
template Eigen::Matrix<WideImuJet, 6, kNumIdimColumns> EffectRows::Rows<WideImuJet>(int, size_t) const;

}  // namespace rotorid::internal

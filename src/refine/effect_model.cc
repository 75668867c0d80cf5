#include "rotorid/refine/effect_model.h"

#include <ceres/jet.h>

#include <algorithm>

#include "refine/effect_rows.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/signal/butterworth.h"
#include "rotorid/signal/differentiate.h"

namespace rotorid {
namespace {

// The rotor-signal chain on rotor `rotor`; parameters[j] are those of chain[j].
template <typename T>
Eigen::Matrix<T, Eigen::Dynamic, 1> TransformRotor(const ProcessedFlight& flight, const std::vector<EffectKind>& chain,
                                                   const std::vector<const T*>& parameters, Eigen::Index rotor) {
  const Eigen::Index n = flight.rotor_raw.rows();
  Eigen::Matrix<T, Eigen::Dynamic, 1> signal = flight.rotor_raw.col(rotor).cast<T>(), next;
  RotorSignalInput input;
  input.dt = flight.dt_s;
  Eigen::VectorXd command;
  if (flight.voltage_v && flight.voltage_v->size() == n) {
    input.voltage = &*flight.voltage_v;
    input.reference_voltage = flight.vehicle.command_to_speed_voltage_v.value_or(flight.voltage_v->mean());
  }
  if (flight.vehicle.command_to_speed) input.map = &*flight.vehicle.command_to_speed;
  if (flight.rotor_command && flight.rotor_command->rows() == n) {
    command = flight.rotor_command->col(rotor);
    input.command = &command;
  }
  for (size_t j = 0; j < chain.size(); ++j) {
    chain[j]->TransformRotorSignal(parameters[j], input, signal, &next);
    signal.swap(next);
  }
  return signal;
}

Eigen::MatrixXd TransformRotors(const ProcessedFlight& flight, const std::vector<EffectKind>& chain,
                                const std::vector<const double*>& parameters) {
  Eigen::MatrixXd out(flight.rotor_raw.rows(), flight.rotor_raw.cols());
  for (Eigen::Index r = 0; r < out.cols(); ++r) out.col(r) = TransformRotor<double>(flight, chain, parameters, r);
  return out;
}

// lowpass(y^2) of the rotor signal y after the chain, every sample (values only): the square
// the rotor entries are the root of.
Eigen::MatrixXd FilteredSquareAfterChain(const ProcessedFlight& flight, const EffectChain& acting) {
  Eigen::MatrixXd square = TransformRotors(flight, acting.kinds, acting.Parameters());
  square = square.array().square();  // in place: one whole-flight matrix less (23 MB on a 1 h log)
  return FiltFiltColumns(flight.filter, square);
}

}  // namespace

Eigen::MatrixXd RotorSignalWithEffects(const ProcessedFlight& flight, const Effects& effects) {
  const EffectChain chain = ActingEffects(effects, EffectStage::kRotorSignal);
  return TransformRotors(flight, chain.kinds, chain.Parameters());
}

EffectiveRotor EffectiveRotorAtRows(const ProcessedFlight& flight, const Effects& effects,
                                    const std::vector<EffectKind>& free) {
  const EffectChain acting = ActingEffects(effects, EffectStage::kRotorSignal, free);
  const std::vector<EffectKind>& chain = acting.kinds;
  const std::vector<Eigen::VectorXd>& values = acting.values;
  // The free coordinates, differentiated kRotorJetSize at a time.
  struct Coordinate {
    size_t link;
    int index;
  };
  std::vector<Coordinate> coordinates;
  for (size_t j = 0; j < chain.size(); ++j)
    if (std::find(free.begin(), free.end(), chain[j]) != free.end())
      for (int a = 0; a < values[j].size(); ++a) coordinates.push_back({j, a});
  const int rows = flight.num_rows_samples();
  const Eigen::Index rotors = flight.rotor_raw.cols(), n = flight.rotor_raw.rows();
  EffectiveRotor out;
  out.speed.resize(rows, rotors);
  out.acceleration = Eigen::MatrixXd::Zero(rows, rotors);
  const auto at_rows = [&](const Eigen::MatrixXd& series, Eigen::MatrixXd* sampled) {
    for (int r = 0; r < rows; ++r) sampled->row(r) = series.row(flight.row_samples[r]);
  };
  if (chain.empty()) {  // the flight's own rotor entries
    at_rows(flight.rotor, &out.speed);
    if (n >= 3)
      for (int r = 0; r < rows; ++r)
        out.acceleration.row(r) = FourthOrderCentralDifferenceAt(flight.rotor, flight.row_samples[r], flight.dt_s);
    return out;
  }
  if (coordinates.empty()) {  // values only: the chain in doubles, no Jet signal of every sample
    const Eigen::MatrixXd speed = SpeedFromFilteredSquare(FilteredSquareAfterChain(flight, acting));
    at_rows(speed, &out.speed);
    at_rows(FourthOrderCentralDifference(speed, flight.dt_s), &out.acceleration);
    return out;
  }
  out.derivative.assign(coordinates.size(), Eigen::MatrixXd(rows, rotors));
  out.acceleration_derivative.assign(coordinates.size(), Eigen::MatrixXd(rows, rotors));
  // The chain's parameters as Jets, kRotorJetSize coordinates seeded per block.
  std::vector<std::vector<Eigen::Matrix<RotorJet, Eigen::Dynamic, 1>>> blocks;
  for (size_t first = 0; first < coordinates.size(); first += kRotorJetSize) {
    std::vector<Eigen::Matrix<RotorJet, Eigen::Dynamic, 1>>& jets = blocks.emplace_back(chain.size());
    for (size_t j = 0; j < chain.size(); ++j) jets[j] = values[j].cast<RotorJet>();
    for (size_t c = first; c < std::min(coordinates.size(), first + kRotorJetSize); ++c)
      jets[coordinates[c].link][coordinates[c].index].v[c - first] = 1.0;
  }
  // One rotor at a time (the chain and the filters act on each alone): the Jet signal of every
  // sample is one column, not the flight's rotors. The low-pass is linear: y^2 and each of its
  // derivatives filter separately, side by side in one call.
  const Eigen::Index num_coordinates = static_cast<Eigen::Index>(coordinates.size());
  Eigen::MatrixXd squared(n, 1 + num_coordinates);  // y^2, then its derivatives
  for (Eigen::Index rotor = 0; rotor < rotors; ++rotor) {
    for (size_t b = 0; b < blocks.size(); ++b) {
      std::vector<const RotorJet*> parameters;
      for (const auto& j : blocks[b]) parameters.push_back(j.data());
      const Eigen::Matrix<RotorJet, Eigen::Dynamic, 1> signal =
          TransformRotor<RotorJet>(flight, chain, parameters, rotor);
      if (b == 0)
        for (Eigen::Index k = 0; k < n; ++k) squared(k, 0) = (signal[k] * signal[k]).a;
      const size_t first = b * kRotorJetSize;
      for (size_t c = first; c < std::min(coordinates.size(), first + kRotorJetSize); ++c) {
        double* column = squared.col(1 + static_cast<Eigen::Index>(c)).data();
        for (Eigen::Index k = 0; k < n; ++k) column[k] = (signal[k] * signal[k]).v[c - first];
      }
    }
    Eigen::MatrixXd filtered = FiltFiltColumns(flight.filter, squared);
    filtered.col(0) = SpeedFromFilteredSquare(filtered.col(0));
    // d sqrt(z) = dz / (2 sqrt(z)): the same factor for every coordinate.
    const Eigen::ArrayXd half_inverse_speed =
        (filtered.col(0).array() > 0.0).select(0.5 * filtered.col(0).array().inverse(), 0.0);
    for (Eigen::Index c = 1; c <= num_coordinates; ++c) filtered.col(c).array() *= half_inverse_speed;
    const Eigen::MatrixXd rate = FourthOrderCentralDifference(filtered, flight.dt_s);
    for (int r = 0; r < rows; ++r) {
      const Eigen::Index i = flight.row_samples[r];
      out.speed(r, rotor) = filtered(i, 0);
      out.acceleration(r, rotor) = rate(i, 0);
      for (Eigen::Index c = 0; c < num_coordinates; ++c) {
        out.derivative[c](r, rotor) = filtered(i, 1 + c);
        out.acceleration_derivative[c](r, rotor) = rate(i, 1 + c);
      }
    }
  }
  return out;
}

Eigen::MatrixXd EffectiveRotorSpeedAtRows(const ProcessedFlight& flight, const Effects& effects) {
  const EffectChain acting = ActingEffects(effects, EffectStage::kRotorSignal);
  const int rows = flight.num_rows_samples();
  Eigen::MatrixXd speed(rows, flight.rotor_raw.cols());
  if (acting.kinds.empty()) {
    for (int r = 0; r < rows; ++r) speed.row(r) = flight.rotor.row(flight.row_samples[r]);
    return speed;
  }
  // As EffectiveRotorAtRows, with the square root taken at the row samples only.
  const Eigen::MatrixXd filtered_square = FilteredSquareAfterChain(flight, acting);
  for (int r = 0; r < rows; ++r) speed.row(r) = filtered_square.row(flight.row_samples[r]);
  return SpeedFromFilteredSquare(speed);
}

Eigen::MatrixXd BuildIdimMatrixWithEffects(const ProcessedFlight& flight, const Effects& effects) {
  const EffectiveRotor rotor = EffectiveRotorAtRows(flight, effects, {});
  const internal::EffectRows rows(&flight, effects, {}, &rotor);
  Eigen::MatrixXd w(6 * flight.num_rows_samples(), kNumIdimColumns);
  const internal::EffectRows::PassValues<double> pass = rows.Pass<double>();
  for (int r = 0; r < flight.num_rows_samples(); ++r) w.middleRows<6>(6 * r) = rows.Rows<double>(r, pass);
  return w;
}

}  // namespace rotorid

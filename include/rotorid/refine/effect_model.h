#pragma once

// The unmodelled effects acting on a processed flight's signals before the regressor is built
// (MODEL.md section 4), through the registry's descriptors (rotorid/model/effects.h). The
// refinement, the reports and the diagnosis all build effect-laden rows through these functions,
// so they cannot disagree.
//
// Rotor signal, per rotor at the base rate, in the order of the physics: the rotor-signal effects
// transform Omega_log in chain order (delay, then lag, ...), and the row's rotor entry is
// sqrt(lowpass(y^2)) (the rotor columns are linear in Omega^2). With every rotor-signal effect
// absent this is exactly ProcessedFlight::rotor.
// IMU effects act on the filtered signals, which is exact for the linear corrections (the low-pass
// has unit gain at DC): the corrections run in decreasing chain order, from the log to the body.

#include <Eigen/Core>
#include <vector>

#include "rotorid/ident/observation.h"
#include "rotorid/model/effects.h"

namespace rotorid {

// The raw rotor signal (n_base x n_rotors) after the rotor-signal effects of `effects`, unfiltered.
Eigen::MatrixXd RotorSignalWithEffects(const ProcessedFlight& flight, const Effects& effects);

// The rotor entries of the rows at the row samples with the rotor-signal effects applied, and
// their derivatives (row sample x rotor) with respect to each scalar parameter of `free` (rotor-
// signal effects, in that order, coordinates in order).
struct EffectiveRotor {
  Eigen::MatrixXd speed;
  std::vector<Eigen::MatrixXd> derivative;
};
EffectiveRotor EffectiveRotorAtRows(const ProcessedFlight& flight, const Effects& effects,
                                    const std::vector<EffectKind>& free);

// The IMU signals of sample i of a flight, as the log has them (filtered).
template <typename T>
ImuSample<T> LoggedImu(const ProcessedFlight& flight, int i) {
  ImuSample<T> s;
  s.angular_velocity = flight.angular_velocity.row(i).transpose().cast<T>();
  s.angular_acceleration = flight.angular_acceleration.row(i).transpose().cast<T>();
  s.specific_force = flight.specific_force.row(i).transpose().cast<T>();
  return s;
}

// Corrects an IMU sample from the log to the body at O_b: parameters[j] are those of chain[j]
// (IMU effects in increasing chain order; the corrections run backwards).
template <typename T>
void CorrectImu(const std::vector<EffectKind>& chain, const std::vector<const T*>& parameters, ImuSample<T>* s) {
  for (size_t j = chain.size(); j-- > 0;) chain[j]->CorrectImu(parameters[j], s);
}

// The IDIM rows of a flight (as BuildIdimMatrix) with the effects applied.
Eigen::MatrixXd BuildIdimMatrixWithEffects(const ProcessedFlight& flight, const Effects& effects);

}  // namespace rotorid

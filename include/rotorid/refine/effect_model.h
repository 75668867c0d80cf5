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
#include "rotorid/signal/differentiate.h"

namespace rotorid {

// The raw rotor signal (n_base x n_rotors) after the rotor-signal effects of `effects`, unfiltered.
Eigen::MatrixXd RotorSignalWithEffects(const ProcessedFlight& flight, const Effects& effects);

// The rotor entries of the rows at the row samples with the rotor-signal effects applied, and
// their derivatives (row sample x rotor) with respect to each scalar parameter of `free` (rotor-
// signal effects, in that order, coordinates in order); likewise the rotor acceleration Omega' of
// that signal (the rotor-wrench effects' input), differentiated as ProcessFlight differentiates the
// logged one, so that a delay or a lag moves Omega' with Omega.
struct EffectiveRotor {
  Eigen::MatrixXd speed;
  std::vector<Eigen::MatrixXd> derivative;
  Eigen::MatrixXd acceleration;
  std::vector<Eigen::MatrixXd> acceleration_derivative;
};
EffectiveRotor EffectiveRotorAtRows(const ProcessedFlight& flight, const Effects& effects,
                                    const std::vector<EffectKind>& free);
// EffectiveRotorAtRows(flight, effects, {}).speed alone: no acceleration, no derivatives (the delay
// grid's rotor columns, evaluated at every grid value).
Eigen::MatrixXd EffectiveRotorSpeedAtRows(const ProcessedFlight& flight, const Effects& effects);

// The IMU signals of sample i of a flight, as the log has them (filtered); s' and s'' only when
// `with_rates` (an effect of the chain needs them, FlightInput::kSpecificForceRates: they are
// taken there from nine samples of s, and every row evaluation would pay for them).
template <typename T>
ImuSample<T> LoggedImu(const ProcessedFlight& flight, int i, bool with_rates) {
  ImuSample<T> s;
  s.angular_velocity = flight.angular_velocity.row(i).transpose().cast<T>();
  s.angular_acceleration = flight.angular_acceleration.row(i).transpose().cast<T>();
  s.specific_force = flight.specific_force.row(i).transpose().cast<T>();
  if (with_rates && flight.specific_force.rows() >= 3) {  // as the whole series' differences give them there
    s.specific_force_rate = FourthOrderCentralDifferenceAt(flight.specific_force, i, flight.dt_s).transpose().cast<T>();
    s.specific_force_rate2 =
        SecondFourthOrderCentralDifferenceAt(flight.specific_force, i, flight.dt_s).transpose().cast<T>();
  }
  return s;
}

// What the rotor-wrench effects see at sample i of a flight: the rotor speeds acting `speed` and
// their acceleration (with the rotor-signal effects), the corrected angular velocity `w`, the
// velocity of O_d and rotor heights (zero or empty where the flight has none).
template <typename T>
RotorSample<T> FlightRotorSample(const ProcessedFlight& flight, int i, const Eigen::Matrix<T, Eigen::Dynamic, 1>& speed,
                                 const Eigen::Matrix<T, Eigen::Dynamic, 1>& acceleration,
                                 const Eigen::Matrix<T, 3, 1>& w) {
  RotorSample<T> sample;
  sample.vehicle = &flight.vehicle;
  sample.speed = speed;
  sample.acceleration = acceleration;
  sample.angular_velocity = w;
  if (flight.velocity_mps) sample.velocity = flight.velocity_mps->row(i).transpose().cast<T>();
  if (flight.rotor_height_m) sample.height = flight.rotor_height_m->row(i).transpose().cast<T>();
  return sample;
}

// The IDIM rows of a flight (as BuildIdimMatrix) with the effects applied.
Eigen::MatrixXd BuildIdimMatrixWithEffects(const ProcessedFlight& flight, const Effects& effects);

}  // namespace rotorid

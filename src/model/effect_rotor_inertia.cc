// `rotor_inertia` (INTERFACE.md, "Effects of real vehicles (v2)"): each rotor's angular momentum
// J sigma_i Omega_i z reacts on the body when the rotor speeds up and when the body turns it:
//   tau = -J sum_i sigma_i (Omega_i' z + Omega_i w x z),   J = rotor_inertia_kgm2 >= 0
// (rotor and propeller about the rotor axis). Omega_i' is the derivative of the filtered rotor
// speed after the rotor-signal effects (EffectiveRotorAtRows), so a refined delay or lag moves it
// with Omega_i: where the term is large (the TU Delft 3-inch quad, whose measured speed lags the
// gyro by 10-14 ms, docs/blackbox.md 6) the two must not disagree.

#include "model/effect_adapter.h"
#include "rotorid/core/vehicle.h"

namespace rotorid::internal {
namespace {

struct RotorInertiaModel {
  template <typename T>
  static void Add(const T* p, const RotorSample<T>& s, RotorWrenchTerms<T>* terms) {
    const Vehicle& vehicle = *s.vehicle;
    T momentum(0.0), momentum_rate(0.0);  // sum_i sigma_i Omega_i and its derivative
    for (int i = 0; i < vehicle.num_rotors(); ++i) {
      const double spin = vehicle.rotors[i].spin;
      momentum += spin * s.speed[i];
      momentum_rate += spin * s.acceleration[i];
    }
    // w x z = (w_y, -w_x, 0).
    terms->extra[3] -= p[0] * momentum * s.angular_velocity.y();
    terms->extra[4] += p[0] * momentum * s.angular_velocity.x();
    terms->extra[5] -= p[0] * momentum_rate;
  }
};

}  // namespace

const EffectDescriptor& RotorInertiaEffect() {
  static const RotorWrenchEffect<RotorInertiaModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "rotor_inertia";
    i.parameter_name = "rotor_inertia_kgm2";
    i.unit = "kg m^2";
    // tau = -J sum_i sigma_i (Omega_i' z + Omega_i w x z), J = rotor_inertia_kgm2 >= 0
    i.stage = EffectStage::kRotorWrench;
    i.chain_position = 2;
    i.dimension = 1;
    i.lower_bound = 0.0;
    i.upper_bound = 1e-3;  // a 20-inch propeller's is ~1e-4
    // The paper's vehicle's 10-inch propellers with their motor bells.
    i.draw = {DrawShape::kUniform, 2e-5, 6e-5};
    i.simulator_limit = {true, 0.0, 1e-3};
    // A rotor's spinning parts (propeller, motor bell) weigh under ~5 % of the vehicle and sit within
    // ~0.45 arm of the axis: J <= 0.05 m (0.45 L)^2 ~ 0.01 m L^2 (B: 7e-4 against 10-inch propellers'
    // 3-6e-5; Crazyflie 7e-7 against 5e-8).
    i.plausible = {true, 0.0, 0.01, PlausibleScale::kMassArmSquared,
                   "a rotor weighs a few % of the vehicle, within its radius"};
    i.settle_tolerance = 1e-9;
    i.display_unit = "kg m^2";
    i.inputs = {FlightInput::kRotorAcceleration};
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal

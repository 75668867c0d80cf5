// `ground_effect` (INTERFACE.md, "Effects of real vehicles (v2)"): near the ground a rotor's wake
// cannot expand and its thrust rises (Cheeseman and Bennett's image-rotor model):
//   thrust_i times 1 / (1 - rho (R / (4 h_i))^2),   rho = ground_effect_coefficient,
// h_i the rotor's height above the ground (pose needed; ground = the log's `# ground_z:` metadata,
// else its lowest pose), R the vehicle's rotor_radius. The drag torque is left alone. Below
// h = R / 2, where the model stops holding (the vehicle is landing), the height is held at R / 2.

#include <algorithm>

#include "model/effect_adapter.h"
#include "rotorid/core/vehicle.h"

namespace rotorid::internal {
namespace {

struct GroundEffectModel {
  template <typename T>
  static void Add(const T* p, const RotorSample<T>& s, RotorWrenchTerms<T>* terms) {
    const Vehicle& vehicle = *s.vehicle;
    if (!vehicle.rotor_radius_m || s.height.size() != vehicle.num_rotors()) return;  // unavailable
    const double radius = *vehicle.rotor_radius_m;
    for (int i = 0; i < vehicle.num_rotors(); ++i) {
      const T height = ScalarPart(s.height[i]) > 0.5 * radius ? s.height[i] : T(0.5 * radius);
      const T ratio = T(radius) / (T(4.0) * height);
      terms->thrust_factor[i] /= T(1.0) - p[0] * ratio * ratio;
    }
  }
};

}  // namespace

const EffectDescriptor& GroundEffectEffect() {
  static const RotorWrenchEffect<GroundEffectModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "ground_effect";
    i.parameter_name = "ground_effect_coefficient";
    i.unit = "1";
    // thrust_i / (1 - rho (R / (4 h_i))^2), rho = ground_effect_coefficient
    i.stage = EffectStage::kRotorWrench;
    i.chain_position = 3;
    i.dimension = 1;
    i.lower_bound = 0.0;
    i.upper_bound = 3.0;                       // (R / 4h)^2 <= 1/4 at h = R / 2: the factor stays finite below 4
    i.draw = {DrawShape::kUniform, 0.5, 1.5};  // the image-rotor model's 1, give or take
    i.simulator_limit = {true, 0.0, 3.0};
    // Cheeseman-Bennett's rotor has rho = 1; multirotor measurements fit about 0.5-2. Negative: less
    // thrust near the ground.
    i.plausible = {true, 0.0, 2.0, PlausibleScale::kNone, "Cheeseman-Bennett's rotor has 1"};
    i.settle_tolerance = 1e-3;
    i.inputs = {FlightInput::kHeight, FlightInput::kRotorRadius};
    // Only flights near the ground (take-off, landing, low hover) carry it: used when named.
    i.default_candidate = false;
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal

// `rotor_drag` (INTERFACE.md, "Effects of real vehicles (v2)"): a rotor moving edgewise through
// the air feels a hub force against its in-plane velocity and tilts its disc back (blade flapping):
//   f_i   = -k_d |Omega_i| v_i_perp   at p_i (so also the moment p_i x f_i),
//   tau_i = -k_f |Omega_i| (z x v_i_perp),
// with v_i = v + w x p_i the hub's velocity in F_d and v_i_perp its part in the rotor plane. Both
// coefficients are >= 0 (the force opposes the motion, the moment is nose up in forward flight).
// It needs the velocity: motion capture (differentiated) or velocity columns.

#include <Eigen/Geometry>

#include "model/effect_adapter.h"
#include "rotorid/core/text.h"
#include "rotorid/core/vehicle.h"

namespace rotorid::internal {
namespace {

struct RotorDragModel {
  template <typename T>
  static void Add(const T* p, const RotorSample<T>& s, RotorWrenchTerms<T>* terms) {
    using std::abs;
    const Vehicle& vehicle = *s.vehicle;
    const Eigen::Matrix<T, 3, 1> z(T(0.0), T(0.0), T(1.0));
    for (int i = 0; i < vehicle.num_rotors(); ++i) {
      const Eigen::Matrix<T, 3, 1> position = vehicle.rotors[i].position_m.cast<T>();
      Eigen::Matrix<T, 3, 1> hub = s.velocity + s.angular_velocity.cross(position);
      hub.z() = T(0.0);  // v_i_perp
      const T speed = abs(s.speed[i]);
      const Eigen::Matrix<T, 3, 1> force = -p[0] * speed * hub;
      terms->extra.template head<3>() += force;
      terms->extra.template tail<3>() += position.cross(force) - p[1] * speed * z.cross(hub);
    }
  }
};

}  // namespace

const EffectDescriptor& RotorDragEffect() {
  static const RotorWrenchEffect<RotorDragModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "rotor_drag";
    i.parameter_name = "rotor_drag_coefficient";
    i.labels = {"rotor_drag_coefficient", "flapping_moment_coefficient"};
    i.unit = "N s/m per rad/s";
    // f_i = -k_d |Omega_i| v_i_perp at p_i, tau_i = -k_f |Omega_i| (z x v_i_perp)
    i.stage = EffectStage::kRotorWrench;
    i.chain_position = 1;
    i.dimension = 2;
    i.lower_bound = 0.0;
    i.upper_bound = 1e-2;  // 10x a 10-inch propeller's: beyond any multirotor
    // The paper's vehicle (1.3 kg, 0.45 m): 0.04-0.2 N of drag at 1 m/s and 500 rad/s per rotor.
    i.draw = {DrawShape::kUniform, 1e-5, 5e-5};
    i.simulator_limit = {true, 0.0, 1e-3};
    // Drag opposes the hub's motion and flapping tilts the rotor away from it: both non-negative (which
    // the bounds already keep); no upper limit without the rotor speed.
    i.plausible = {true, 0.0, HUGE_VAL, PlausibleScale::kNone, "drag opposes the hub's motion"};
    i.settle_tolerance = 1e-8;
    i.display_unit = "N s/m per rad/s";
    i.inputs = {FlightInput::kVelocity};
    // Measured: on the circle with the IMU 30 mm below O_d and the vehicle file silent, k_f read 7.20e-6
    // for 6e-6 and k_d 4e-5, i.e. k_f - k_d r_z (docs/adding_an_effect.md, "k_f and the IMU's height").
    i.relative_to_known = "imu_lever_arm";
    i.reads_without_it = [](const Eigen::VectorXd& value) {
      const double per_mm = value[0] * 1e-3;
      return "flapping_moment_coefficient is measured about the IMU's height: it reads k_f - k_d r_z, with r_z "
             "the IMU's height above O_d (z up), which the vehicle file does not give (imu_position: [x, y, z]); "
             "each mm of r_z moves it by k_d x 1 mm = " +
             ShortNumber(per_mm) +
             (value[1] > 0.0 ? " (" + ShortNumber(100.0 * per_mm / value[1]) + " % of its value)" : std::string());
    };
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal

// PX4 parameter files: `px4` (control allocation, the gz bridge's ESC range and the thrust model
// for the exported gz model) and `px4-sih` (the SIH simulator's fixed X quad and X hexa).

#include <cmath>

#include "export_text.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"

namespace rotorid::internal {
namespace {

// F_d (FLU) to PX4's FRD body frame.
Eigen::Vector3d Frd(const Eigen::Vector3d& v) { return {v.x(), -v.y(), -v.z()}; }

class ParameterLines {
 public:
  explicit ParameterLines(const std::vector<std::string>& header) {
    for (const std::string& line : header) text_ += "# " + line + "\n";
  }
  void Set(const std::string& name, double value) {
    text_ += "param set " + name + " " + ExportNumber(name, value) + "\n";
  }
  void SetInteger(const std::string& name, long value) {
    text_ += "param set " + name + " " + std::to_string(value) + "\n";
  }
  void Comment(const std::string& line) { text_ += "# " + line + "\n"; }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

// PX4's SIH layouts (src/modules/simulation/simulator_sih/sih.cpp): the quad X and the hexa X,
// motors in its order, bearing from the nose towards starboard.
const std::vector<RotorSlot> kSihQuadX = {{45, +1}, {-135, +1}, {-45, -1}, {135, -1}};
const std::vector<RotorSlot> kSihHexaX = {{30, +1}, {90, -1}, {150, +1}, {-150, -1}, {-90, +1}, {-30, -1}};

}  // namespace

std::vector<ExportedFile> Px4Parameters(const ExportModel& model) {
  const int n = model.vehicle.num_rotors();
  if (n > 8)
    throw Error("px4: PX4's gz bridge drives at most 8 ESCs (SIM_GZ_EC_FUNC1..8); the vehicle has " +
                std::to_string(n) + " rotors");
  // SIM_GZ_EC_MAX is an integer: the exported PX4 side commands whole rad/s.
  const long ec_max = static_cast<long>(std::floor(RequireMaxRotorSpeed(model, "px4")));
  const double kt = model.parameters.rotor.kt, kd = model.parameters.rotor.kd;
  const double ct = kt * static_cast<double>(ec_max) * static_cast<double>(ec_max);
  const Eigen::Vector3d c = model.Mass().centre_of_mass_m;
  ExportHeader h;
  h.format = "PX4 parameters (control allocation and gz bridge, for the gz model of this export)";
  h.units =
      "SI; CA_ROTOR*_P* in PX4's FRD body frame (x forward, y right, z down), relative to the centre of mass; "
      "CA_ROTOR*_CT in N at full command, CA_ROTOR*_KM in m (drag torque / thrust, positive counter-clockwise "
      "seen from above)";
  h.command_to_speed = "PX4 output u in [0, 1] -> rotor speed SIM_GZ_EC_MIN + u (SIM_GZ_EC_MAX - SIM_GZ_EC_MIN) = " +
                       std::to_string(ec_max) +
                       " u rad/s (SIM_GZ_EC_MAX: the model's maximum rotor speed, floored to "
                       "an integer), so thrust = CA_ROTOR*_CT u^2 and THR_MDL_FAC = 1";
  h.holds = {"no effect itself: the gz model (gz format) holds the motor lag and the rotor drag"};
  h.not_held = {
      "the inertia and the first moment (the simulator's model.sdf has them; PX4 needs only the geometry "
      "relative to the centre of mass)",
      "flapping, battery: neither the PX4 side nor the gz model holds them"};
  ParameterLines out(HeaderLines(model, h));
  out.SetInteger("CA_AIRFRAME", 0);
  out.SetInteger("CA_ROTOR_COUNT", n);
  for (int i = 0; i < n; ++i) {
    const Rotor& r = model.vehicle.rotors[static_cast<size_t>(i)];
    const Eigen::Vector3d p = Frd(r.position_m - c);
    const std::string k = "CA_ROTOR" + std::to_string(i) + "_";
    out.Set(k + "PX", p.x());
    out.Set(k + "PY", p.y());
    out.Set(k + "PZ", p.z());
    out.Set(k + "CT", ct);
    out.Set(k + "KM", r.spin * kd / kt);
  }
  for (int i = 1; i <= n; ++i) {
    out.SetInteger("SIM_GZ_EC_FUNC" + std::to_string(i), 100 + i);
    out.SetInteger("SIM_GZ_EC_MIN" + std::to_string(i), 0);
    out.SetInteger("SIM_GZ_EC_MAX" + std::to_string(i), ec_max);
  }
  const double hover = model.parameters.mass_kg * kStandardGravity / (n * ct);
  if (hover < 0.1 || hover > 0.8)
    out.Comment(
        "MPC_THR_HOVER below is outside PX4's range 0.1 .. 0.8: the rotor speed at full command is far from "
        "what this vehicle needs");
  out.Set("MPC_THR_HOVER", hover);
  out.Set("THR_MDL_FAC", 1.0);
  return {{"", out.text()}};
}

std::vector<ExportedFile> Px4SihParameters(const ExportModel& model) {
  const auto quad = MatchLayout(model.vehicle, kSihQuadX);
  const auto hexa = quad ? std::nullopt : MatchLayout(model.vehicle, kSihHexaX);
  if (!quad && !hexa)
    throw Error(
        "px4-sih: SIH flies a fixed X quad (SIH_VEHICLE_TYPE 0: front-right and rear-left rotors "
        "counter-clockwise) or X hexa (type 4: rotors at 30, 90, ... degrees from the nose, the front-right one "
        "counter-clockwise); vehicle '" +
        model.vehicle.name + "' with " + std::to_string(model.vehicle.num_rotors()) +
        " rotors is neither (a plus layout, another rotor count or other spins): use gz or gazebo-classic");
  const std::vector<int>& slots = quad ? *quad : *hexa;
  const double w = RequireMaxRotorSpeed(model, "px4-sih");
  // SIH's arms: rotor k at (L_PITCH f_x, L_ROLL f_y) with its layout's factors f.
  double l_roll = 0.0, l_pitch = 0.0;
  for (const Rotor& r : model.vehicle.rotors) {
    l_roll = std::max(l_roll, std::abs(r.position_m.y()));
    l_pitch = std::max(l_pitch, std::abs(r.position_m.x()));
  }
  if (hexa) l_pitch /= std::sqrt(3.0) / 2.0;
  const std::vector<RotorSlot>& layout = quad ? kSihQuadX : kSihHexaX;
  for (size_t k = 0; k < slots.size(); ++k) {
    const double b = layout[k].bearing_deg * M_PI / 180.0;
    const Eigen::Vector2d expected(l_pitch * (quad ? std::copysign(1.0, std::cos(b)) : std::cos(b)),
                                   -l_roll * (quad ? std::copysign(1.0, std::sin(b)) : std::sin(b)));
    const Eigen::Vector3d& p = model.vehicle.rotors[static_cast<size_t>(slots[k])].position_m;
    if ((p.head<2>() - expected).norm() > 1e-3 * expected.norm() || std::abs(p.z()) > 1e-3 * expected.norm())
      throw Error("px4-sih: SIH's rotors sit symmetrically at +-SIH_L_PITCH, +-SIH_L_ROLL in the rotor plane; rotor " +
                  std::to_string(slots[k] + 1) + " of vehicle '" + model.vehicle.name + "' is off that place by " +
                  ShortNumber(1000.0 * (p.head<2>() - expected).norm()) + " mm: use gz or gazebo-classic");
  }
  const MassProperties mass = model.Mass();
  const Eigen::Matrix3d F = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Matrix3d I = F * mass.inertia_at_com * F;  // FRD flips the xy and xz products
  ExportHeader h;
  h.format =
      std::string("PX4 SIH parameters (") + (quad ? "quad X, SIH_VEHICLE_TYPE 0" : "hexa X, SIH_VEHICLE_TYPE 4") + ")";
  h.units =
      "SI; FRD body frame (x forward, y right, z down); inertia about the centre of mass; SIH_T_MAX in N and "
      "SIH_Q_MAX in N m per rotor at full command";
  h.command_to_speed = quad ? "SIH thrust per rotor = SIH_T_MAX u (u in [0, 1]): rotor speed " +
                                  FormatValue("%.6g", w) + " sqrt(u) rad/s, drag torque SIH_Q_MAX u = kd Omega^2"
                            : "SIH thrust per rotor = SIH_T_MAX u^2 (u in [0, 1]): rotor speed " +
                                  FormatValue("%.6g", w) + " u rad/s, drag torque SIH_Q_MAX u^2 = kd Omega^2";
  std::string order;
  for (size_t k = 0; k < slots.size(); ++k)
    order +=
        (k ? ", " : "") + std::string("SIH motor ") + std::to_string(k) + " = rotor " + std::to_string(slots[k] + 1);
  h.holds = {std::string("motor_lag: SIH_T_TAU = motor_tau_s, acting on u (") +
                 (quad ? "the thrust, not the speed: equal for small changes" : "the speed, as the model") +
                 "); a model without lag gets SIH's step 0.004 s, which passes the command through",
             "rotor_drag: approximately, as SIH_KDV = N k_d Omega_hover (SIH's drag is linear in the velocity and "
             "isotropic, the model's in the rotor plane and proportional to the rotor speed)",
             "motor order: " + order};
  h.not_held = {"the first moment: SIH puts the centre of mass at the rotor cross (the model's is at (" +
                    ShortNumber(1000 * mass.centre_of_mass_m.x()) + ", " +
                    ShortNumber(1000 * mass.centre_of_mass_m.y()) + ", " +
                    ShortNumber(1000 * mass.centre_of_mass_m.z()) + ") mm)",
                "flapping, battery, rotor inertia: SIH has no such terms"};
  ParameterLines out(HeaderLines(model, h));
  out.SetInteger("SIH_VEHICLE_TYPE", quad ? 0 : 4);
  out.Set("SIH_MASS", mass.mass_kg);
  out.Set("SIH_IXX", I(0, 0));
  out.Set("SIH_IYY", I(1, 1));
  out.Set("SIH_IZZ", I(2, 2));
  out.Set("SIH_IXY", I(0, 1));
  out.Set("SIH_IXZ", I(0, 2));
  out.Set("SIH_IYZ", I(1, 2));
  out.Set("SIH_T_MAX", model.parameters.rotor.kt * w * w);
  out.Set("SIH_Q_MAX", model.parameters.rotor.kd * w * w);
  out.Set("SIH_L_ROLL", l_roll);
  out.Set("SIH_L_PITCH", l_pitch);
  out.Set("SIH_T_TAU", model.motor_tau_s > 0.0 ? model.motor_tau_s : 0.004);
  out.Set("SIH_KDV", model.vehicle.num_rotors() * model.rotor_drag_coefficient * model.HoverRotorSpeedRadps());
  out.Set("SIH_KDW", 0.0);
  return {{"", out.text()}};
}

}  // namespace rotorid::internal

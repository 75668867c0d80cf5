// ArduPilot SITL's JSON frame model (libraries/SITL/SIM_Frame.cpp, Frame::load_frame_params): every
// key its loader reads for a multicopter, the motors of the built-in frame the vehicle matches moved
// to the identified places (motor<k>_position, _vector, _yaw). SITL's motor (SIM_Motor.cpp) gives a
// static thrust T_max ((1 - e) c + e c^2) with T_max = (m g / N) / hoverThrOut, a yaw torque
// yaw * c * 0.05 * diagonal_size * T and a momentum drag mdrag_coef sqrt(rho A T) v per motor.

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "export_text.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"

namespace rotorid::internal {
namespace {

// ArduPilot's frames (SIM_Frame.cpp), motors in its order: bearing from the nose towards starboard
// and yaw factor (+1 counter-clockwise).
struct ArduPilotFrameTemplate {
  const char* name;
  std::vector<RotorSlot> motors;
};
const std::vector<ArduPilotFrameTemplate> kArduPilotFrames = {
    {"+", {{90, +1}, {-90, +1}, {0, -1}, {180, -1}}},
    {"x", {{45, +1}, {-135, +1}, {-45, -1}, {135, -1}}},
    {"hexa", {{0, -1}, {180, +1}, {-120, -1}, {60, +1}, {-60, +1}, {120, -1}}},
    {"hexax", {{90, -1}, {-90, +1}, {-30, -1}, {150, +1}, {30, +1}, {-150, -1}}}};

constexpr double kSeaLevelAirDensity = 1.225;  // kg/m^3, ArduPilot's at refAlt 0

// MOT_THST_EXPO e with (Omega(u) / Omega(1))^2 ~ (1 - e) u + e u^2 over u in [0, 1] (least squares):
// 1 when the speed is proportional to the command.
double ThrustExpo(const Vehicle& vehicle) {
  if (!vehicle.command_to_speed) return 1.0;
  const double full = (*vehicle.command_to_speed)(1.0);
  if (!(full > 0.0)) return 1.0;
  double numerator = 0.0, denominator = 0.0;
  for (int k = 0; k <= 100; ++k) {
    const double u = k / 100.0, f = std::pow((*vehicle.command_to_speed)(u) / full, 2);
    numerator += (f - u) * (u * u - u);
    denominator += (u * u - u) * (u * u - u);
  }
  return std::clamp(numerator / denominator, -1.0, 1.0);
}

// The command c of (1 - e) c + e c^2 = fraction.
double CommandForThrustFraction(double expo, double fraction) {
  if (std::abs(expo) < 1e-12) return fraction;
  return (-(1.0 - expo) + std::sqrt((1.0 - expo) * (1.0 - expo) + 4.0 * expo * fraction)) / (2.0 * expo);
}

double Checked(const std::string& key, double x) {
  ExportNumber(key, x);  // throws on inf and nan
  return x;
}

ExportHeader ArduPilotHeader(const ExportModel& model, const char* frame, double w, double expo) {
  ExportHeader h;
  h.format = std::string("ArduPilot SITL JSON frame (sim_vehicle.py -v ArduCopter --model ") + frame +
             ":/absolute/path/to/this.json)";
  h.units =
      "SI (kg, m, kg m^2, N, V, A, Ah); degrees for refAngle; motor positions in ArduPilot's FRD body frame "
      "relative to the centre of mass; moment_inertia: the diagonal of the inertia about the centre of mass";
  h.command_to_speed =
      "SITL command c in [0, 1] between spin_min and spin_max of the PWM range: thrust T_max ((1 - e) c "
      "+ e c^2) = kt Omega^2 with T_max = kt " +
      FormatValue("%.6g", w) + "^2, e = propExpo = " + ShortNumber(expo) +
      (model.vehicle.command_to_speed ? " (fitted to the vehicle's command_to_speed)"
                                      : " (speed proportional to the command)");
  h.holds = {
      "rotor_drag: mdrag_coef = k_d / sqrt(1.225 disc_area / N kt) (SITL's momentum drag; it also adds a "
      "vertical drag the model has not), body drag zeroed by refSpd/refAngle"};
  h.not_held = {
      "motor_lag (" + ShortNumber(model.motor_tau_s) + " s): SITL's motors have a slew limit only (slew_max 0: off)",
      "the yaw torque is exact at the hover command only (SITL's grows as c T, the model's as T)",
      "products of inertia and gyroscopic coupling: SITL integrates torque / moment_inertia",
      "flapping, rotor inertia: no such terms; battery: a constant voltage (refBatRes 0, battCapacityAh 0)",
      "thrust is exact at refAlt 0 (air density 1.225): start SITL at altitude 0 (-l LAT,LON,0,HEADING)"};
  return h;
}

}  // namespace

std::vector<ExportedFile> ArduPilotFrame(const ExportModel& model) {
  const ArduPilotFrameTemplate* frame = nullptr;
  std::optional<std::vector<int>> order;
  for (const ArduPilotFrameTemplate& t : kArduPilotFrames)
    if ((order = MatchLayout(model.vehicle, t.motors))) {
      frame = &t;
      break;
    }
  if (!frame)
    throw Error("ardupilot: SITL's JSON frame moves the motors of a built-in frame; vehicle '" + model.vehicle.name +
                "' matches none of quad + and X, hexa + and X with ArduPilot's spins (front-right rotor "
                "counter-clockwise on an X quad): use gz or gazebo-classic");
  const double w = RequireMaxRotorSpeed(model, "ardupilot");
  const int n = model.vehicle.num_rotors();
  const VehicleParameters& p = model.parameters;
  const MassProperties mass = model.Mass();
  const double g = kStandardGravity, expo = ThrustExpo(model.vehicle);
  const double hover_fraction = p.mass_kg * g / (n * p.rotor.kt * w * w);
  const double hover_command = CommandForThrustFraction(expo, hover_fraction);
  const double diagonal = 2.0 * model.vehicle.MeanArm();
  const double radius = model.vehicle.rotor_radius_m.value_or(0.4 * model.vehicle.MeanArm());
  const double disc_area = n * M_PI * radius * radius;
  const double mdrag = model.rotor_drag_coefficient / std::sqrt(kSeaLevelAirDensity * disc_area / n * p.rotor.kt);
  // SITL splits the drag at refSpd, refAngle into momentum and body drag: equal shares leave no body drag.
  const double angle = mdrag > 0.0 ? 10.0 * M_PI / 180.0 : 0.0;
  const double weight = p.mass_kg * g;
  const double ref_speed = mdrag > 0.0 ? weight * std::tan(angle) /
                                             (std::pow(std::cos(angle), 2) * mdrag *
                                              std::sqrt(weight / std::cos(angle) * kSeaLevelAirDensity * disc_area))
                                       : 10.0;
  const double voltage = model.vehicle.command_to_speed_voltage_v.value_or(12.6);
  const double hover_power = std::pow(weight, 1.5) / std::sqrt(2.0 * kSeaLevelAirDensity * disc_area);  // ideal
  nlohmann::ordered_json j;
  ExportHeader header = ArduPilotHeader(model, frame->name, w, expo);
  // The autopilot's own parameters that must agree with the frame (FRAME_CLASS 1 quad, 2 hexa;
  // FRAME_TYPE 0 plus, 1 X).
  header.holds.push_back("autopilot parameters to match: FRAME_CLASS " + std::string(n == 4 ? "1" : "2") +
                         ", FRAME_TYPE " + (frame->name[0] == '+' || std::string(frame->name) == "hexa" ? "0" : "1") +
                         ", MOT_THST_EXPO " + FormatValue("%.4f", expo) + ", MOT_THST_HOVER " +
                         FormatValue("%.4f", hover_command) + ", MOT_SPIN_MIN 0.15, MOT_SPIN_MAX 0.95");
  j["_rotorid"] = HeaderLines(model, header);
  j["mass"] = Checked("mass", p.mass_kg);
  j["diagonal_size"] = Checked("diagonal_size", diagonal);
  j["refSpd"] = Checked("refSpd", ref_speed);
  j["refAngle"] = Checked("refAngle", angle * 180.0 / M_PI);
  j["refVoltage"] = Checked("refVoltage", voltage);
  j["refCurrent"] = Checked("refCurrent", hover_power / voltage);
  j["refAlt"] = 0.0;
  j["refTempC"] = 15.0;
  j["maxVoltage"] = Checked("maxVoltage", voltage);
  j["battCapacityAh"] = 0.0;
  j["refBatRes"] = 0.0;
  j["propExpo"] = Checked("propExpo", expo);
  j["refRotRate"] = 0.0;
  j["hoverThrOut"] = Checked("hoverThrOut", hover_fraction);
  j["pwmMin"] = 1000.0;
  j["pwmMax"] = 2000.0;
  j["spin_min"] = 0.15;
  j["spin_max"] = 0.95;
  j["slew_max"] = 0.0;
  j["disc_area"] = Checked("disc_area", disc_area);
  j["mdrag_coef"] = Checked("mdrag_coef", mdrag);
  j["num_motors"] = n;
  j["moment_inertia"] = {Checked("moment_inertia", mass.inertia_at_com(0, 0)),
                         Checked("moment_inertia", mass.inertia_at_com(1, 1)),
                         Checked("moment_inertia", mass.inertia_at_com(2, 2))};
  for (int k = 0; k < n; ++k) {
    const Rotor& r = model.vehicle.rotors[static_cast<size_t>((*order)[static_cast<size_t>(k)])];
    const Eigen::Vector3d q = r.position_m - mass.centre_of_mass_m;
    const std::string key = "motor" + std::to_string(k + 1) + "_";
    j[key + "position"] = {Checked(key + "position", q.x()), Checked(key + "position", -q.y()),
                           Checked(key + "position", -q.z())};
    j[key + "vector"] = {0.0, 0.0, -1.0};
    j[key + "yaw"] = Checked(key + "yaw", r.spin * p.rotor.kd / p.rotor.kt / (0.05 * diagonal * hover_command));
  }
  return {{"", j.dump(2) + "\n"}};
}

}  // namespace rotorid::internal

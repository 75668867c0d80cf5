#include "rotorid/report/export.h"

#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/ident/identify.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

namespace {

std::string PreciseNumber(double x) {
  std::ostringstream out;
  out << std::setprecision(9) << x;
  return out.str();
}

std::string Element(const std::string& name, const std::string& value, int indent) {
  return std::string(indent, ' ') + "<" + name + ">" + value + "</" + name + ">\n";
}

// "identified: 0.021 +- 0.002" or "not identified: PX4's default", for the comments of an export.
std::string Provenance(const IdentifiedModel& model, const std::string& effect, const std::string& fallback) {
  if (const auto v = model.Effect(effect)) return effect + " identified: " + PreciseNumber(*v);
  return effect + " not identified: " + fallback;
}

std::string MotorPlugin(const IdentifiedModel& model, int i) {
  const Rotor& rotor = model.vehicle.rotors[static_cast<size_t>(i)];
  const double kt = model.Value("kt");
  const std::string n = std::to_string(i);
  std::string xml = "    <!-- rotor " + std::to_string(i + 1) + " at (" + PreciseNumber(rotor.position_m.x()) + ", " +
                    PreciseNumber(rotor.position_m.y()) + ", " + PreciseNumber(rotor.position_m.z()) + ") m in the body frame -->\n";
  xml += "    <plugin name=\"rotor_" + n + "_motor_model\" filename=\"libgazebo_motor_model.so\">\n";
  xml += Element("robotNamespace", "", 6) + Element("jointName", "rotor_" + n + "_joint", 6) +
         Element("linkName", "rotor_" + n, 6) + Element("turningDirection", rotor.spin > 0 ? "ccw" : "cw", 6);
  const auto tau = model.Effect("motor_tau_s");
  xml += "      <!-- " + Provenance(model, "motor_tau_s", "PX4's defaults 0.0125 s up, 0.025 s down") + " -->\n";
  xml += Element("timeConstantUp", PreciseNumber(tau ? *tau : 0.0125), 6) +
         Element("timeConstantDown", PreciseNumber(tau ? *tau : 0.025), 6);
  if (model.max_rotor_speed_radps > 0.0)
    xml += Element("maxRotVelocity", PreciseNumber(model.max_rotor_speed_radps), 6);
  else
    xml += "      <!-- maxRotVelocity: unknown (give --max-rotor-speed or a command_to_speed map) -->\n";
  xml += Element("motorConstant", PreciseNumber(kt), 6) + Element("momentConstant", PreciseNumber(model.Value("kd") / kt), 6);
  xml += Element("commandSubTopic", "/gazebo/command/motor_speed", 6) + Element("motorNumber", n, 6);
  for (const auto& [effect, element] :
       {std::pair<std::string, std::string>{"rotor_drag_coefficient", "rotorDragCoefficient"},
        {"flapping_moment_coefficient", "rollingMomentCoefficient"}}) {
    if (const auto v = model.Effect(effect))
      xml += Element(element, PreciseNumber(*v), 6);
    else
      xml += "      <!-- " + element + ": " + effect + " not identified, the plugin's default applies -->\n";
  }
  xml += Element("motorSpeedPubTopic", "/motor_speed/" + n, 6) + Element("rotorVelocitySlowdownSim", "10", 6);
  return xml + "    </plugin>\n";
}

// Per-flight first moments: a simulator has one centre of mass, so the export takes their mean.
void SetMeanFirstMoment(IdentifiedModel* model) {
  const std::string config = model->vehicle.name;
  if (model->parameters.count(config + ".ms_x")) return;
  std::vector<std::string> names;
  for (const auto& entry : model->parameters) names.push_back(entry.first);
  const std::vector<std::string> owners = OwnFirstMomentOwners(config, names);
  if (owners.empty()) return;
  double spread_m = 0.0;
  for (int a = 0; a < 3; ++a) {
    Eigen::VectorXd values(static_cast<Eigen::Index>(owners.size()));
    for (size_t k = 0; k < owners.size(); ++k)
      values[static_cast<Eigen::Index>(k)] = model->parameters.at(owners[k] + "." + kBodyParameterNames[a]).value;
    const double mean = values.mean();
    const double spread = std::sqrt((values.array() - mean).square().mean());
    model->parameters[config + "." + kBodyParameterNames[a]] = {mean, spread, true};
    spread_m = std::max(spread_m, (values.maxCoeff() - values.minCoeff()) / model->vehicle.mass_kg);
  }
  model->note = "first moment: the mean of " + std::to_string(owners.size()) + " per-flight first moments (" + config +
                ".flight<k>.ms_*; std: their spread), whose centres of mass differ by up to " +
                ShortNumber(1000.0 * spread_m) + " mm along an axis";
}

}  // namespace

double IdentifiedModel::Value(const std::string& name) const {
  const auto it = parameters.find(name);
  return it == parameters.end() ? 0.0 : it->second.value;
}

std::optional<double> IdentifiedModel::Effect(const std::string& name) const {
  if (!effects.contains(name) || !effects[name].contains("value") || !effects[name]["value"].is_number())
    return std::nullopt;
  return effects[name]["value"].get<double>();
}

IdentifiedModel IdentifiedModelFromReport(const nlohmann::json& report, const std::string& source,
                                          const Vehicle& vehicle, const std::string& block) {
  IdentifiedModel model;
  model.source = source;
  model.vehicle = vehicle;
  model.block = !block.empty() ? block : (report.contains("refined") ? "refined" : "linear");
  if (!report.contains(model.block) || !report[model.block].contains("parameters"))
    throw Error(source + ": no '" + model.block + ".parameters' (an identify or refine report is needed)");
  for (const auto& [name, entry] : report[model.block]["parameters"].items()) {
    if (!entry.is_object() || !entry.contains("value") || !entry["value"].is_number()) continue;
    model.parameters[name] = {entry["value"].get<double>(),
                              entry.contains("std") && entry["std"].is_number() ? entry["std"].get<double>() : 0.0,
                              entry.value("essential", true)};
  }
  if (!(model.Value("kt") > 0.0)) throw Error(source + ": the report has no positive kt");
  if (!model.parameters.count(vehicle.name + ".I_xx"))
    throw Error(source + ": no parameters of configuration '" + vehicle.name + "' (the vehicle file's name)");
  SetMeanFirstMoment(&model);
  // Effects the refinement estimated (a report lists the others as disabled).
  if (model.block == "refined" && report["refined"].contains("effects"))
    for (const auto& [name, effect] : report["refined"]["effects"].items())
      if (effect.value("enabled", true)) model.effects[name] = effect;
  if (vehicle.command_to_speed) model.max_rotor_speed_radps = (*vehicle.command_to_speed)(1.0);
  return model;
}

MassProperties MassPropertiesOf(const IdentifiedModel& model) {
  MassProperties p;
  const std::string c = model.vehicle.name + ".";
  p.mass_kg = model.vehicle.mass_kg;
  const Eigen::Vector3d ms(model.Value(c + "ms_x"), model.Value(c + "ms_y"), model.Value(c + "ms_z"));
  p.centre_of_mass_m = ms / p.mass_kg;
  Eigen::Matrix3d inertia;
  inertia << model.Value(c + "I_xx"), model.Value(c + "I_xy"), model.Value(c + "I_xz"), model.Value(c + "I_xy"),
      model.Value(c + "I_yy"), model.Value(c + "I_yz"), model.Value(c + "I_xz"), model.Value(c + "I_yz"),
      model.Value(c + "I_zz");
  const Eigen::Vector3d& r = p.centre_of_mass_m;
  p.inertia_at_com = inertia - p.mass_kg * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  return p;
}

std::string GazeboSdf(const IdentifiedModel& model) {
  const MassProperties p = MassPropertiesOf(model);
  const Eigen::Matrix3d& I = p.inertia_at_com;
  std::string xml = "<?xml version=\"1.0\"?>\n<!-- rotorid export: " + model.source + " (" + model.block +
                    " parameters), vehicle '" + model.vehicle.name +
                    "'. Inertia about the centre of mass, in the "
                    "body frame (FLU)." +
                    (model.note.empty() ? "" : " " + model.note + ".") +
                    " -->\n<sdf version=\"1.6\">\n  <model name=\"" + model.vehicle.name + "\">\n";
  xml += "    <link name=\"base_link\">\n      <inertial>\n";
  xml += Element("pose",
                 PreciseNumber(p.centre_of_mass_m.x()) + " " + PreciseNumber(p.centre_of_mass_m.y()) + " " +
                     PreciseNumber(p.centre_of_mass_m.z()) + " 0 0 0",
                 8);
  xml += Element("mass", PreciseNumber(p.mass_kg), 8) + "        <inertia>\n";
  xml += Element("ixx", PreciseNumber(I(0, 0)), 10) + Element("ixy", PreciseNumber(I(0, 1)), 10) +
         Element("ixz", PreciseNumber(I(0, 2)), 10) + Element("iyy", PreciseNumber(I(1, 1)), 10) +
         Element("iyz", PreciseNumber(I(1, 2)), 10) + Element("izz", PreciseNumber(I(2, 2)), 10);
  xml += "        </inertia>\n      </inertial>\n    </link>\n";
  for (int i = 0; i < model.vehicle.num_rotors(); ++i) xml += MotorPlugin(model, i);
  return xml + "  </model>\n</sdf>\n";
}

std::string Px4SihParameters(const IdentifiedModel& model) {
  if (!(model.max_rotor_speed_radps > 0.0))
    throw Error(
        "px4-sih needs the rotor speed at full command for SIH_T_MAX and SIH_Q_MAX: give --max-rotor-speed "
        "or a command_to_speed map in the vehicle file");
  const MassProperties p = MassPropertiesOf(model);
  // SIH works in FRD: F = diag(1, -1, -1) flips the xy and xz products of inertia.
  const Eigen::Matrix3d F = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Matrix3d I = F * p.inertia_at_com * F;
  double arm_x = 0.0, arm_y = 0.0;
  for (const Rotor& r : model.vehicle.rotors) {
    arm_x += std::abs(r.position_m.x()) / model.vehicle.num_rotors();
    arm_y += std::abs(r.position_m.y()) / model.vehicle.num_rotors();
  }
  const double w2 = model.max_rotor_speed_radps * model.max_rotor_speed_radps;
  std::string out = "# rotorid export: " + model.source + " (" + model.block + " parameters), vehicle '" +
                    model.vehicle.name + "', max rotor speed " + PreciseNumber(model.max_rotor_speed_radps) + " rad/s\n";
  if (!model.note.empty()) out += "# " + model.note + "\n";
  const auto set = [&out](const std::string& name, double value) {
    out += "param set " + name + " " + PreciseNumber(value) + "\n";
  };
  set("SIH_MASS", p.mass_kg);
  set("SIH_IXX", I(0, 0));
  set("SIH_IYY", I(1, 1));
  set("SIH_IZZ", I(2, 2));
  set("SIH_IXY", I(0, 1));
  set("SIH_IXZ", I(0, 2));
  set("SIH_IYZ", I(1, 2));
  set("SIH_T_MAX", model.Value("kt") * w2);
  set("SIH_Q_MAX", model.Value("kd") * w2);
  set("SIH_L_ROLL", arm_y);
  set("SIH_L_PITCH", arm_x);
  if (const auto tau = model.Effect("motor_tau_s")) set("SIH_T_TAU", *tau);
  return out;
}

std::string ModelYaml(const IdentifiedModel& model) {
  std::ostringstream out;
  out << std::setprecision(12);
  out << "# rotorid export: every parameter and effect with its std\nsource: \"" << model.source
      << "\"\nblock: " << model.block << "\nvehicle: " << model.vehicle.name << "\nmass: " << model.vehicle.mass_kg
      << "\n";
  if (!model.note.empty()) out << "note: \"" << model.note << "\"\n";
  out << "parameters:\n";
  for (const auto& [name, v] : model.parameters)
    out << "  " << name << ": {value: " << v.value << ", std: " << v.std
        << ", essential: " << (v.essential ? "true" : "false") << "}\n";
  out << "effects:" << (model.effects.empty() ? " {}" : "") << "\n";
  for (const auto& [name, e] : model.effects.items())
    out << "  " << name << ": {value: " << e.value("value", nlohmann::json()).dump()
        << ", std: " << e.value("std", nlohmann::json()).dump() << "}\n";
  const MassProperties p = MassPropertiesOf(model);
  out << "centre_of_mass: [" << p.centre_of_mass_m.x() << ", " << p.centre_of_mass_m.y() << ", "
      << p.centre_of_mass_m.z() << "]\n";
  return out.str();
}

}  // namespace rotorid

// gz-sim and Gazebo Classic model directories: model.sdf (base_link, one link and revolute joint
// per rotor, one multicopter motor model per rotor) and model.config. The inertial blocks are about
// each link's centre of mass; together the links have exactly the identified mass, first moment and
// inertia at O_d (the rotor links' small share is taken off base_link).

#include <cmath>
#include <tuple>

#include "export_text.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/model/physical_consistency.h"

namespace rotorid::internal {
namespace {

// One link's inertial: its pose in the model frame (O_d, F_d), the centre of mass in the link frame,
// mass and inertia about that centre.
struct LinkInertial {
  Eigen::Vector3d pose_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d com_in_link_m = Eigen::Vector3d::Zero();
  double mass_kg = 0.0;
  Eigen::Matrix3d inertia_at_com = Eigen::Matrix3d::Zero();
};

constexpr double kRotorHeightOverRadius = 0.1;

double RotorDiscRadius(const Vehicle& vehicle) {
  const double arm = vehicle.MeanArm() > 0.0 ? vehicle.MeanArm() : 0.1;
  return vehicle.rotor_radius_m.value_or(0.4 * arm);
}

// Rotor links as short cylinders (height a tenth of the radius: strictly inside the triangle
// inequalities, unlike a flat disc) of a small share of the mass; base_link the rest, checked to be a body
// (the share shrinks until it is).
std::vector<LinkInertial> SplitIntoLinks(const ExportModel& model) {
  const VehicleParameters& p = model.parameters;
  const int n = model.vehicle.num_rotors();
  const double r = RotorDiscRadius(model.vehicle);
  for (double share = 1e-2; share >= 1e-6; share /= 10.0) {
    const double m_rotor = share * p.mass_kg / std::max(n, 1);
    const double lateral = (3.0 + kRotorHeightOverRadius * kRotorHeightOverRadius) / 12.0;
    const Eigen::Matrix3d cylinder = Eigen::Vector3d(lateral, lateral, 0.5).asDiagonal() * (m_rotor * r * r);
    BodyParameters base = p.body;
    std::vector<LinkInertial> links(1);
    for (const Rotor& rotor : model.vehicle.rotors) {
      base = AddPointMass(base, -m_rotor, rotor.position_m);
      base.inertia -= cylinder;
      links.push_back({rotor.position_m, Eigen::Vector3d::Zero(), m_rotor, cylinder});
    }
    const double m_base = p.mass_kg - n * m_rotor;
    if (!CheckPhysicalConsistency(m_base, base).consistent) continue;
    const MassProperties b = MassPropertiesOf(m_base, base);
    links[0] = {Eigen::Vector3d::Zero(), b.centre_of_mass_m, m_base, b.inertia_at_com};
    return links;
  }
  throw Error("export: no split of the body into base_link and rotor links is physically possible");
}

std::string Element(const std::string& name, const std::string& value, int indent) {
  return std::string(static_cast<size_t>(indent), ' ') + "<" + name + ">" + value + "</" + name + ">\n";
}

std::string Vector(const std::string& quantity, const Eigen::Vector3d& v) {
  return ExportNumber(quantity, v.x()) + " " + ExportNumber(quantity, v.y()) + " " + ExportNumber(quantity, v.z());
}

std::string Inertial(const std::string& link, const LinkInertial& l, int indent) {
  const std::string pad(static_cast<size_t>(indent), ' ');
  const Eigen::Matrix3d& I = l.inertia_at_com;
  const std::string q = link + " inertia";
  return pad + "<inertial>\n" +
         Element("pose", Vector(link + " centre of mass", l.com_in_link_m) + " 0 0 0", indent + 2) +
         Element("mass", ExportNumber(link + " mass", l.mass_kg), indent + 2) + pad + "  <inertia>\n" +
         Element("ixx", ExportNumber(q, I(0, 0)), indent + 4) + Element("ixy", ExportNumber(q, I(0, 1)), indent + 4) +
         Element("ixz", ExportNumber(q, I(0, 2)), indent + 4) + Element("iyy", ExportNumber(q, I(1, 1)), indent + 4) +
         Element("iyz", ExportNumber(q, I(1, 2)), indent + 4) + Element("izz", ExportNumber(q, I(2, 2)), indent + 4) +
         pad + "  </inertia>\n" + pad + "</inertial>\n";
}

std::string Box(const std::string& kind, const std::string& name, const Eigen::Vector3d& size) {
  return "      <" + kind + " name=\"" + name + "\">\n        <geometry><box><size>" + Vector("box size", size) +
         "</size></box></geometry>\n      </" + kind + ">\n";
}

// PX4's gz bridge reads these sensors of base_link (the world provides their systems).
std::string GzSensors() {
  std::string xml;
  for (const auto& [name, type, rate] : {std::tuple<const char*, const char*, int>{"imu_sensor", "imu", 250},
                                         {"air_pressure_sensor", "air_pressure", 50},
                                         {"magnetometer_sensor", "magnetometer", 100},
                                         {"navsat_sensor", "navsat", 30}})
    xml += std::string("      <sensor name=\"") + name + "\" type=\"" + type +
           "\">\n        <always_on>1</always_on>\n" + "        <update_rate>" + std::to_string(rate) +
           "</update_rate>\n      </sensor>\n";
  return xml;
}

std::string MotorModel(const ExportModel& model, int i, bool gz) {
  const Rotor& rotor = model.vehicle.rotors[static_cast<size_t>(i)];
  const std::string n = std::to_string(i);
  const double kt = model.parameters.rotor.kt;
  std::string xml = gz ? "    <plugin filename=\"gz-sim-multicopter-motor-model-system\" "
                         "name=\"gz::sim::systems::MulticopterMotorModel\">\n"
                       : "    <plugin name=\"rotor_" + n + "_motor_model\" filename=\"libgazebo_motor_model.so\">\n";
  if (!gz) xml += Element("robotNamespace", "", 6);
  xml += Element("jointName", "rotor_" + n + "_joint", 6) + Element("linkName", "rotor_" + n, 6) +
         Element("turningDirection", rotor.spin > 0 ? "ccw" : "cw", 6) +
         Element("timeConstantUp", ExportNumber("motor_tau_s", model.motor_tau_s), 6) +
         Element("timeConstantDown", ExportNumber("motor_tau_s", model.motor_tau_s), 6) +
         Element("maxRotVelocity", ExportNumber("max rotor speed", model.max_rotor_speed_radps), 6) +
         Element("motorConstant", ExportNumber("kt", kt), 6) +
         Element("momentConstant", ExportNumber("kd / kt", model.parameters.rotor.kd / kt), 6) +
         Element("commandSubTopic", gz ? "command/motor_speed" : "/gazebo/command/motor_speed", 6) +
         Element("motorNumber", n, 6) +
         Element("rotorDragCoefficient", ExportNumber("rotor drag", model.rotor_drag_coefficient), 6) +
         Element("rollingMomentCoefficient", "0", 6) +
         Element("motorSpeedPubTopic", gz ? "motor_speed/" + n : "/motor_speed/" + n, 6) +
         Element("rotorVelocitySlowdownSim", "10", 6);
  if (gz) xml += Element("motorType", "velocity", 6);
  return xml + "    </plugin>\n";
}

ExportHeader GazeboHeader(const ExportModel& model, bool gz, double rotor_mass_share) {
  ExportHeader h;
  h.format = gz ? "gz-sim model (MulticopterMotorModel)" : "Gazebo Classic model (libgazebo_motor_model.so)";
  h.units =
      "SI (kg, m, kg m^2, s, rad/s); model frame = the body frame F_d (FLU: x forward, y left, z up) with its "
      "origin O_d at the rotor cross; each <inertial> about its link's centre of mass";
  h.command_to_speed =
      std::string("the motor model takes rotor speed commands in rad/s (") +
      (gz ? "gz.msgs.Actuators velocity[motorNumber] on /<model name>/command/motor_speed"
          : "/gazebo/command/motor_speed from the mavlink interface, velocity = input_scaling (u + input_offset) + "
            "zero_position_armed") +
      "), clamped at maxRotVelocity; thrust = motorConstant Omega^2 (kt), drag torque = momentConstant x thrust "
      "(kd / kt); PX4 maps its output u in [0, 1] linearly to speed (the px4 format writes the matching parameters)";
  h.holds = {
      "motor_lag: timeConstantUp = timeConstantDown = motor_tau_s (first-order filter of the commanded speed; "
      "0 = none, as the model predicts)",
      "rotor_drag: rotorDragCoefficient = rotor_drag_coefficient (the same law, -k |Omega| v_perp at the hub)"};
  h.not_held = {
      "flapping_moment_coefficient (" + ShortNumber(model.flapping_moment_coefficient) +
          "): the plugin's rollingMoment acts along the in-plane velocity, not about z x v_perp; "
          "rollingMomentCoefficient is written 0",
      "battery: the plugin takes rotor speeds and has no voltage",
      "rotor_inertia: rotor links spin at 1/rotorVelocitySlowdownSim of the rotor speed; they are short cylinders "
      "holding " +
          ShortNumber(100.0 * rotor_mass_share) + " % of the mass (taken off base_link)"};
  return h;
}

std::string ModelSdf(const ExportModel& model, bool gz) {
  const std::vector<LinkInertial> links = SplitIntoLinks(model);
  const double rotor_share = 1.0 - links[0].mass_kg / model.parameters.mass_kg;
  std::string xml = "<?xml version=\"1.0\"?>\n";
  for (const std::string& line : HeaderLines(model, GazeboHeader(model, gz, rotor_share))) xml += XmlComment(line, 0);
  const double arm = model.vehicle.MeanArm() > 0.0 ? model.vehicle.MeanArm() : 0.1;
  const Eigen::Vector3d box(1.2 * arm, 1.2 * arm, 0.3 * arm);
  xml += "<sdf version=\"1.9\">\n  <model name=\"" + XmlEscape(model.vehicle.name) + "\">\n";
  xml += "    <link name=\"base_link\">\n" + Inertial("base_link", links[0], 6) +
         Box("collision", "base_collision", box) + Box("visual", "base_visual", box) + (gz ? GzSensors() : "") +
         "    </link>\n";
  const double radius = RotorDiscRadius(model.vehicle);
  for (int i = 0; i < model.vehicle.num_rotors(); ++i) {
    const std::string n = "rotor_" + std::to_string(i);
    const LinkInertial& l = links[static_cast<size_t>(i) + 1];
    xml += XmlComment(n + ": rotor " + std::to_string(i + 1) + " of the vehicle file", 4);
    xml += "    <link name=\"" + n + "\">\n" + Element("pose", Vector(n + " position", l.pose_m) + " 0 0 0", 6) +
           Inertial(n, l, 6) + "      <visual name=\"" + n + "_visual\">\n        <geometry><cylinder><radius>" +
           ExportNumber("rotor radius", radius) + "</radius><length>" +
           ExportNumber("rotor height", kRotorHeightOverRadius * radius) + "</length></cylinder></geometry>\n" +
           "      </visual>\n    </link>\n";
    xml += "    <joint name=\"" + n + "_joint\" type=\"revolute\">\n" + Element("parent", "base_link", 6) +
           Element("child", n, 6) + "      <axis>\n" + Element("xyz", "0 0 1", 8) +
           "        <limit><lower>-1e+16</lower><upper>1e+16</upper></limit>\n      </axis>\n    </joint>\n";
  }
  for (int i = 0; i < model.vehicle.num_rotors(); ++i) xml += MotorModel(model, i, gz);
  return xml + "  </model>\n</sdf>\n";
}

std::string ModelConfig(const ExportModel& model) {
  return "<?xml version=\"1.0\"?>\n<model>\n  <name>" + XmlEscape(model.vehicle.name) +
         "</name>\n  <version>1.0</version>\n  <sdf version=\"1.9\">model.sdf</sdf>\n  <author>\n"
         "    <name>rotorid export</name>\n  </author>\n  <description>" +
         XmlEscape("identified from " + model.source + " (" + model.block + " parameters) by rotorid") +
         "</description>\n</model>\n";
}

}  // namespace

std::vector<ExportedFile> GzModel(const ExportModel& model) {
  RequireMaxRotorSpeed(model, "gz");
  return {{"model.sdf", ModelSdf(model, true)}, {"model.config", ModelConfig(model)}};
}

std::vector<ExportedFile> GazeboClassicModel(const ExportModel& model) {
  RequireMaxRotorSpeed(model, "gazebo-classic");
  return {{"model.sdf", ModelSdf(model, false)}, {"model.config", ModelConfig(model)}};
}

}  // namespace rotorid::internal

#include "rotorid/io/vehicle_yaml.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "io/yaml_fields.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/effects.h"

namespace rotorid {
namespace {

// The keys of effects a vehicle file may give known values of (imu_position: [x, y, z]), each a
// list of the effect's values within its physical bounds.
void ReadKnownEffects(const YAML::Node& root, const std::string& source, Vehicle* vehicle) {
  for (EffectKind kind : AllEffects()) {
    const std::string& key = kind->info().vehicle_key;
    if (key.empty()) continue;
    const YAML::Node node = root[key];
    if (!node) continue;
    const int size = kind->FixedDimension();
    if (!node.IsSequence() || static_cast<int>(node.size()) != size)
      internal::FailAt(source, node,
                       key + " must be a list of " + std::to_string(size) + " values (" + kind->info().unit + ")");
    Eigen::VectorXd value(size);
    for (int k = 0; k < size; ++k) {
      value[k] = internal::ReadYamlNumber(source, node[k], key);
      if (!(value[k] >= kind->info().lower_bound && value[k] <= kind->info().upper_bound))
        internal::FailAt(source, node[k],
                         key + " values must lie in [" + ShortNumber(kind->info().lower_bound) + ", " +
                             ShortNumber(kind->info().upper_bound) + "] " + kind->info().unit + " (" + kind->name() +
                             "'s physical range)");
    }
    vehicle->known_effects[kind->name()] = value;
  }
}

// A misspelt optional key (rotor_raduis) would silently leave its value out: an error instead.
void RejectUnknownKeys(const YAML::Node& root, const std::string& source) {
  std::set<std::string> known = {"name",         "mass",      "rotors", "command_to_speed", "command_to_speed_voltage",
                                 "rotor_radius", "simulation"};  // the simulator's true parameters (docs/simulator.md)
  for (EffectKind kind : AllEffects())
    if (!kind->info().vehicle_key.empty()) known.insert(kind->info().vehicle_key);
  for (const auto& entry : root) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : "";
    if (known.count(key)) continue;
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    internal::FailAt(source, entry.first,
                     "unknown key '" + ShortText(key, 80) + "' (a vehicle file knows " + list + ")");
  }
}

}  // namespace

Vehicle ParseVehicleYaml(const std::string& text, const std::string& source) {
  const YAML::Node root = internal::LoadYaml(text, source);
  if (!root.IsMap()) throw Error(source + ": a vehicle file must be a YAML mapping with name, mass and rotors");
  RejectUnknownKeys(root, source);
  Vehicle vehicle;
  if (const YAML::Node name = root["name"]) {
    if (!name.IsScalar() || name.Scalar().empty()) internal::FailAt(source, name, "name must be a non-empty string");
    vehicle.name = name.Scalar();
  }
  const YAML::Node mass = root["mass"];
  if (!mass) throw Error(source + ": missing 'mass' (kg)");
  vehicle.mass_kg = internal::ReadYamlNumber(source, mass, "mass");
  if (!(vehicle.mass_kg > 0.0)) internal::FailAt(source, mass, "mass must be positive (kg)");
  const YAML::Node rotors = root["rotors"];
  if (!rotors) throw Error(source + ": missing 'rotors'");
  if (!rotors.IsSequence() || rotors.size() == 0) internal::FailAt(source, rotors, "rotors must be a non-empty list");
  if (rotors.size() > static_cast<size_t>(kMaxVehicleRotors))
    internal::FailAt(source, rotors,
                     "rotors lists " + std::to_string(rotors.size()) + " rotors; rotorid handles at most " +
                         std::to_string(kMaxVehicleRotors));
  for (size_t i = 0; i < rotors.size(); ++i) {
    const YAML::Node rotor = rotors[i];
    const std::string label = "rotor " + std::to_string(i + 1);
    if (!rotor.IsMap())
      internal::FailAt(source, rotor, label + " must be a mapping {position: [x, y, z], spin: +1|-1}");
    const YAML::Node position = rotor["position"];
    if (!position || !position.IsSequence() || position.size() != 3)
      internal::FailAt(source, position ? position : rotor, label + " needs position: [x, y, z] (m)");
    Rotor r;
    for (int k = 0; k < 3; ++k) r.position_m[k] = internal::ReadYamlNumber(source, position[k], label + " position");
    const YAML::Node spin = rotor["spin"];
    if (!spin) internal::FailAt(source, rotor, label + " needs spin: +1 or -1");
    const double spin_value = internal::ReadYamlNumber(source, spin, label + " spin");
    if (spin_value != 1.0 && spin_value != -1.0) internal::FailAt(source, spin, label + " spin must be +1 or -1");
    r.spin = static_cast<int>(spin_value);
    vehicle.rotors.push_back(r);
  }
  if (const YAML::Node map = root["command_to_speed"]) {
    if (!map.IsSequence() || map.size() != 3)
      internal::FailAt(source, map, "command_to_speed must be [c0, c1, c2]: Omega = c0 + c1 u + c2 u^2 (rad/s)");
    CommandToSpeed command_to_speed;
    for (int k = 0; k < 3; ++k)
      command_to_speed.coefficients[k] = internal::ReadYamlNumber(source, map[k], "command_to_speed");
    if (const std::string problem = command_to_speed.Validate(); !problem.empty())
      internal::FailAt(source, map, problem);
    vehicle.command_to_speed = command_to_speed;
  }
  if (const YAML::Node voltage = root["command_to_speed_voltage"]) {
    vehicle.command_to_speed_voltage_v = internal::ReadYamlNumber(source, voltage, "command_to_speed_voltage");
    if (!(*vehicle.command_to_speed_voltage_v > 0.0) || *vehicle.command_to_speed_voltage_v > 1000.0)
      internal::FailAt(source, voltage, "command_to_speed_voltage must be a battery voltage in V, in (0, 1000]");
  }
  if (const YAML::Node radius = root["rotor_radius"]) {
    vehicle.rotor_radius_m = internal::ReadYamlNumber(source, radius, "rotor_radius");
    if (!(*vehicle.rotor_radius_m > 0.0) || *vehicle.rotor_radius_m > 2.0)
      internal::FailAt(source, radius, "rotor_radius must be a propeller radius in m, in (0, 2]");
  }
  ReadKnownEffects(root, source, &vehicle);
  if (const std::string problem = vehicle.Validate(); !problem.empty()) throw Error(source + ": " + problem);
  return vehicle;
}

Vehicle ReadVehicleYaml(const std::string& path) {
  Vehicle vehicle = ParseVehicleYaml(ReadFile(path, kMaxYamlFileBytes), path);
  vehicle.source = path;
  return vehicle;
}

std::string VehicleToYaml(const Vehicle& vehicle) {
  std::ostringstream out;
  out << std::setprecision(10);
  // Quoted (a JSON string is a YAML double-quoted scalar): a name like "A: #1" stays one string.
  out << "name: " << nlohmann::json(vehicle.name).dump() << "\n";
  out << "mass: " << vehicle.mass_kg << "  # kg\n";
  out << "rotors:  # position in F_d (m); spin +1 = counter-clockwise seen from above\n";
  for (const Rotor& r : vehicle.rotors) {
    out << "  - {position: [" << r.position_m.x() << ", " << r.position_m.y() << ", " << r.position_m.z()
        << "], spin: " << (r.spin > 0 ? "+1" : "-1") << "}\n";
  }
  if (vehicle.command_to_speed) {
    const Eigen::Vector3d& c = vehicle.command_to_speed->coefficients;
    out << "command_to_speed: [" << c[0] << ", " << c[1] << ", " << c[2] << "]  # Omega = c0 + c1 u + c2 u^2 (rad/s)\n";
    if (vehicle.command_to_speed_voltage_v)
      out << "command_to_speed_voltage: " << *vehicle.command_to_speed_voltage_v
          << "  # V, the map's battery voltage\n";
  }
  if (vehicle.rotor_radius_m) out << "rotor_radius: " << *vehicle.rotor_radius_m << "  # m\n";
  for (const auto& [name, value] : vehicle.known_effects) {
    const EffectKind kind = ParseEffectKind(name);
    out << kind->info().vehicle_key << ": [";
    for (Eigen::Index k = 0; k < value.size(); ++k) out << (k ? ", " : "") << value[k];
    out << "]  # " << kind->info().unit << ", a known " << name << "\n";
  }
  return out.str();
}

}  // namespace rotorid

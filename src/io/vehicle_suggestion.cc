#include "rotorid/io/vehicle_suggestion.h"

#include "io/yaml_fields.h"
#include "rotorid/core/error.h"
#include "rotorid/io/blackbox_flight.h"
#include "rotorid/io/column_map.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/io/px4_flight.h"
#include "rotorid/io/ulog.h"

namespace rotorid {

namespace {

constexpr double kCrazyflieHalfDiagonalM = 0.0325;

Vehicle VehicleFromColumnMap(const ColumnMap& map, const std::string& name) {
  const auto positions = map.metadata.find("rotor_positions");
  const auto spins = map.metadata.find("rotor_spins");
  if (positions == map.metadata.end() || spins == map.metadata.end())
    throw Error(map.source +
                ": the column map's metadata has no rotor_positions and rotor_spins, so the vehicle "
                "cannot be derived; write the vehicle file by hand (docs/input_formats.md)");
  const YAML::Node p = internal::LoadYaml(positions->second, map.source + " metadata rotor_positions");
  const YAML::Node s = internal::LoadYaml(spins->second, map.source + " metadata rotor_spins");
  if (!p.IsSequence() || !s.IsSequence() || p.size() != s.size() || p.size() == 0)
    throw Error(map.source + ": rotor_positions and rotor_spins must be lists of the same length");
  Vehicle vehicle;
  vehicle.name = name;
  for (size_t i = 0; i < p.size(); ++i) {
    if (!p[i].IsSequence() || p[i].size() != 3) internal::FailAt(map.source, p[i], "a rotor position is [x, y, z]");
    Rotor rotor;
    for (int k = 0; k < 3; ++k) rotor.position_m[k] = internal::ReadYamlNumber(map.source, p[i][k], "rotor position");
    rotor.spin = internal::ReadYamlNumber(map.source, s[i], "rotor spin") > 0 ? 1 : -1;
    vehicle.rotors.push_back(rotor);
  }
  return vehicle;
}

}  // namespace

Vehicle CrazyflieLayout(const std::string& name) {
  Vehicle vehicle;
  vehicle.name = name;
  const double a = kCrazyflieHalfDiagonalM;
  vehicle.rotors = {{{a, -a, 0.0}, 1}, {{-a, -a, 0.0}, -1}, {{-a, a, 0.0}, 1}, {{a, a, 0.0}, -1}};
  return vehicle;
}

VehicleSuggestion SuggestVehicle(const std::string& log_path, const VehicleSuggestionOptions& options) {
  if (!(options.mass_kg > 0.0)) throw Error("the mass must be positive (kg, from a scale)");
  const std::string& name = options.name;
  const std::string& column_map_path = options.column_map_path;
  VehicleSuggestion suggestion;
  // One branch per log format.
  switch (DetectLogFormat(log_path)) {
    case LogFormat::kULog:
      suggestion.vehicle = SuggestVehicleFromPx4Parameters(ReadULog(log_path), name);
      suggestion.source = log_path + ": PX4 CA_ROTOR* parameters (FRD converted to FLU)";
      break;
    case LogFormat::kCrazyflieUsd:
      suggestion.vehicle = CrazyflieLayout(name);
      suggestion.source = log_path + ": Crazyflie micro-SD log, the Crazyflie 2.x layout (92 mm diagonal)";
      break;
    case LogFormat::kBlackbox: {
      QuadXGeometry geometry;
      geometry.arm_length_m = options.arm_length_m;
      geometry.mass_kg = options.mass_kg;
      geometry.props_out = options.props_out;
      const std::vector<BlackboxLog> logs = ReadBlackboxFile(log_path);
      suggestion.vehicle = SuggestVehicleFromBlackboxHeader(SelectBlackboxLog(logs, log_path), geometry, name);
      suggestion.source = log_path + ": blackbox header (Quad-X, Betaflight motor order), arm " +
                          std::to_string(options.arm_length_m) + " m given on the command line";
      break;
    }
    case LogFormat::kCsv:
      if (column_map_path.empty())
        throw Error(log_path +
                    ": a CSV log says nothing about the rotors; give --column-map with rotor_positions and "
                    "rotor_spins in its metadata, or write the vehicle file by hand");
      suggestion.vehicle = VehicleFromColumnMap(ReadColumnMap(column_map_path), name);
      suggestion.source = column_map_path + ": the column map's metadata";
      break;
  }
  suggestion.vehicle.mass_kg = options.mass_kg;
  if (const std::string problem = suggestion.vehicle.Validate(); !problem.empty())
    throw Error(log_path + ": the suggested vehicle is not valid: " + problem);
  return suggestion;
}

}  // namespace rotorid

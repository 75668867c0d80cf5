#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/vehicle_suggestion.h"
#include "rotorid/io/vehicle_yaml.h"

namespace rotorid::cli {

Command AddVehicleCommand(CLI::App& root) {
  struct Options {
    std::string log;
    double mass_kg = 0.0;
    std::string out;
    std::string name = "A";
    std::string column_map;
    double arm_length_m = 0.0;
    bool props_out = false;
    bool quiet = false;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "vehicle",
      "writes a vehicle file from what a log knows: PX4 CA_ROTOR* parameters, the Crazyflie 2.x layout, "
      "a Quad-X from a Betaflight/INAV blackbox header (with --arm-length), or a column map's metadata "
      "(rotor_positions, rotor_spins); the mass comes from a scale");
  CLI::App* app = command.app;
  app->add_option("--log", options->log,
                  "flight log (PX4 ULog, Crazyflie micro-SD, Betaflight/INAV blackbox, or CSV with --column-map)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--mass", options->mass_kg, "mass in kg, measured with a scale")
      ->required()
      ->check(CLI::PositiveNumber);
  app->add_option("--out", options->out, "vehicle YAML to write")->required();
  app->add_option("--name", options->name, "configuration name (prefixes the body parameters)")->capture_default_str();
  app->add_option("--column-map", options->column_map, "column map (YAML) whose metadata gives the rotors")
      ->check(CLI::ExistingFile);
  app->add_option("--arm-length", options->arm_length_m,
                  "blackbox logs: hub-to-centre distance of each rotor (m); the header does not record it")
      ->check(CLI::PositiveNumber);
  app->add_flag("--props-out", options->props_out, "blackbox logs: the props turn outwards (reversed)");
  app->add_flag("--quiet,-q", options->quiet, "print nothing but errors");
  command.run = [options]() {
    MarkOptionsValidated();
    VehicleSuggestionOptions suggest;
    suggest.mass_kg = options->mass_kg;
    suggest.name = options->name;
    suggest.column_map_path = options->column_map;
    suggest.arm_length_m = options->arm_length_m;
    suggest.props_out = options->props_out;
    const VehicleSuggestion suggestion = SuggestVehicle(options->log, suggest);
    WriteFileAtomically(options->out, "# written by rotorid vehicle from " + suggestion.source +
                                          "\n# mass: given on the command line\n" + VehicleToYaml(suggestion.vehicle));
    if (!options->quiet)
      std::cout << "rotorid vehicle: " << suggestion.vehicle.num_rotors() << " rotors from " << suggestion.source
                << " -> " << options->out << "\n";
    return 0;
  };
  return command;
}

}  // namespace rotorid::cli

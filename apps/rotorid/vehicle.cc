#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/vehicle_command.h"

namespace rotorid::cli {

Command AddVehicleCommand(CLI::App& root) {
  auto options = std::make_shared<VehicleCommandOptions>();
  auto quiet = std::make_shared<bool>(false);
  Command command;
  command.app = root.add_subcommand(
      "vehicle",
      "writes a vehicle file from what a log knows: PX4 CA_ROTOR* parameters, the Crazyflie 2.x layout, "
      "a Quad-X from a Betaflight/INAV blackbox header (with --arm-length), or a column map's metadata "
      "(rotor_positions, rotor_spins); the mass comes from a scale");
  CLI::App* app = command.app;
  VehicleSuggestionOptions& suggest = options->suggestion;
  app->add_option("--log", options->log,
                  "flight log (PX4 ULog, Crazyflie micro-SD, Betaflight/INAV blackbox, or CSV with --column-map)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--mass", suggest.mass_kg, "mass in kg, measured with a scale")
      ->required()
      ->check(CLI::PositiveNumber);
  app->add_option("--out", options->out, "vehicle YAML to write")->required();
  app->add_option("--name", suggest.name, "configuration name (prefixes the body parameters)")->capture_default_str();
  app->add_option("--column-map", suggest.column_map_path, "column map (YAML) whose metadata gives the rotors")
      ->check(CLI::ExistingFile);
  app->add_option("--arm-length", suggest.arm_length_m,
                  "blackbox logs: hub-to-centre distance of each rotor (m); the header does not record it")
      ->check(CLI::PositiveNumber);
  app->add_flag("--props-out", suggest.props_out, "blackbox logs: the props turn outwards (reversed)");
  app->add_flag("--quiet,-q", *quiet, "print nothing but errors");
  command.run = [options, quiet]() {
    MarkOptionsValidated();
    const VehicleSuggestion suggestion = RunVehicleCommand(*options);
    if (!*quiet) std::cout << VehicleConsoleLine(*options, suggestion) << "\n";
    return 0;
  };
  return command;
}

}  // namespace rotorid::cli

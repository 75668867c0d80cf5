#include "rotorid/report/export.h"

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddExportCommand(CLI::App& root) {
  struct Options {
    std::string params;
    std::string vehicle;
    std::string format;
    std::string out;
    std::string block;
    double max_rotor_speed_radps = 0.0;
    bool quiet = false;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "export",
      "writes an identified model for simulators: gazebo (SDF fragment: inertial block and one multicopter "
      "motor model per rotor), px4-sih (PX4 SIH parameters) or yaml (every parameter and effect with std)");
  CLI::App* app = command.app;
  app->add_option("--params", options->params, "identify or refine JSON report")->required()->check(CLI::ExistingFile);
  app->add_option("--vehicle", options->vehicle, "the vehicle file of the report's configuration")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--format", options->format, "gazebo, px4-sih or yaml")
      ->required()
      ->check(CLI::IsMember({"gazebo", "px4-sih", "yaml"}));
  app->add_option("--out", options->out, "file to write")->required();
  app->add_option("--block", options->block, "linear or refined (default: refined when present)")
      ->check(CLI::IsMember({"linear", "refined"}));
  app->add_option("--max-rotor-speed", options->max_rotor_speed_radps,
                  "rotor speed at full command (rad/s; default: the vehicle's command_to_speed at u = 1)")
      ->check(CLI::PositiveNumber);
  app->add_flag("--quiet,-q", options->quiet, "print nothing but errors");
  command.run = [options]() {
    MarkOptionsValidated();
    IdentifiedModel model = IdentifiedModelFromReport(ReadJsonFile(options->params), options->params,
                                                      ReadVehicleYaml(options->vehicle), options->block);
    if (options->max_rotor_speed_radps > 0.0) model.max_rotor_speed_radps = options->max_rotor_speed_radps;
    const std::string text = options->format == "gazebo"    ? GazeboSdf(model)
                             : options->format == "px4-sih" ? Px4SihParameters(model)
                                                            : ModelYaml(model);
    WriteFileAtomically(options->out, text);
    if (!options->quiet)
      std::cout << "rotorid export: " << model.block << " parameters of " << options->params << " as "
                << options->format << " -> " << options->out << "\n";
    return 0;
  };
  return command;
}

}  // namespace rotorid::cli

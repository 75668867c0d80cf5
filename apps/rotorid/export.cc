#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/export_command.h"

namespace rotorid::cli {

Command AddExportCommand(CLI::App& root) {
  auto options = std::make_shared<ExportCommandOptions>();
  auto quiet = std::make_shared<bool>(false);
  Command command;
  command.out_may_be_folder = true;
  command.app = root.add_subcommand(
      "export",
      "writes an identified model for simulators (never a non-physical one): gz or gazebo-classic (a model directory), "
      "px4 (parameter file), px4-sih, ardupilot (SITL JSON frame) or yaml; docs/simulators.md");
  CLI::App* app = command.app;
  app->add_option("--params", options->params_path, "identify or refine JSON report")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--vehicle", options->vehicle_path, "the vehicle file of the report's configuration")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--format", options->format, "gz, gazebo-classic (v2's gazebo), px4, px4-sih, ardupilot or yaml")
      ->required()
      ->check(CLI::IsMember(ExportFormatNames()));
  app->add_option("--out", options->out, "file to write; a directory for gz and gazebo-classic")->required();
  app->add_option("--block", options->block, "linear or refined (default: refined when present)")
      ->check(CLI::IsMember({"linear", "refined"}));
  app->add_option("--max-rotor-speed", options->max_rotor_speed_radps,
                  "rotor speed at full command (rad/s; default: the vehicle's command_to_speed at u = 1)")
      ->check(CLI::PositiveNumber);
  app->add_option("--set", options->settings,
                  "NAME=VALUE (repeatable): a value the report leaves open or that you measured (kd, I_zz, ..., "
                  "motor_tau_s, max_rotor_speed)")
      ->check(ParsesWith(ParseExportSetting));
  app->add_flag("--force", options->force, "export a report that failed its checks (they go into the file's header)");
  app->add_flag("--quiet,-q", *quiet, "print nothing but errors");
  command.run = [options, quiet]() {
    MarkOptionsValidated();
    const ExportCommandResult result = RunExportCommand(*options);
    if (!*quiet) std::cout << ExportConsoleText(*options, result);
    return 0;
  };
  return command;
}

}  // namespace rotorid::cli

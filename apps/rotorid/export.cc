#include "rotorid/report/export.h"

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddExportCommand(CLI::App& root) {
  struct Options {
    std::string params, vehicle, format, out, block;
    double max_rotor_speed_radps = 0.0;
    std::vector<std::string> set;
    bool force = false, quiet = false;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.out_may_be_folder = true;
  command.app = root.add_subcommand(
      "export",
      "writes an identified model for simulators (never a non-physical one): gz or gazebo-classic (a model directory), "
      "px4 (parameter file), px4-sih, ardupilot (SITL JSON frame) or yaml; docs/simulators.md");
  CLI::App* app = command.app;
  app->add_option("--params", options->params, "identify or refine JSON report")->required()->check(CLI::ExistingFile);
  app->add_option("--vehicle", options->vehicle, "the vehicle file of the report's configuration")
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
  app->add_option("--set", options->set,
                  "NAME=VALUE (repeatable): a value the report leaves open or that you measured (kd, I_zz, ..., "
                  "motor_tau_s, max_rotor_speed)")
      ->check([](const std::string& s) {
        try {
          ParseExportSetting(s);
        } catch (const Error& e) {
          return std::string(e.what());
        }
        return std::string();
      });
  app->add_flag("--force", options->force, "export a report that failed its checks (they go into the file's header)");
  app->add_flag("--quiet,-q", options->quiet, "print nothing but errors");
  command.run = [options]() {
    MarkOptionsValidated();
    const IdentifiedModel identified = IdentifiedModelFromReport(ReadJsonFile(options->params), options->params,
                                                                 ReadVehicleYaml(options->vehicle), options->block);
    ExportOptions export_options;
    export_options.force = options->force;
    if (options->max_rotor_speed_radps > 0.0) export_options.set["max_rotor_speed"] = options->max_rotor_speed_radps;
    for (const std::string& s : options->set) export_options.set.insert(ParseExportSetting(s));
    const ExportFormat format = ParseExportFormat(options->format);
    const ExportModel model = ResolveExportModel(identified, export_options);
    WriteExportedFiles(ExportFiles(model, format), options->out, ExportWritesDirectory(format));
    if (options->quiet) return 0;
    std::cout << "rotorid export: " << identified.block << " parameters of " << options->params << " as "
              << ExportFormatName(format) << " -> " << options->out << "\n";
    for (const std::string& line : model.provenance) std::cout << "  " << line << "\n";
    return 0;
  };
  return command;
}

}  // namespace rotorid::cli

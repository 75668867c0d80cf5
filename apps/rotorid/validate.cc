#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/validate_command.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddValidateCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    ValidateCommandOptions validate;
    FlightSourceOptions source;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "validate",
      "applies saved parameters (--params, an identify or refine report) to other flights: the paper's "
      "cross-validation, Table III");
  command.app->add_option("--params", options->validate.params_path, "identify/refine JSON report")
      ->required()
      ->check(CLI::ExistingFile);
  command.app->add_option("--block", options->validate.block, "linear or refined (default: refined when present)");
  command.app->add_option("--rotor-signal", options->source.rotor_signal, "auto, rpm or command");
  command.app->add_option("--column-map", options->source.column_map_path,
                          "column map (YAML) for CSV exports of other tools");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/false);
  command.run = [options, app = command.app]() {
    ValidateCommandOptions validate = options->validate;
    validate.input = ResolveCommandInput(*app, options->flights, options->source);
    MarkOptionsValidated();
    const ValidateCommandResult result = RunValidate(validate);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, ValidateJson(result));
    const std::string report_path = WriteValidateReport(result);
    if (!options->flights.quiet) {
      std::cout << ValidateBrief(result);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(result.checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/identify_command.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddIdentifyCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app =
      root.add_subcommand("identify",
                          "the paper's IDIM-TLS: parameters with statistics, essential parameters, weighted and "
                          "multi-configuration TLS (repeat --vehicle/--log for configurations A and B)");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/false);
  AddIdentifyOptions(command.app, &options->identify);
  AddFirstMomentOption(command.app, &options->identify);
  command.run = [options, app = command.app]() {
    IdentifyCommandOptions identify;
    identify.identify = ResolveIdentifyOptions(&options->identify);
    identify.input = ResolveCommandInput(*app, options->flights, SourceOptions(options->identify));
    MarkOptionsValidated();
    const IdentifyCommandResult result = RunIdentify(identify);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, IdentifyJson(result));
    const std::string report_path = WriteIdentifyReport(result);
    if (!options->flights.quiet) {
      std::cout << IdentifyBrief(result);
      PrintWarnings(result.linear.warnings);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(result.checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

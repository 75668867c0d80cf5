#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/ablate_command.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddAblateCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
    AblateCommandOptions ablate;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "ablate",
      "refines with every subset of the chosen effects and tabulates relative errors (identification and "
      "held-out flights), parameter counts, information criteria and key parameters");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/true);
  AddIdentifyOptions(command.app, &options->identify);
  command.app
      ->add_option("--effects", options->ablate.effects,
                   "effects to combine (default all: 2^n subsets of the default effects the flights can carry)")
      ->capture_default_str();
  command.app->add_option("--threads", options->ablate.threads, "subsets refined in parallel")->capture_default_str();
  command.run = [options, app = command.app]() {
    AblateCommandOptions ablate = options->ablate;
    ablate.identify = ResolveIdentifyOptions(&options->identify);
    ablate.input = ResolveCommandInput(*app, options->flights, SourceOptions(options->identify));
    MarkOptionsValidated();
    const AblateCommandResult result = RunAblate(ablate);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, AblateJson(result));
    const std::string report_path = WriteAblateReport(result);
    if (!options->flights.quiet) {
      std::cout << AblateBrief(result);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(result.checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

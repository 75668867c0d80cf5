#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/delay_command.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddDelayCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
    DelayOptions delay;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "delay",
      "estimates the command-to-IMU delay of a log with its std: a global search of the TLS criterion, then "
      "the joint refinement");
  CLI::App* app = command.app;
  AddFlightOptions(app, &options->flights, /*held_out=*/false);
  AddIdentifyOptions(app, &options->identify);
  AddFirstMomentOption(app, &options->identify);
  app->add_option("--min-s", options->delay.search.min_s, "smallest delay searched (s)")->capture_default_str();
  app->add_option("--max-s", options->delay.search.max_s, "largest delay searched (s)")->capture_default_str();
  app->add_option("--step-s", options->delay.search.step_s, "grid step of the global search (s)")
      ->capture_default_str();
  app->add_flag("--with-motor-lag", options->delay.with_motor_lag, "estimate the motor time constant jointly");
  app->add_option("--threads", options->delay.num_threads)->capture_default_str();
  command.run = [options, app]() {
    DelayCommandOptions delay{{}, ResolveIdentifyOptions(&options->identify), options->delay};
    delay.input = ResolveCommandInput(*app, options->flights, SourceOptions(options->identify));
    MarkOptionsValidated();
    const DelayCommandResult result = RunDelay(delay);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, DelayJson(result));
    const std::string report_path = WriteDelayReport(result);
    if (!options->flights.quiet) {
      std::cout << DelayBrief(result);
      PrintWarnings(result.estimate.warnings);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(result.checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

#include <iostream>

#include "commands.h"

namespace rotorid::cli {

namespace {

bool options_validated = false;

}  // namespace

void MarkOptionsValidated() { options_validated = true; }
bool OptionsValidated() { return options_validated; }

void AddFlightOptions(CLI::App* app, FlightOptions* options, bool held_out) {
  app->add_option("--vehicle", options->vehicle_paths, "vehicle file (YAML); repeat for several configurations")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--log", options->log_paths,
                  "flight log (CSV, PX4 ULog or Crazyflie micro-SD), paired with --vehicle")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--weight", options->weights,
                  "weight of each --vehicle/--log pair (default 1; the paper uses 2 for B)")
      ->check(Within(1e-6, 1e6));
  app->add_option("--window", options->windows,
                  "START,END: seconds of the log's own time base to use, paired in order with --log")
      ->check(ParsesWith(ParseTimeWindow));
  if (held_out) {
    app->add_option("--validate-vehicle", options->validate_vehicle_paths, "vehicle file of a held-out flight")
        ->check(CLI::ExistingFile);
    app->add_option("--validate-log", options->validate_log_paths,
                    "held-out flight log, paired with --validate-vehicle")
        ->check(CLI::ExistingFile);
    app->add_option("--validate-window", options->validate_windows, "START,END of each --validate-log, in order")
        ->check(ParsesWith(ParseTimeWindow));
  }
  app->add_option("--segment", options->segment,
                  "auto: keep only the airborne, unsaturated stretches of each log; none: the whole log (or window)")
      ->check(CLI::IsMember({"auto", "none"}))
      ->capture_default_str();
  app->add_option("--json", options->json_path, "write the machine-readable report to this file");
  app->add_option("--report", options->report_dir, "write an HTML report with figures into this folder");
  app->add_flag("--quiet,-q", options->quiet, "print nothing but errors");
  app->add_flag("--verbose,-v", options->verbose, "print solver details and library log lines");
}

CommandInputOptions ResolveCommandInput(const CLI::App& app, const FlightOptions& flights,
                                        const FlightSourceOptions& source) {
  CommandInputOptions input;
  input.training = {flights.vehicle_paths, flights.log_paths, flights.weights, flights.windows, "--log"};
  input.held_out = {
      flights.validate_vehicle_paths, flights.validate_log_paths, {}, flights.validate_windows, "--validate-log"};
  input.segment = ParseSegmentMode(flights.segment);
  input.source = source;
  input.config = ConfigJson(app);
  input.report_dir = flights.report_dir;
  input.quiet = flights.quiet;
  if (!flights.quiet) {
    input.on_read = [](const std::string& line) { std::cout << line << "\n"; };
    input.on_note = [](const std::string& note) { std::cerr << "rotorid: note: " << note << "\n"; };
  }
  if (const std::string problem = input.Validate(); !problem.empty()) throw UsageError(problem);
  return input;
}

void PrintWarnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) std::cerr << "rotorid: warning: " << w << "\n";
}

}  // namespace rotorid::cli

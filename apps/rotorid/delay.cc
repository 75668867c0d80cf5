#include "rotorid/refine/delay.h"

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/refine/delay.h"
#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"
#include "rotorid/report/progress.h"
#include "rotorid/report/refine_json.h"

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
  AddFlightOptions(command.app, &options->flights, /*held_out=*/false);
  AddIdentifyOptions(command.app, &options->identify);
  AddFirstMomentOption(command.app, &options->identify);
  command.app->add_option("--min-s", options->delay.search.min_s, "smallest delay searched (s)")->capture_default_str();
  command.app->add_option("--max-s", options->delay.search.max_s, "largest delay searched (s)")->capture_default_str();
  command.app->add_option("--step-s", options->delay.search.step_s, "grid step of the global search (s)")
      ->capture_default_str();
  command.app->add_flag("--with-motor-lag", options->delay.with_motor_lag, "estimate the motor time constant jointly");
  command.app->add_option("--threads", options->delay.num_threads)->capture_default_str();
  command.run = [options, app = command.app]() {
    IdentifyOptions identify = ResolveIdentifyOptions(&options->identify);
    // The delay shows in every parameter; a partial linear start is fine here.
    identify.allow_partial = true;
    LoadedFlights loaded = LoadTrainingFlights(options->flights, SourceOptions(options->identify));
    std::vector<Check> checks;
    IdentificationResult linear = IdentifyWithChecks(std::move(loaded.flights), identify, &checks);
    linear.system.w = Eigen::MatrixXd();  // the refinements rebuild rows with effects: 100 MB less on a 1 h log
    Progress progress("delay: search and Ceres passes", DelaySteps(options->delay), options->flights.quiet);
    progress.StartTicking();
    const DelayEstimate estimate =
        EstimateDelay(linear, options->delay, [&progress](int done, int) { progress.Update(done); });
    progress.Finish();
    for (Check& c : CheckDelay(linear, estimate, options->delay)) checks.push_back(std::move(c));
    const nlohmann::json settings = {
        {"observation", ObservationOptionsJson(identify.observation)},
        {"tls", TlsOptionsJson(identify.tls)},
        {"first_moment", FirstMomentName(identify.first_moment)},
        {"search_s", {options->delay.search.min_s, options->delay.search.max_s, options->delay.search.step_s}},
        {"with_motor_lag", options->delay.with_motor_lag}};
    nlohmann::json report = DelayJson(linear, estimate);
    report["rotorid_version"] = kRotoridVersion;
    report["command"] = "delay";
    report["settings"] = settings;
    report["linear"] = LinearJson(linear);
    report["checks"] = ChecksJson(checks);
    AddCommonReportSections(*app, loaded, nullptr, &report);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, report);
    ReportInput input = CommandReportInput("delay", identify.observation, loaded, nullptr, settings);
    input.linear = &linear;
    input.refined = &estimate.refined;
    input.warnings = estimate.warnings;
    input.checks = checks;
    input.flights = ReportFlights(linear.flights, false);
    input.parameter_sets = {
        {"linear", NamedParameters(linear.system, linear.solution.chi), Effects()},
        {"with the delay", NamedParameters(linear.system, estimate.refined.refined.chi), estimate.refined.effects}};
    const std::string report_path = WriteCommandReport(options->flights, input);
    if (!options->flights.quiet) {
      std::cout << "rotorid delay: " << 1000 * estimate.delay_s << " ms +- " << 1000 * estimate.delay_std_s
                << " ms (global search best " << 1000 * estimate.grid_best_s << " ms over ["
                << 1000 * options->delay.search.min_s << ", " << 1000 * options->delay.search.max_s << "] ms)";
      if (options->delay.with_motor_lag)
        std::cout << "; motor time constant " << 1000 * estimate.motor_tau_s << " ms +- "
                  << 1000 * estimate.motor_tau_std_s << " ms";
      std::cout << "\n";
      PrintWarnings(estimate.warnings);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

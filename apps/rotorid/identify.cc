#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/diagnosis/diagnosis_checks.h"
#include "rotorid/refine/refine.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"
#include "rotorid/report/progress.h"

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
    const IdentifyOptions identify = ResolveIdentifyOptions(&options->identify);
    LoadedFlights loaded = LoadTrainingFlights(options->flights, SourceOptions(options->identify));
    const size_t num_flights = loaded.flights.size();
    // Long logs take seconds: a progress line on a terminal (nothing drawn for short work).
    Progress progress("identify: processing, system, TLS", IdentifySteps(loaded.flights), options->flights.quiet);
    progress.StartTicking();
    std::vector<Check> checks;
    IdentificationResult result = IdentifyWithChecks(std::move(loaded.flights), identify, &checks,
                                                     [&progress](int done, int) { progress.Update(done); });
    progress.Finish();
    // Nothing after the solve reads the system's rows (the check and the report work from the
    // flights): freed before the check's own allocations (an hour at 200 Hz: 100 MB of 370).
    result.system.w = Eigen::MatrixXd();
    checks.push_back(CheckResidualSignature(result));
    const nlohmann::json settings = {{"observation", ObservationOptionsJson(identify.observation)},
                                     {"tls", TlsOptionsJson(identify.tls)},
                                     {"first_moment", FirstMomentName(identify.first_moment)}};
    nlohmann::json report = {{"rotorid_version", kRotoridVersion},
                             {"command", "identify"},
                             {"settings", settings},
                             {"linear", LinearJson(result)},
                             {"checks", ChecksJson(checks)}};
    AddCommonReportSections(*app, loaded, nullptr, &report);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, report);
    ReportInput input = CommandReportInput("identify", identify.observation, loaded, nullptr, settings);
    input.linear = &result;
    input.checks = checks;
    input.flights = ReportFlights(result.flights, false);
    input.parameter_sets = {{"linear", NamedParameters(result.system, PredictionChi(result.solution)), Effects()}};
    const std::string report_path = WriteCommandReport(options->flights, input);
    if (!options->flights.quiet) {
      std::cout << "rotorid identify: " << TlsMethodName(identify.tls.method) << " TLS, "
                << DataSourceName(identify.observation.source) << " data, " << num_flights << " flight(s), "
                << result.system.num_rows() << " equations\n";
      PrintParameterTable(std::cout, result.system.parameter_names, result.solution);
      std::cout << "relative error (paper Table III): " << FormatComponents(result.relative_error_pct) << "\n";
      PrintWarnings(result.warnings);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

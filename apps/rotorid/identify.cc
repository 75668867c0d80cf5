#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/refine/refine.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddIdentifyCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "identify", "the paper's IDIM-TLS: parameters with statistics, essential parameters, weighted and "
                  "multi-configuration TLS (repeat --vehicle/--log for configurations A and B)");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/false);
  AddIdentifyOptions(command.app, &options->identify);
  command.run = [options]() {
    const IdentifyOptions identify = ResolveIdentifyOptions(&options->identify);
    const std::vector<FlightData> flights = LoadTrainingFlights(options->flights, SourceOptions(options->identify));
    std::vector<Check> checks;
    const IdentificationResult result = IdentifyWithChecks(flights, identify, &checks);
    const nlohmann::json report = {{"rotorid_version", kRotoridVersion},
                                   {"command", "identify"},
                                   {"settings", {{"observation", ObservationOptionsJson(identify.observation)},
                                                 {"tls", TlsOptionsJson(identify.tls)}}},
                                   {"linear", LinearJson(result)},
                                   {"checks", ChecksJson(checks)}};
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, report);
    std::string report_path;
    if (!options->flights.report_dir.empty()) {
      ReportInput input;
      input.title = "rotorid identify";
      input.report = report;
      input.flights = ReportFlights(result.flights, /*held_out=*/false);
      input.parameter_sets = {{"linear", NamedParameters(result.system, result.solution.chi), Effects()}};
      ReportOptions report_options;
      report_options.print_warnings = !options->flights.quiet;
      report_path = WriteHtmlReport(options->flights.report_dir, input, report_options).html_path;
    }
    if (!options->flights.quiet) {
      std::cout << "rotorid identify: " << TlsMethodName(identify.tls.method) << " TLS, "
                << DataSourceName(identify.observation.source) << " data, " << flights.size() << " flight(s), "
                << result.system.w.rows() << " equations\n";
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

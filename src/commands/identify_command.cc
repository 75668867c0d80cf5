#include "rotorid/commands/identify_command.h"

#include <sstream>

#include "rotorid/diagnosis/diagnosis_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"
#include "rotorid/report/progress.h"

namespace rotorid {

namespace {

nlohmann::json IdentifySettingsJson(const IdentifyOptions& identify) {
  return {{"observation", ObservationOptionsJson(identify.observation)},
          {"tls", TlsOptionsJson(identify.tls)},
          {"first_moment", FirstMomentName(identify.first_moment)}};
}

}  // namespace

IdentifyCommandResult RunIdentify(const IdentifyCommandOptions& options) {
  IdentifyCommandResult result;
  result.options = options;
  result.loaded = LoadFlights(options.input.training, options.input);
  result.num_flights = result.loaded.flights.size();
  // Long logs take seconds: a progress line on a terminal (nothing drawn for short work).
  Progress progress("identify: processing, system, TLS", IdentifySteps(result.loaded.flights), options.input.quiet);
  progress.StartTicking();
  result.linear = IdentifyWithChecks(std::move(result.loaded.flights), options.identify, &result.checks,
                                     [&progress](int done, int) { progress.Update(done); });
  progress.Finish();
  // Nothing after the solve reads the system's rows (the check and the report work from the
  // flights): freed before the check's own allocations (an hour at 200 Hz: 100 MB of 370).
  result.linear.system.w = Eigen::MatrixXd();
  result.checks.push_back(CheckResidualSignature(result.linear));
  return result;
}

nlohmann::json IdentifyJson(const IdentifyCommandResult& result) {
  nlohmann::json report = CommandJsonHead("identify", IdentifySettingsJson(result.options.identify));
  report["linear"] = LinearJson(result.linear);
  report["checks"] = ChecksJson(result.checks);
  AddCommonReportSections(result.options.input, result.loaded, nullptr, &report);
  return report;
}

ReportInput IdentifyReportInput(const IdentifyCommandResult& result) {
  const IdentifyOptions& identify = result.options.identify;
  ReportInput input =
      CommandReportInput("identify", identify.observation, result.loaded, nullptr, IdentifySettingsJson(identify));
  input.linear = &result.linear;
  input.checks = result.checks;
  input.flights = ReportFlights(result.linear.flights, false);
  input.parameter_sets = {{"linear", PredictedParameters(result.linear.system, result.linear.solution), Effects()}};
  return input;
}

std::string WriteIdentifyReport(const IdentifyCommandResult& result) {
  return WriteCommandReport(result.options.input, IdentifyReportInput(result));
}

std::string IdentifyBrief(const IdentifyCommandResult& result) {
  const IdentifyOptions& identify = result.options.identify;
  std::ostringstream out;
  out << "rotorid identify: " << TlsMethodName(identify.tls.method) << " TLS, "
      << DataSourceName(identify.observation.source) << " data, " << result.num_flights << " flight(s), "
      << result.linear.system.num_rows() << " equations\n";
  out << ParameterTableText(result.linear.system.parameter_names, result.linear.solution);
  out << "relative error (paper Table III): " << ComponentsText(result.linear.relative_error_pct) << "\n";
  return out.str();
}

}  // namespace rotorid

#include "rotorid/commands/delay_command.h"

#include <sstream>

#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"
#include "rotorid/report/progress.h"
#include "rotorid/report/refine_json.h"

namespace rotorid {

namespace {

nlohmann::json DelaySettingsJson(const DelayCommandOptions& options) {
  const DelaySearch& search = options.delay.search;
  return {{"observation", ObservationOptionsJson(options.identify.observation)},
          {"tls", TlsOptionsJson(options.identify.tls)},
          {"first_moment", FirstMomentName(options.identify.first_moment)},
          {"delay_search_s", {search.min_s, search.max_s, search.step_s}},
          {"with_motor_lag", options.delay.with_motor_lag}};
}

}  // namespace

DelayCommandResult RunDelay(const DelayCommandOptions& options) {
  DelayCommandResult result;
  result.options = options;
  // The delay shows in every parameter; a partial linear start is fine here.
  result.options.identify.allow_partial = true;
  result.loaded = LoadFlights(options.input.training, options.input);
  result.linear = IdentifyWithChecks(std::move(result.loaded.flights), result.options.identify, &result.checks);
  result.linear.system.w = Eigen::MatrixXd();  // the refinements rebuild rows with effects: 100 MB less on a 1 h log
  Progress progress("delay: search and Ceres passes", DelaySteps(options.delay), options.input.quiet);
  progress.StartTicking();
  result.estimate = EstimateDelay(result.linear, options.delay, [&progress](int done, int) { progress.Update(done); });
  progress.Finish();
  for (Check& c : CheckDelay(result.linear, result.estimate, options.delay)) result.checks.push_back(std::move(c));
  return result;
}

nlohmann::json DelayJson(const DelayCommandResult& result) {
  nlohmann::json report = DelayJson(result.linear, result.estimate);
  report.update(CommandJsonHead("delay", DelaySettingsJson(result.options)));
  report["linear"] = LinearJson(result.linear);
  report["checks"] = ChecksJson(result.checks);
  AddCommonReportSections(result.options.input, result.loaded, nullptr, &report);
  return report;
}

ReportInput DelayReportInput(const DelayCommandResult& result) {
  ReportInput input = CommandReportInput("delay", result.options.identify.observation, result.loaded, nullptr,
                                         DelaySettingsJson(result.options));
  const RefineResult& refined = result.estimate.refined;
  input.linear = &result.linear;
  input.refined = &refined;
  input.warnings = result.estimate.warnings;
  input.checks = result.checks;
  input.flights = ReportFlights(result.linear.flights, false);
  input.parameter_sets = {
      {"linear", PredictedParameters(result.linear.system, result.linear.solution), Effects()},
      {"with the delay", PredictedParameters(result.linear.system, refined.refined), refined.effects}};
  return input;
}

std::string WriteDelayReport(const DelayCommandResult& result) {
  return WriteCommandReport(result.options.input, DelayReportInput(result));
}

std::string DelayBrief(const DelayCommandResult& result) {
  const DelayEstimate& e = result.estimate;
  const DelayOptions& delay = result.options.delay;
  std::ostringstream out;
  out << "rotorid delay: " << 1000 * e.delay_s << " ms +- " << 1000 * e.delay_std_s << " ms (global search best "
      << 1000 * e.grid_best_s << " ms over [" << 1000 * delay.search.min_s << ", " << 1000 * delay.search.max_s
      << "] ms)";
  if (delay.with_motor_lag)
    out << "; motor time constant " << 1000 * e.motor_tau_s << " ms +- " << 1000 * e.motor_tau_std_s << " ms";
  out << "\n";
  return out.str();
}

}  // namespace rotorid

#include "rotorid/commands/validate_command.h"

#include <sstream>

#include "rotorid/ident/body_consistency.h"
#include "rotorid/refine/refine.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/json.h"

namespace rotorid {

namespace {

// The saved parameters as validate predicts with them (the flights' own first moments fitted), with
// the report's essential flags and the flights' masses: what physical_consistency checks.
CheckedParameters ValidatedModel(const ValidateCommandResult& result) {
  CheckedParameters model;
  model.value = result.model.values;
  model.mass_kg = ConfigurationMasses(result.flights);
  for (const auto& [name, entry] : result.params[result.model.block]["parameters"].items()) {
    if (!entry.is_object()) continue;
    if (entry.contains("essential") && entry["essential"].is_boolean())
      model.essential[name] = entry["essential"].get<bool>();
    if (entry.contains("predicts_with") && model.value.count(name)) model.predicts_with[name] = model.value.at(name);
  }
  return model;
}

nlohmann::json ValidateSettingsJson(const ValidateCommandResult& result) {
  return {{"observation", ObservationOptionsJson(result.observation)}};
}

}  // namespace

ValidateCommandResult RunValidate(const ValidateCommandOptions& options) {
  ValidateCommandResult result;
  result.options = options;
  result.loaded = LoadFlights(options.input.training, options.input);
  result.params = ReadJsonFile(options.params_path);
  result.model = PredictedParameters(result.params, options.params_path, options.block);
  // Rows are built exactly as in the run that produced the parameters.
  const nlohmann::json& settings = result.params.value("settings", nlohmann::json::object());
  result.observation = ObservationOptionsFromJson(settings.value("observation", nlohmann::json()));
  result.flights = ProcessFlights(result.loaded.flights, result.observation);
  result.checks = CheckFlights(result.loaded.flights, result.flights);
  // A report with per-flight first moments knows none of these flights' own: each is fitted.
  result.first_moments = FitHeldOutFirstMomentsWithEffects(&result.flights, &result.model.values, result.model.effects);
  result.relative_error_pct = RelativeErrorWithEffects(result.flights, result.model.values, result.model.effects);
  for (const ProcessedFlight& f : result.flights) {
    result.fits.push_back(FitFlight(f, result.model.values));
    result.fits.back().relative_error_pct = RelativeErrorWithEffects({f}, result.model.values, result.model.effects);
  }
  for (Check& c : CheckRelativeError(result.relative_error_pct, "validation", /*held_out=*/true))
    result.checks.push_back(std::move(c));
  for (Check& c : PhysicalConsistencyChecks(ValidatedModel(result), "validation"))
    result.checks.push_back(std::move(c));
  return result;
}

nlohmann::json ValidateJson(const ValidateCommandResult& result) {
  nlohmann::json report = CommandJsonHead("validate", ValidateSettingsJson(result));
  report["params"] = result.options.params_path;
  report["block"] = result.model.block;
  report["relative_error_pct"] = ComponentsJson(result.relative_error_pct);
  report["flights"] = nlohmann::json::array();
  for (const FlightFit& fit : result.fits) report["flights"].push_back(FlightFitJson(fit));
  if (!result.first_moments.empty()) report["first_moments"] = FirstMomentsJson(result.first_moments);
  AddCommonReportSections(result.options.input, result.loaded, nullptr, &report);
  report["checks"] = ChecksJson(result.checks);
  return report;
}

ReportInput ValidateReportInput(const ValidateCommandResult& result) {
  const std::string& path = result.options.params_path;
  ReportInput input =
      CommandReportInput("validate", result.observation, result.loaded, nullptr, ValidateSettingsJson(result));
  input.settings.emplace_back("params", path);
  input.relative_errors = {{"given flights", result.model.block + " parameters of " + path, result.relative_error_pct}};
  input.checks = result.checks;
  input.flights = ReportFlights(result.flights, /*held_out=*/true);
  // The saved parameters (and the refined effects) are drawn beside each other, each with the values
  // it predicts with and the flights' own first moments.
  input.parameter_sets = ParameterSetsFromReport(result.params, path);
  std::vector<ProcessedFlight> flights = result.flights;
  for (ParameterSet& set : input.parameter_sets) FitHeldOutFirstMomentsWithEffects(&flights, &set.values, set.effects);
  return input;
}

std::string WriteValidateReport(const ValidateCommandResult& result) {
  if (result.options.input.report_dir.empty()) return {};
  return WriteCommandReport(result.options.input, ValidateReportInput(result));
}

std::string ValidateBrief(const ValidateCommandResult& result) {
  std::ostringstream out;
  out << "rotorid validate: parameters of " << result.options.params_path << " on " << result.flights.size()
      << " flight(s)\n";
  for (const FlightFit& fit : result.fits)
    out << "  " << fit.source << " (" << fit.config << "): " << ComponentsText(fit.relative_error_pct) << "\n";
  out << "relative error (paper Table III): " << ComponentsText(result.relative_error_pct) << "\n";
  if (!result.first_moments.empty())
    out << "first moments fitted on these flights (the report's are per flight): "
        << FirstMomentsJson(result.first_moments).dump() << "\n";
  return out.str();
}

}  // namespace rotorid

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/ident/body_consistency.h"
#include "rotorid/refine/refine.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"
#include "rotorid/report/refine_json.h"

namespace rotorid::cli {

namespace {

// The saved parameters as validate predicts with them (the flights' own first moments fitted), with
// the report's essential flags and the flights' masses: what physical_consistency checks.
CheckedParameters ValidatedModel(const nlohmann::json& params, const std::string& block,
                                 const std::map<std::string, double>& values,
                                 const std::vector<ProcessedFlight>& flights) {
  CheckedParameters model;
  model.value = values;
  model.mass_kg = ConfigurationMasses(flights);
  for (const auto& [name, entry] : params[block]["parameters"].items()) {
    if (!entry.is_object()) continue;
    if (entry.contains("essential") && entry["essential"].is_boolean())
      model.essential[name] = entry["essential"].get<bool>();
    if (entry.contains("predicts_with") && values.count(name)) model.predicts_with[name] = values.at(name);
  }
  return model;
}

}  // namespace

Command AddValidateCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    std::string params_path;
    std::string block;
    std::string rotor_signal = "auto";
    std::string column_map;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "validate",
      "applies saved parameters (--params, an identify or refine report) to other flights: the paper's "
      "cross-validation, Table III");
  command.app->add_option("--params", options->params_path, "identify/refine JSON report")
      ->required()
      ->check(CLI::ExistingFile);
  command.app->add_option("--block", options->block, "linear or refined (default: refined when present)");
  command.app->add_option("--rotor-signal", options->rotor_signal, "auto, rpm or command");
  command.app->add_option("--column-map", options->column_map, "column map (YAML) for CSV exports of other tools");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/false);
  command.run = [options, app = command.app]() {
    FlightSourceOptions source;
    source.rotor_signal = options->rotor_signal;
    source.column_map_path = options->column_map;
    if (const std::string problem = source.Validate(); !problem.empty()) throw UsageError(problem);
    const LoadedFlights loaded = LoadTrainingFlights(options->flights, source);
    const nlohmann::json params = ReadJsonFile(options->params_path);
    std::map<std::string, double> values =
        ParameterValuesFromReport(params, options->params_path, options->block, /*predicted=*/true);
    // Rows are built exactly as in the run that produced the parameters.
    const ObservationOptions observation = ObservationOptionsFromJson(
        params.contains("settings") && params["settings"].contains("observation") ? params["settings"]["observation"]
                                                                                  : nlohmann::json());
    std::vector<ProcessedFlight> flights = ProcessFlights(loaded.flights, observation);
    std::vector<Check> checks = CheckFlights(loaded.flights, flights);
    // Refined parameters are only valid together with their effects.
    const bool refined = options->block == "refined" || (options->block.empty() && params.contains("refined") &&
                                                         params["refined"].contains("parameters"));
    const Effects effects = refined ? EffectsFromReport(params) : Effects{};
    // A report with per-flight first moments knows none of these flights' own: each is fitted.
    const nlohmann::json first_moments = FitHeldOutFirstMomentsJson(&flights, &values, effects);
    const auto combined = RelativeErrorWithEffects(flights, values, effects);
    nlohmann::json per_flight = nlohmann::json::array();
    std::vector<FlightFit> fits;
    for (const ProcessedFlight& f : flights) {
      fits.push_back(FitFlight(f, values));
      fits.back().relative_error_pct = RelativeErrorWithEffects({f}, values, effects);
      per_flight.push_back(FlightFitJson(fits.back()));
    }
    const nlohmann::json settings = {{"observation", ObservationOptionsJson(observation)}};
    const std::string block = refined ? "refined" : "linear";
    nlohmann::json report = {{"rotorid_version", kRotoridVersion},
                             {"command", "validate"},
                             {"params", options->params_path},
                             {"block", block},
                             {"settings", settings},
                             {"relative_error_pct", ComponentsJson(combined)},
                             {"flights", per_flight}};
    if (!first_moments.empty()) report["first_moments"] = first_moments;
    AddCommonReportSections(*app, loaded, nullptr, &report);
    for (Check& c : CheckRelativeError(combined, "validation", /*held_out=*/true)) checks.push_back(std::move(c));
    for (Check& c : PhysicalConsistencyChecks(ValidatedModel(params, block, values, flights), "validation"))
      checks.push_back(std::move(c));
    report["checks"] = ChecksJson(checks);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, report);
    ReportInput input = CommandReportInput("validate", observation, loaded, nullptr, settings);
    input.settings.emplace_back("params", options->params_path);
    input.relative_errors = {{"given flights", block + " parameters of " + options->params_path, combined}};
    input.checks = checks;
    input.flights = ReportFlights(flights, /*held_out=*/true);
    // The saved parameters (and the refined effects) are drawn beside each other.
    input.parameter_sets = ParameterSetsFromReport(params, options->params_path);
    for (ParameterSet& set : input.parameter_sets) FitHeldOutFirstMomentsJson(&flights, &set.values, set.effects);
    const std::string report_path = WriteCommandReport(options->flights, input);
    if (!options->flights.quiet) {
      std::cout << "rotorid validate: parameters of " << options->params_path << " on " << flights.size()
                << " flight(s)\n";
      for (const FlightFit& fit : fits)
        std::cout << "  " << fit.source << " (" << fit.config << "): " << FormatComponents(fit.relative_error_pct)
                  << "\n";
      std::cout << "relative error (paper Table III): " << FormatComponents(combined) << "\n";
      if (!first_moments.empty())
        std::cout << "first moments fitted on these flights (the report's are per flight): " << first_moments.dump()
                  << "\n";
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

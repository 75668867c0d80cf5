#include "rotorid/commands/command_input.h"

#include <iomanip>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/refine/effect_model.h"
#include "rotorid/refine/refine.h"
#include "rotorid/report/input_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"

namespace rotorid {

namespace {

std::string CountMismatch(size_t got, const std::string& what, size_t logs, const std::string& log_option) {
  return "got " + std::to_string(got) + " " + what + " for " + std::to_string(logs) + " " + log_option +
         "; give one per log, in the same order";
}

std::string FilesProblem(const FlightFiles& files) {
  const size_t logs = files.log_paths.size();
  if (files.vehicle_paths.size() != logs)
    return CountMismatch(files.vehicle_paths.size(), "vehicle files", logs, files.log_option);
  if (!files.weights.empty() && files.weights.size() != logs)
    return CountMismatch(files.weights.size(), "--weight values", logs, files.log_option);
  if (!files.windows.empty() && files.windows.size() != logs)
    return CountMismatch(files.windows.size(), "windows", logs, files.log_option);
  for (double weight : files.weights)
    if (!(weight > 0.0)) return "--weight must be positive, got " + std::to_string(weight);
  return {};
}

}  // namespace

std::string CommandInputOptions::Validate() const {
  if (std::string problem = source.Validate(); !problem.empty()) return problem;
  if (std::string problem = FilesProblem(training); !problem.empty()) return problem;
  return FilesProblem(held_out);
}

LoadedFlights LoadFlights(const FlightFiles& files, const CommandInputOptions& options) {
  if (const std::string problem = FilesProblem(files); !problem.empty()) throw Error(problem);
  LoadedFlights loaded;
  for (size_t i = 0; i < files.log_paths.size(); ++i) {
    const Vehicle vehicle = ReadVehicleYaml(files.vehicle_paths[i]);
    const std::optional<TimeWindow> window =
        files.windows.empty() ? std::nullopt : std::optional<TimeWindow>(ParseTimeWindow(files.windows[i]));
    FlightLog log = LoadFlightLog(files.log_paths[i], vehicle, options.source);
    // Before the segmentation, which would leave a deg/s gyro's log out as "gyro limit".
    if (const Check rate = CheckGyroRate(log); rate.status == CheckStatus::kError) throw Error(rate.message);
    SelectedFlight selected = SelectFlight(std::move(log), files.log_paths[i], window, options.segment);
    if (options.on_read) options.on_read(selected.summary.ConsoleLine());
    const double weight = files.weights.empty() ? 1.0 : files.weights[i];
    for (FlightLog& segment : selected.segments)
      loaded.flights.push_back({vehicle, std::move(segment), weight, static_cast<int>(i)});
    loaded.inputs.push_back(std::move(selected.summary));
  }
  return loaded;
}

std::map<std::string, double> FitHeldOutFirstMomentsWithEffects(std::vector<ProcessedFlight>* flights,
                                                                std::map<std::string, double>* parameters,
                                                                const Effects& effects) {
  const std::vector<std::string> names =
      FitHeldOutFirstMoments(flights, parameters, [&effects](const ProcessedFlight& f) {
        // Without effects, the rows the linear identification used.
        return effects.AllZero() ? BuildIdimMatrix(f) : BuildIdimMatrixWithEffects(f, effects);
      });
  std::map<std::string, double> fitted;
  for (const std::string& name : names) fitted[name] = parameters->at(name);
  return fitted;
}

nlohmann::json FirstMomentsJson(const std::map<std::string, double>& first_moments) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, value] : first_moments) out[name] = value;
  return out;
}

std::vector<EffectKind> EffectsForFlights(const std::string& list, const IdentificationResult& linear,
                                          const CommandInputOptions& options) {
  const std::vector<EffectKind> named = ParseEffectList(list);
  if (list != "all" && list != "every") return named;
  std::vector<EffectKind> kept;
  for (EffectKind kind : named) {
    std::string why;
    for (const ProcessedFlight& flight : linear.flights)
      if (why.empty()) why = kind->Unavailable(flight.inputs());
    if (why.empty()) {
      kept.push_back(kind);
    } else if (!options.quiet && options.on_note) {
      options.on_note(why + "; left out of \"" + list + "\"");
    }
  }
  return kept;
}

nlohmann::json CommandJsonHead(const std::string& command, const nlohmann::json& settings) {
  return {{"rotorid_version", kRotoridVersion}, {"command", command}, {"settings", settings}};
}

void AddCommonReportSections(const CommandInputOptions& options, const LoadedFlights& training,
                             const LoadedFlights* held_out, nlohmann::json* report) {
  (*report)["input"] = InputJson(training.inputs, held_out ? held_out->inputs : std::vector<FlightInputSummary>{});
  if (!options.config.is_null()) (*report)["config"] = options.config;
}

ReportInput CommandReportInput(const std::string& command, const ObservationOptions& observation,
                               const LoadedFlights& training, const LoadedFlights* held_out,
                               const nlohmann::json& settings) {
  ReportInput input;
  input.title = "rotorid " + command;
  input.command = command;
  input.rotorid_version = kRotoridVersion;
  input.observation = observation;
  input.inputs = training.inputs;
  if (held_out) input.validate_inputs = held_out->inputs;
  input.settings = SettingsRows(settings);
  return input;
}

std::string WriteCommandReport(const CommandInputOptions& options, const ReportInput& input) {
  if (options.report_dir.empty()) return {};
  ReportOptions report_options;
  report_options.print_warnings = !options.quiet;
  return WriteHtmlReport(options.report_dir, input, report_options).html_path;
}

std::string ComponentsText(const std::vector<std::optional<double>>& values) {
  std::ostringstream out;
  for (size_t j = 0; j < values.size(); ++j) {
    if (!values[j]) continue;
    out << (out.tellp() > 0 ? "  " : "") << kWrenchComponentNames[j] << " " << std::fixed << std::setprecision(2)
        << *values[j] << " %";
  }
  return out.str();
}

std::string ParameterTableText(const std::vector<std::string>& names, const TlsSolution& solution) {
  std::ostringstream out;
  size_t width = 10;
  for (const std::string& n : names) width = std::max(width, n.size() + 2);
  out << std::left << std::setw(static_cast<int>(width)) << "parameter" << std::right << std::setw(14) << "value"
      << std::setw(12) << "std" << std::setw(10) << "%sigma"
      << "  essential\n";
  const Eigen::VectorXd predicted = PredictionChi(solution);
  for (size_t k = 0; k < names.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    out << std::left << std::setw(static_cast<int>(width)) << names[k] << std::right << std::scientific
        << std::setprecision(4) << std::setw(14) << solution.chi[i] << std::setprecision(2) << std::setw(12)
        << ParameterStatisticsOf(names, solution, k).std << std::fixed << std::setprecision(2) << std::setw(10)
        << solution.rel_std_pct[i] << "  " << (solution.essential[k] ? "yes" : "no (discarded)");
    // A discarded inertia the model still estimates and predicts with (PredictionChi), and the range a
    // physical body allows it.
    if (PredictsWithOtherValue(solution, static_cast<int>(k))) out << ", predicted with " << ShortNumber(predicted[i]);
    if (solution.HasAllowedRange(static_cast<int>(k)))
      out << ", a body allows " << ShortNumber(solution.allowed_low[i]) << " .. "
          << ShortNumber(solution.allowed_high[i]);
    out << "\n";
  }
  return out.str();
}

std::string EffectListText(const std::vector<EffectKind>& effects) {
  std::string names;
  for (EffectKind kind : effects) names += (names.empty() ? "" : ",") + kind->name();
  return names;
}

}  // namespace rotorid

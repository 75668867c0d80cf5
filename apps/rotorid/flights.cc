#include <algorithm>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/model/parameters.h"
#include "rotorid/refine/effect_model.h"
#include "rotorid/report/input_json.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

namespace {

bool options_validated = false;

}  // namespace

CLI::Validator Within(double low, double high) {
  return CLI::Validator(
      [low, high](const std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        if (!(value >= low && value <= high))  // NaN fails too
          return "must lie in [" + ShortNumber(low) + ", " + ShortNumber(high) + "], got " + text;
        return {};
      },
      "in [" + ShortNumber(low) + ", " + ShortNumber(high) + "]");
}

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

void AddIdentifyOptions(CLI::App* app, IdentifyCliOptions* o) {
  ObservationOptions& obs = o->identify.observation;
  TlsOptions& tls = o->identify.tls;
  app->add_option("--method", o->method,
                  "noise-aware (default: errors-in-variables TLS with calibrated statistics) "
                  "or paper (the published procedure, for comparison)")
      ->capture_default_str();
  app->add_option("--source", o->source, "imu or mocap")->capture_default_str();
  // Ranges checked while parsing: a value far outside (--edge-trim-s 1e7) crashed the processing.
  app->add_option("--cutoff-hz", obs.filter.cutoff_hz, "low-pass cut-off of every signal (Hz)")
      ->check(Within(0.01, 5000.0))
      ->capture_default_str();
  app->add_option("--filter-order", obs.filter.order, "Butterworth order")->check(Within(1, 12))->capture_default_str();
  app->add_option("--row-rate-hz", obs.row_rate_hz, "rate of the IDIM rows (Hz; 0: five times the cut-off)")
      ->check(Within(0.0, 1e5))
      ->capture_default_str();
  app->add_option("--edge-trim-s", obs.edge_trim_s, "seconds left out at each end of a flight")
      ->check(Within(0.0, 600.0))
      ->capture_default_str();
  app->add_option("--r-sigma", tls.r_sigma, "paper method: essential parameters until max/min %sigma < r_sigma")
      ->check(Within(1e-6, 1e12))
      ->capture_default_str();
  app->add_option("--max-rel-std", tls.max_rel_std_pct, "noise-aware method: drop parameters whose %sigma exceeds this")
      ->check(Within(1e-6, 1e12))
      ->capture_default_str();
  app->add_flag("!--all-parameters", tls.select_essential, "keep every parameter (no essential selection)");
  app->add_flag("!--no-component-weighting", tls.weight_by_component, "paper method: no weighting by wrench component");
  app->add_option("--fix-zero", o->fixed_zero, "hold this parameter at 0 (repeatable), e.g. A.I_xy");
  app->add_flag("--allow-partial", o->identify.allow_partial,
                "accept a result in which roll or pitch inertia is not identifiable");
  app->add_option("--rotor-signal", o->rotor_signal, "auto, rpm or command (logs that have both)")
      ->capture_default_str();
  app->add_option("--column-map", o->column_map, "column map (YAML) for CSV exports of other tools");
}

void AddFirstMomentOption(CLI::App* app, IdentifyCliOptions* o) {
  app->add_option("--first-moment", o->first_moment,
                  "shared (default: the flights of a configuration share its first moment) or per-flight (each log "
                  "has its own, <config>.flight<k>.ms_x with k from 1 in the order given: the battery moves between "
                  "flights; held-out flights get theirs fitted)")
      ->check(ParsesWith(ParseFirstMoment))
      ->capture_default_str();
}

IdentifyOptions ResolveIdentifyOptions(IdentifyCliOptions* o) {
  o->identify.tls.method = ParseTlsMethod(o->method);
  o->identify.first_moment = ParseFirstMoment(o->first_moment);
  if (o->source != "imu" && o->source != "mocap")
    throw UsageError("--source must be imu or mocap, got '" + o->source + "'");
  o->identify.observation.source = o->source == "imu" ? DataSource::kImu : DataSource::kMocap;
  o->identify.tls.fixed_zero = o->fixed_zero;
  if (const std::string problem = o->identify.Validate(); !problem.empty()) throw UsageError(problem);
  return o->identify;
}

FlightSourceOptions SourceOptions(const IdentifyCliOptions& o) {
  FlightSourceOptions source;
  source.rotor_signal = o.rotor_signal;
  source.column_map_path = o.column_map;
  if (const std::string problem = source.Validate(); !problem.empty()) throw UsageError(problem);
  return source;
}

namespace {

std::string CountMismatch(size_t got, const std::string& what, size_t logs, const std::string& log_option) {
  return "got " + std::to_string(got) + " " + what + " for " + std::to_string(logs) + " " + log_option +
         "; give one per log, in the same order";
}

LoadedFlights LoadFlights(const std::vector<std::string>& vehicle_paths, const std::vector<std::string>& log_paths,
                          const std::vector<double>& weights, const std::vector<std::string>& windows,
                          const std::string& log_option, const FlightOptions& options,
                          const FlightSourceOptions& source) {
  if (vehicle_paths.size() != log_paths.size())
    throw UsageError(CountMismatch(vehicle_paths.size(), "vehicle files", log_paths.size(), log_option));
  if (!weights.empty() && weights.size() != log_paths.size())
    throw UsageError(CountMismatch(weights.size(), "--weight values", log_paths.size(), log_option));
  if (!windows.empty() && windows.size() != log_paths.size())
    throw UsageError(CountMismatch(windows.size(), "windows", log_paths.size(), log_option));
  for (double weight : weights)
    if (!(weight > 0.0)) throw UsageError("--weight must be positive, got " + std::to_string(weight));
  MarkOptionsValidated();
  const SegmentMode mode = ParseSegmentMode(options.segment);
  LoadedFlights loaded;
  for (size_t i = 0; i < log_paths.size(); ++i) {
    const Vehicle vehicle = ReadVehicleYaml(vehicle_paths[i]);
    const std::optional<TimeWindow> window =
        windows.empty() ? std::nullopt : std::optional<TimeWindow>(ParseTimeWindow(windows[i]));
    FlightLog log = LoadFlightLog(log_paths[i], vehicle, source);
    // Before the segmentation, which would leave a deg/s gyro's log out as "gyro limit".
    if (const Check rate = CheckGyroRate(log); rate.status == CheckStatus::kError) throw Error(rate.message);
    SelectedFlight selected = SelectFlight(std::move(log), log_paths[i], window, mode);
    if (!options.quiet) std::cout << selected.summary.ConsoleLine() << "\n";
    for (FlightLog& segment : selected.segments)
      loaded.flights.push_back({vehicle, std::move(segment), weights.empty() ? 1.0 : weights[i], static_cast<int>(i)});
    loaded.inputs.push_back(std::move(selected.summary));
  }
  return loaded;
}

}  // namespace

LoadedFlights LoadTrainingFlights(const FlightOptions& options, const FlightSourceOptions& source) {
  return LoadFlights(options.vehicle_paths, options.log_paths, options.weights, options.windows, "--log", options,
                     source);
}

nlohmann::json FitHeldOutFirstMomentsJson(std::vector<ProcessedFlight>* flights,
                                          std::map<std::string, double>* parameters, const Effects& effects) {
  const std::vector<std::string> names =
      FitHeldOutFirstMoments(flights, parameters, [&effects](const ProcessedFlight& f) {
        // Without effects, the rows the linear identification used.
        return effects.AllZero() ? BuildIdimMatrix(f) : BuildIdimMatrixWithEffects(f, effects);
      });
  nlohmann::json out = nlohmann::json::object();
  for (const std::string& name : names) out[name] = parameters->at(name);
  return out;
}

std::vector<EffectKind> EffectsForFlights(const std::string& list, const IdentificationResult& linear, bool quiet) {
  const std::vector<EffectKind> named = ParseEffectList(list);
  if (list != "all" && list != "every") return named;
  std::vector<EffectKind> kept;
  for (EffectKind kind : named) {
    std::string why;
    for (const ProcessedFlight& flight : linear.flights)
      if (why.empty()) why = kind->Unavailable(flight.inputs());
    if (why.empty()) {
      kept.push_back(kind);
    } else if (!quiet) {
      std::cerr << "rotorid: note: " << why << "; left out of \"" << list << "\"\n";
    }
  }
  return kept;
}

LoadedFlights LoadValidationFlights(const FlightOptions& options, const FlightSourceOptions& source) {
  return LoadFlights(options.validate_vehicle_paths, options.validate_log_paths, {}, options.validate_windows,
                     "--validate-log", options, source);
}

void AddCommonReportSections(const CLI::App& app, const LoadedFlights& training, const LoadedFlights* held_out,
                             nlohmann::json* report) {
  (*report)["input"] = InputJson(training.inputs, held_out ? held_out->inputs : std::vector<FlightInputSummary>{});
  if (const nlohmann::json config = ConfigJson(app); !config.is_null()) (*report)["config"] = config;
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

std::string WriteCommandReport(const FlightOptions& options, const ReportInput& input) {
  if (options.report_dir.empty()) return {};
  ReportOptions report_options;
  report_options.print_warnings = !options.quiet;
  return WriteHtmlReport(options.report_dir, input, report_options).html_path;
}

std::string FormatComponents(const std::vector<std::optional<double>>& values) {
  std::ostringstream out;
  for (size_t j = 0; j < values.size(); ++j) {
    if (!values[j]) continue;
    out << (out.tellp() > 0 ? "  " : "") << kWrenchComponentNames[j] << " " << std::fixed << std::setprecision(2)
        << *values[j] << " %";
  }
  return out.str();
}

void PrintParameterTable(std::ostream& out, const std::vector<std::string>& names, const TlsSolution& solution) {
  size_t width = 10;
  for (const std::string& n : names) width = std::max(width, n.size() + 2);
  out << std::left << std::setw(static_cast<int>(width)) << "parameter" << std::right << std::setw(14) << "value"
      << std::setw(12) << "std" << std::setw(10) << "%sigma"
      << "  essential\n";
  for (size_t k = 0; k < names.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    out << std::left << std::setw(static_cast<int>(width)) << names[k] << std::right << std::scientific
        << std::setprecision(4) << std::setw(14) << solution.chi[i] << std::setprecision(2) << std::setw(12)
        << ParameterStatisticsOf(names, solution, k).std << std::fixed << std::setprecision(2) << std::setw(10)
        << solution.rel_std_pct[i] << "  " << (solution.essential[k] ? "yes" : "no (discarded)");
    // A discarded inertia the model still estimates and predicts with (PredictionChi), and the range a
    // physical body allows it.
    if (PredictsWithProfiled(solution, static_cast<int>(k)) || solution.PredictsWithinRange(static_cast<int>(k)))
      out << ", predicted with " << ShortNumber(PredictionChi(solution)[i]);
    if (solution.HasAllowedRange(static_cast<int>(k)))
      out << ", a body allows " << ShortNumber(solution.allowed_low[i]) << " .. " << ShortNumber(solution.allowed_high[i]);
    out << "\n";
  }
  out.unsetf(std::ios::floatfield);
}

void PrintWarnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) std::cerr << "rotorid: warning: " << w << "\n";
}

}  // namespace rotorid::cli

#include <iostream>

#include "commands.h"
#include "rotorid/core/text.h"

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
  return source;  // checked with the flights (ResolveCommandInput)
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

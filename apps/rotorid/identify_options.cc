// The identification options every analysing command shares (--method, --cutoff-hz, ..., --first-moment),
// and their resolution into the library's IdentifyOptions.

#include "commands.h"

namespace rotorid::cli {

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

}  // namespace rotorid::cli

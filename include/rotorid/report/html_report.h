#pragma once

// The report people look at: one self-contained HTML file (inline CSS, figures inlined as SVG)
// with the parameter tables, the paper's Table III per flight, the run settings and warnings,
// and figures drawn by gnuplot:
//   (a) per flight, per wrench component: rigid-body wrench and rotor-model wrench over time with
//       the error on a second axis (the paper's Fig. 3/4), one column per parameter set;
//   (b) residual amplitude spectra per component, one curve per parameter set;
//   (c) parameter estimates +- 3 std, normalised by the linear value;
//   (d) the diagnosis (verdict; which effect, how far the held-out gap shrinks, where the gap is:
//       tables with units, the gap, per-band and signature charts) and the ablation table, when
//       the command has them; the plausibility checks and what was read when given.
//
//   ReportInput input;
//   input.title = "rotorid identify";
//   input.command = "identify";
//   input.linear = &result;                            // tables come from the typed results
//   input.flights = {{"flight 1", &result.flights[0], /*held_out=*/false}};
//   input.parameter_sets = {{"linear", values, Effects{}}};
//   WriteHtmlReport("out/report", input);
//
// Figures need gnuplot (Debian: gnuplot-nox). Without it the report still holds every table and
// says why the figures are missing. The report shows the same typed results the JSON writers
// (LinearJson, RefinedJson, DiagnosisJson, AblationJson, ChecksJson, InputJson) write, never the
// JSON read back: a result the command did not give is left out.

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/ident/checks.h"
#include "rotorid/ident/identify.h"
#include "rotorid/ident/observation.h"
#include "rotorid/io/flight_selection.h"
#include "rotorid/model/effects.h"
#include "rotorid/refine/ablate.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

// A flight to draw. The flight is not owned and must outlive WriteHtmlReport.
struct ReportFlight {
  std::string label;
  const ProcessedFlight* flight = nullptr;
  // Held-out (validation) flight, not used to fit the parameters.
  bool held_out = false;
};

// Parameters ("kt", "kd", "<config>.<name>") and the unmodelled effects they go with (for a refine
// report: NamedParameters of the refined chi and RefineResult::effects).
struct ParameterSet {
  std::string label;  // "linear", "refined", ...
  std::map<std::string, double> values;
  Effects effects;
};

// Table III of one parameter set over the flights a command computed it on, e.g. the held-out
// flights of refine or the flights validate applied saved parameters to.
struct RelativeErrorRow {
  std::string data;        // "held-out flights", "given flights"
  std::string parameters;  // "linear", "refined parameters of out/refine.json"
  std::vector<std::optional<double>> relative_error_pct;
};

struct ReportInput {
  std::string title = "rotorid report";
  // Shown under the title and in the settings when not empty.
  std::string command;
  std::string rotorid_version;
  std::vector<ReportFlight> flights;
  std::vector<ParameterSet> parameter_sets;

  // The results shown, each when given; not owned, they must outlive WriteHtmlReport.
  // The linear TLS result: the statistics of the parameter set labelled "linear" (a column of its
  // own when no set has that label), Table III over the identification flights, its warnings.
  const IdentificationResult* linear = nullptr;
  // The refinement of `linear` (which must then be given): the "refined" statistics as above, the
  // effects table, Table III, its warnings.
  const RefineResult* refined = nullptr;
  // Table III rows the command computed beyond those of `linear` and `refined`.
  std::vector<RelativeErrorRow> relative_errors;
  const Diagnosis* diagnosis = nullptr;
  const AblationResult* ablation = nullptr;
  std::optional<std::vector<Check>> checks;
  // What was read per log (input.flights[] and input.validate_flights[] of the JSON).
  std::vector<FlightInputSummary> inputs;
  std::vector<FlightInputSummary> validate_inputs;
  // The analysis's warnings that no result above carries (delay's).
  std::vector<std::string> warnings;
  // The signal processing used: the spectra mark its low-pass cut-off.
  std::optional<ObservationOptions> observation;
  // The run settings table, display only: SettingsRows of the settings the JSON records.
  std::vector<std::pair<std::string, std::string>> settings;
};

struct ReportOptions {
  // gnuplot executable: a name looked up on PATH, or a path. Empty: figures are not drawn.
  std::string gnuplot = "gnuplot";
  // Longest a single gnuplot run may take (s) before it is killed.
  double gnuplot_timeout_s = 60.0;
  // Most points drawn per time series (min/max per bucket keeps the envelope).
  int max_points_per_series = 1200;
  // Length (s) of the zoomed window beside each full-length wrench plot (0: no zoom).
  double zoom_window_s = 5.0;
  // Longest Welch segment (samples, a power of two) of the residual spectra.
  int max_spectrum_segment = 512;
  // Print the report's own warnings (gnuplot missing or failing) on stderr.
  bool print_warnings = true;
  // Also keep each figure's gnuplot script and data in DIR/gnuplot/ (run "gnuplot fig_x.gp" there
  // to redraw or restyle a figure, e.g. for a paper).
  bool keep_gnuplot_files = false;

  // Empty when valid, else a message naming the violated constraint.
  std::string Validate() const;
};

struct ReportSummary {
  std::string html_path;
  std::vector<std::string> figure_paths;  // fig_*.svg written
  bool figures_drawn = false;             // gnuplot was found and every figure rendered
  std::vector<std::string> warnings;      // the report's own problems (not the analysis's)
};

// Writes DIR/report.html and DIR/fig_*.svg (each atomically), creating DIR when missing. Figures
// an earlier report wrote into DIR (listed in DIR/.rotorid_report_figures) that this one does not
// produce are removed; no other file is ever deleted. Throws rotorid::Error on invalid input (null
// flight, invalid options, a refined result without its linear one) or when DIR cannot be
// written; gnuplot failures are warnings, not errors.
ReportSummary WriteHtmlReport(const std::string& dir, const ReportInput& input, const ReportOptions& options = {});

// Report flights for processed flights, labelled by their log's file name.
std::vector<ReportFlight> ReportFlights(const std::vector<ProcessedFlight>& flights, bool held_out);
// The identification flights, then the held-out ones (marked held out).
std::vector<ReportFlight> ReportFlights(const std::vector<ProcessedFlight>& flights,
                                        const std::vector<ProcessedFlight>& held_out);

// The parameter sets a saved identify/refine report (read from `source`) holds: "linear" (no
// effects) and "refined" (with its "refined.effects"), each when present, with the values each
// predicts with (PredictedParameters). Throws rotorid::Error naming `source` when a present block
// lacks "parameters" or a parameter its numeric "value".
std::vector<ParameterSet> ParameterSetsFromReport(const nlohmann::json& report, const std::string& source);

// The rows of the settings table: the dotted key of every scalar (or array of scalars) of a
// report's "settings" object, in its order, arrays and numbers as JSON text.
std::vector<std::pair<std::string, std::string>> SettingsRows(const nlohmann::json& settings);

// True when `gnuplot` (a name on PATH or a path) is an executable file.
bool GnuplotAvailable(const std::string& gnuplot = "gnuplot");

}  // namespace rotorid

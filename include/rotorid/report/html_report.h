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
//       the command's JSON report carries them; the plausibility checks and what was read
//       (checks[], input.flights[]) when present.
//
//   ReportInput input;
//   input.title = "rotorid identify";
//   input.report = json_report;                       // tables come from it
//   input.flights = {{"flight 1", &result.flights[0], /*held_out=*/false}};
//   input.parameter_sets = {{"linear", values, Effects{}}};
//   WriteHtmlReport("out/report", input);
//
// Figures need gnuplot (Debian: gnuplot-nox). Without it the report still holds every table and
// says why the figures are missing. The report reads exactly the keys the writers emit (LinearJson,
// RefinedJson, DiagnosisJson and the commands' blocks, docs/report_format.md): a block the command
// did not write is left out, a missing or mistyped key inside a block is an error naming it.

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/ident/observation.h"
#include "rotorid/model/effects.h"

namespace rotorid {

// A flight to draw. The flight is not owned and must outlive WriteHtmlReport.
struct ReportFlight {
  std::string label;
  const ProcessedFlight* flight = nullptr;
  // Held-out (validation) flight, not used to fit the parameters.
  bool held_out = false;
};

// Parameters ("kt", "kd", "<config>.<name>") and the unmodelled effects they go with (for a refine
// report: NamedParameters and EffectsFromReport of rotorid/report/refine_json.h).
struct ParameterSet {
  std::string label;  // "linear", "refined", ...
  std::map<std::string, double> values;
  Effects effects;
};

struct ReportInput {
  std::string title = "rotorid report";
  // The command's JSON report (INTERFACE.md section 5 keys and the project's additions).
  nlohmann::json report = nlohmann::json::object();
  std::vector<ReportFlight> flights;
  std::vector<ParameterSet> parameter_sets;
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
// produce are removed; no other file is ever deleted. Throws
// rotorid::Error on invalid input (null flight, invalid options, a report JSON without a key its
// writer emits) or when DIR cannot be written; gnuplot failures are warnings, not errors.
ReportSummary WriteHtmlReport(const std::string& dir, const ReportInput& input, const ReportOptions& options = {});

// Report flights for processed flights, labelled by their log's file name.
std::vector<ReportFlight> ReportFlights(const std::vector<ProcessedFlight>& flights, bool held_out);

// The parameter sets a saved identify/refine report holds: "linear" (no effects) and "refined"
// (with its "refined.effects"), each when present. Throws rotorid::Error when a present block
// lacks "parameters" or a parameter its "value".
std::vector<ParameterSet> ParameterSetsFromReport(const nlohmann::json& report);

// True when `gnuplot` (a name on PATH or a path) is an executable file.
bool GnuplotAvailable(const std::string& gnuplot = "gnuplot");

}  // namespace rotorid

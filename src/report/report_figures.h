#pragma once

// The report's figures as gnuplot scripts plus their data (internal to the report module).
// Every builder returns a script that reads one data file, given as an already quoted gnuplot
// string, and leaves terminal and output to the caller.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/report/wrench_split.h"

namespace rotorid::internal {

struct FigureSpec {
  std::string name;     // file name without ".svg", e.g. "fig_wrench_1"
  std::string title;    // heading in the report
  std::string caption;  // plain text; how to read it
  int width_px = 1000;
  int height_px = 600;
  std::string data;  // content of the data file
  std::string body;  // gnuplot commands; "$DATA" stands for the quoted data file path
};

// `spec` with its heading and caption set.
inline FigureSpec Titled(FigureSpec spec, std::string title, std::string caption) {
  spec.title = std::move(title);
  spec.caption = std::move(caption);
  return spec;
}

// One column of the wrench figure: a parameter set's split on the flight (nullopt: no values).
struct WrenchColumn {
  std::string label;
  std::optional<WrenchSplit> split;
};

// A time interval to shade on the time axes.
struct TimeMark {
  double start_s = 0.0;
  double end_s = 0.0;
  std::string label;
};

// Order of the panels: the components the paper draws first, then the lateral forces.
inline constexpr int kPanelOrder[6] = {2, 3, 4, 5, 0, 1};

// Figure (a): rows = wrench components, columns = parameter sets over the whole flight, and beside
// them a zoom of `zoom_s` seconds (0: none) on the most excited stretch (MostExcitedWindow of the
// first set) with the rigid body and every set's rotor model, where a lead or lag is visible.
FigureSpec WrenchFigure(const std::string& name, const std::string& flight_label,
                        const std::vector<WrenchColumn>& columns, const std::vector<TimeMark>& marks,
                        int max_points_per_series, double zoom_s);

// The window [start, start + length_s] of the flight in which the rotor wrench changes most (each
// component's squared change normalised by its total over the flight, Fz, Mx, My, Mz summed); the
// whole flight when it is shorter.
std::pair<double, double> MostExcitedWindow(const WrenchSplit& split, double length_s);

// Figure (b): residual amplitude spectra; one curve per parameter set (and series) per component.
struct SpectrumCurve {
  std::string label;
  Eigen::VectorXd frequency_hz;
  Eigen::MatrixXd asd;  // bins x 6
};
FigureSpec SpectrumFigure(const std::string& name, const std::string& group_label,
                          const std::vector<SpectrumCurve>& curves, std::optional<double> cutoff_hz,
                          const std::vector<std::pair<double, double>>& bands_hz);

// Figure (c): parameters +- 3 std normalised by the reference (first) set.
struct ParameterPoint {
  std::string name;
  std::vector<std::optional<double>> value;  // per set
  std::vector<std::optional<double>> std;    // per set
};
// The y axis is 1 +- ParameterAxisHalfWidth(points): it holds the bulk of the ratios and error bars;
// a ratio beyond it is drawn as a triangle at the axis' edge, labelled with its value ("33x").
FigureSpec ParameterFigure(const std::string& name, const std::vector<std::string>& set_labels,
                           const std::vector<ParameterPoint>& points);
double ParameterAxisHalfWidth(const std::vector<ParameterPoint>& points);

// Figure (d1): the diagnosis: gap per component (bars per stage), and the ranking of effects.
struct GapSeries {
  std::string label;                                 // "baseline", "+ delay", "final"
  std::vector<std::optional<double>> per_component;  // 6
};
struct RankedEffect {
  std::string effect;
  std::optional<double> shrink_pct;
  std::string status;  // "selected", "confounded", "not significant", ...: the bar's colour
};
FigureSpec DiagnosisFigure(const std::string& name, const std::vector<GapSeries>& gaps,
                           const std::vector<RankedEffect>& ranking);

// Figure (d3): the residual per frequency band, before and after the selected effects; one panel
// per component with a rotor wrench (Fz, Mx, My, Mz), each in its unit.
struct BandBars {
  std::string label;                          // "1-3 Hz"
  std::vector<std::optional<double>> before;  // 6, residual RMS
  std::vector<std::optional<double>> after;   // 6
};
FigureSpec BandFigure(const std::string& name, const std::vector<BandBars>& bands);

// Figure (d4): the effect signatures: the in-sample shrink of a first-order fit of each effect, and
// the residual's correlation with each of its parameters' signatures.
struct SignatureBars {
  std::string effect;
  double linearized_shrink_pct = 0.0;
  std::vector<std::pair<std::string, double>> correlation;  // parameter label, cosine
};
FigureSpec SignatureFigure(const std::string& name, const std::vector<SignatureBars>& signatures);

// Figure (d2): the ablation table: per configuration of effects, the gap per component.
struct AblationRow {
  std::string label;
  std::vector<std::optional<double>> identification;  // 6
  std::vector<std::optional<double>> held_out;        // 6 (empty when absent)
};
FigureSpec AblationFigure(const std::string& name, const std::vector<AblationRow>& rows);

// The common head of every script: SVG terminal and output file.
std::string ScriptHead(const FigureSpec& figure, const std::string& output_path_quoted);

// Min/max decimation to at most max_points (keeps the envelope and the peaks).
std::vector<Eigen::Index> DecimationIndices(const Eigen::VectorXd& values, int max_points);

}  // namespace rotorid::internal

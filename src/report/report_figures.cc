#include "report/report_figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "report/gnuplot.h"
#include "rotorid/model/parameters.h"

namespace rotorid::internal {

namespace {

constexpr const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);
// The paper's Fig. 3/4 colours: rigid body blue, rotor model red; the error gets its own axis.
constexpr const char* kRigidBodyColour = "#1f77b4";
constexpr const char* kRotorModelColour = "#d62728";
constexpr const char* kErrorColour = "#2ca02c";
constexpr const char* kMarkColour = "#fde2e1";

const char* Colour(size_t k) { return kPalette[k % kPaletteSize]; }

const char* Unit(int component) { return component < 3 ? "N" : "N m"; }

std::string Num(double v) {
  if (!std::isfinite(v)) return "NaN";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", v);
  return buffer;
}

std::string Num(const std::optional<double>& v) { return v ? Num(*v) : "NaN"; }

std::string Fixed(double v, int digits) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.*f", digits, v);
  return buffer;
}

// A data-file string token (xtic labels): no spaces or quotes, so it needs no escaping.
std::string Token(const std::string& text) {
  std::string quoted = GnuplotString(text);
  std::string out = quoted.substr(1, quoted.size() - 2);
  std::replace(out.begin(), out.end(), ' ', '_');
  return "\"" + (out.empty() ? std::string("_") : out) + "\"";
}

bool AnyFinite(const Eigen::Ref<const Eigen::VectorXd>& v) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i])) return true;
  return false;
}

bool AnyPositive(const Eigen::Ref<const Eigen::VectorXd>& v) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i]) && v[i] > 0.0) return true;
  return false;
}

// gnuplot stops a script at "all points undefined": an empty panel gets a note instead of a plot.
std::string EmptyPanel(const std::string& note) {
  return "set yrange [0:1]\nset xrange [0:1]\nunset logscale y\nset label 99 " + GnuplotString(note) +
         " at graph 0.5, graph 0.5 center\nplot 2 notitle\nunset label 99\nset autoscale\n";
}

// A multiplot grid with margins and gaps fixed in pixels, so that the axes of every panel line up
// and the page title gets room of its own.
std::string MultiplotGrid(const FigureSpec& f, int rows, int cols, const std::string& title, int left_px, int right_px,
                          int bottom_px, int top_px, int column_gap_px, int row_gap_px) {
  const double w = f.width_px, h = f.height_px;
  return "set multiplot layout " + std::to_string(rows) + "," + std::to_string(cols) +
         (title.empty() ? std::string() : " title " + GnuplotString(title) + " font ',13'") + " margins " +
         Num(left_px / w) + "," + Num(1.0 - right_px / w) + "," + Num(bottom_px / h) + "," + Num(1.0 - top_px / h) +
         " spacing " + Num(column_gap_px / w) + "," + Num(row_gap_px / h) + "\n";
}

// A legend entry drawn at screen coordinates (x, y): a short coloured line and its text.
std::string ScreenLegend(int id, double x, double y, const char* colour, const std::string& text) {
  return "set arrow " + std::to_string(id) + " from screen " + Num(x) + ", screen " + Num(y) + " to screen " +
         Num(x + 0.025) + ", screen " + Num(y) + " nohead lw 2.5 lc rgb '" + colour + "'\nset label " +
         std::to_string(id) + " " + GnuplotString(text) + " at screen " + Num(x + 0.03) + ", screen " + Num(y) +
         " left font ',13'\n";
}

void AppendBlock(std::string* out, const Eigen::VectorXd& x, const Eigen::VectorXd& y, int max_points) {
  for (const Eigen::Index i : DecimationIndices(y, max_points)) {
    *out += Num(x[i]);
    *out += ' ';
    *out += Num(y[i]);
    *out += '\n';
  }
  *out += "\n\n";  // gnuplot: two blank lines end an "index" block
}

}  // namespace

std::vector<Eigen::Index> DecimationIndices(const Eigen::VectorXd& values, int max_points) {
  const Eigen::Index n = values.size();
  std::vector<Eigen::Index> out;
  if (n <= std::max(max_points, 2)) {
    out.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) out[i] = i;
    return out;
  }
  const Eigen::Index buckets = std::max(max_points / 2, 1);
  out.reserve(2 * buckets);
  for (Eigen::Index b = 0; b < buckets; ++b) {
    const Eigen::Index begin = b * n / buckets, end = (b + 1) * n / buckets;
    Eigen::Index lo = begin, hi = begin;
    for (Eigen::Index i = begin; i < end; ++i) {
      if (!(values[i] >= values[lo])) lo = i;  // NaN-tolerant: a NaN never wins
      if (!(values[i] <= values[hi])) hi = i;
    }
    out.push_back(std::min(lo, hi));
    if (lo != hi) out.push_back(std::max(lo, hi));
  }
  return out;
}

std::string ScriptHead(const FigureSpec& figure, const std::string& output_path_quoted) {
  return "set terminal svg size " + std::to_string(figure.width_px) + "," + std::to_string(figure.height_px) +
         " dynamic noenhanced font 'Helvetica,11' background '#ffffff'\n"
         "set encoding utf8\n"
         "set output " +
         output_path_quoted +
         "\n"
         "set border lc rgb '#555555'\n"
         "set grid lt 1 lc rgb '#e4e4e4' lw 1\n"
         "set key noopaque samplen 1.5 spacing 1.0 font ',9'\n";
}

std::pair<double, double> MostExcitedWindow(const WrenchSplit& split, double length_s) {
  const Eigen::Index n = split.t_s.size();
  if (n < 3 || split.t_s[n - 1] - split.t_s[0] <= length_s) return {n ? split.t_s[0] : 0.0, n ? split.t_s[n - 1] : 0.0};
  // Score of a window: its share of each component's squared rotor-wrench change, summed over the
  // components with a rotor wrench. A delay or lag shifts the curves by an amount proportional to
  // that change, so this is where a lead or lag is easiest to see.
  Eigen::VectorXd score = Eigen::VectorXd::Zero(n);
  for (const int c : {2, 3, 4, 5}) {
    Eigen::VectorXd change = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 1; i < n; ++i) {
      const double d = split.rotor_model(i, c) - split.rotor_model(i - 1, c);
      change[i] = std::isfinite(d) ? d * d : 0.0;
    }
    const double total = change.sum();
    if (total > 0.0) score += change / total;
  }
  double best = -1.0, best_start = split.t_s[0], sum = 0.0;
  for (Eigen::Index begin = 0, end = 0; begin < n; ++begin) {
    while (end < n && split.t_s[end] < split.t_s[begin] + length_s) sum += score[end++];
    if (end == n && split.t_s[n - 1] < split.t_s[begin] + length_s && begin > 0) break;  // window past the end
    if (sum > best) {
      best = sum;
      best_start = split.t_s[begin];
    }
    sum -= score[begin];
  }
  return {best_start, best_start + length_s};
}

namespace {

// One curve as a data block of at most max_points points between t0 and t1.
void AppendWindow(std::string* out, const Eigen::VectorXd& t, const Eigen::VectorXd& y, double t0, double t1,
                  int max_points) {
  Eigen::Index first = 0, last = t.size();
  while (first < t.size() && t[first] < t0) ++first;
  while (last > first && t[last - 1] > t1) --last;
  AppendBlock(out, t.segment(first, last - first), y.segment(first, last - first), max_points);
}

const char* SetColour(size_t set) { return set == 0 ? kRotorModelColour : Colour(set); }

}  // namespace

FigureSpec WrenchFigure(const std::string& name, const std::string& flight_label,
                        const std::vector<WrenchColumn>& columns, const std::vector<TimeMark>& marks,
                        int max_points_per_series, double zoom_s) {
  FigureSpec f;
  f.name = name;
  // The first column with values picks the zoom window, drawn beside the full-length columns.
  const WrenchSplit* reference = nullptr;
  for (const WrenchColumn& c : columns)
    if (!reference && c.split && c.split->t_s.size() > 2) reference = &*c.split;
  const bool zoom = reference && zoom_s > 0.0;
  const std::pair<double, double> window = zoom ? MostExcitedWindow(*reference, zoom_s) : std::make_pair(0.0, 0.0);
  const int num_columns = std::max<int>(1, static_cast<int>(columns.size())) + (zoom ? 1 : 0);
  f.width_px = std::max(900, 75 + 60 + 480 * num_columns + 100 * (num_columns - 1));
  f.height_px = 150 + 185 * 6;
  std::string& body = f.body;
  body += MultiplotGrid(f, 6, num_columns, flight_label, 75, 60, 45, 105, 100, 60);
  body += "set tics font ',12'\nset ytics nomirror\nset y2tics nomirror tc rgb '" + std::string(kErrorColour) +
          "'\nunset key\nunset y2label\n";
  // One legend for the page, under its title; drawn with the first panel, then removed.
  const double legend_y = 1.0 - 52.0 / f.height_px;
  const double legend_step = 330.0 / f.width_px;
  body += ScreenLegend(101, 0.05, legend_y, kRigidBodyColour, "rigid body (IMU): m D_m + D chi");
  body += ScreenLegend(102, 0.05 + legend_step, legend_y, kRotorModelColour, "rotor model: D_k chi_k");
  body += ScreenLegend(103, 0.05 + 2 * legend_step, legend_y, kErrorColour, "error (right axis, green tics)");
  const std::string remove_legend =
      "unset arrow 101\nunset arrow 102\nunset arrow 103\nunset label 101\nunset label 102\nunset label 103\n";
  int block = 0;
  auto panel = [&](int row, size_t column_index) -> std::string {
    const WrenchColumn& column = columns[column_index];
    const int component = kPanelOrder[row];
    std::string title = std::string(kWrenchComponentNames[component]) + " (" + Unit(component) + "), " + column.label;
    std::string text = "unset object\n";
    if (!column.split || column.split->t_s.size() == 0)
      return text + "set title " + GnuplotString(title) + " font ',13'\n" + EmptyPanel("no parameters for this flight");
    const WrenchSplit& split = *column.split;
    if (split.relative_error_pct[component])
      title += ": error " + Fixed(*split.relative_error_pct[component], 1) + " % of rotor wrench";
    text += "set title " + GnuplotString(title) + " font ',13'\n";
    const Eigen::VectorXd rigid = split.rigid_body.col(component), rotor = split.rotor_model.col(component),
                          error = split.error.col(component);
    if (!AnyFinite(rigid) && !AnyFinite(rotor) && !AnyFinite(error)) return text + EmptyPanel("no finite values");
    text += "set xrange [" + Num(split.t_s[0]) + ":" + Num(split.t_s[split.t_s.size() - 1]) + "]\n";
    int object = 1;
    for (const TimeMark& mark : marks)
      text += "set object " + std::to_string(object++) + " rect from first " + Num(mark.start_s) +
              ", graph 0 to first " + Num(mark.end_s) + ", graph 1 behind fc rgb '" + kMarkColour +
              "' fs solid 1.0 noborder\n";
    if (zoom)  // where the zoom beside it is taken: a frame, not a fill
      text += "set object " + std::to_string(object++) + " rect from first " + Num(window.first) +
              ", graph 0 to first " + Num(window.second) + ", graph 1 front fs empty border lc rgb '#777777' dt 2\n";
    text += column_index == 0 ? "set ylabel " + GnuplotString(Unit(component)) + "\n" : "unset ylabel\n";
    text += row == 5 ? "set xlabel 't (s)'\n" : "unset xlabel\n";
    AppendBlock(&f.data, split.t_s, rigid, max_points_per_series);
    AppendBlock(&f.data, split.t_s, rotor, max_points_per_series);
    AppendBlock(&f.data, split.t_s, error, max_points_per_series);
    // The error first, so that the two wrenches are drawn over it.
    text += "plot $DATA index " + std::to_string(block + 2) + " using 1:2 axes x1y2 with lines lw 0.8 lc rgb '" +
            kErrorColour + "' title 'error', $DATA index " + std::to_string(block) +
            " using 1:2 with lines lw 1.2 lc rgb '" + kRigidBodyColour + "' title 'rigid body', $DATA index " +
            std::to_string(block + 1) + " using 1:2 with lines lw 1.2 lc rgb '" + kRotorModelColour +
            "' title 'rotor model'\n";
    block += 3;
    return text;
  };
  // The zoom: the rigid body of the first set and every set's rotor model, undecimated, so that a
  // lead or lag between them shows.
  auto zoom_panel = [&](int row) -> std::string {
    const int component = kPanelOrder[row];
    std::string text =
        "unset object\nunset ylabel\nset title " +
        GnuplotString(std::string(kWrenchComponentNames[component]) + " (" + Unit(component) + "), " +
                      Fixed(window.second - window.first, 0) + " s zoom at " + Fixed(window.first, 1) + " s") +
        " font ',13'\nset xrange [" + Num(window.first) + ":" + Num(window.second) + "]\n";
    text += row == 5 ? "set xlabel 't (s)'\n" : "unset xlabel\n";
    // With several sets, the zoom's legend (which line is which set) beside the page legend.
    text += row == 0 && columns.size() > 1
                ? "set key at screen " + Num(1.0 - 60.0 / f.width_px) + ", screen " + Num(1.0 - 40.0 / f.height_px) +
                      " right top horizontal noopaque font ',13' samplen 2.5\n"
                : "unset key\n";
    AppendWindow(&f.data, reference->t_s, reference->rigid_body.col(component), window.first, window.second, 100000);
    std::string plot = "plot $DATA index " + std::to_string(block++) + " using 1:2 with lines lw 2 lc rgb '" +
                       kRigidBodyColour + "' notitle";
    for (size_t s = 0; s < columns.size(); ++s) {
      if (!columns[s].split || columns[s].split->t_s.size() == 0) continue;
      const WrenchSplit& split = *columns[s].split;
      AppendWindow(&f.data, split.t_s, split.rotor_model.col(component), window.first, window.second, 100000);
      plot += ", $DATA index " + std::to_string(block++) + " using 1:2 with lines lw 1.6 lc rgb '" + SetColour(s) +
              "'" + (s ? " dt 2" : "") + " title " + GnuplotString("rotor model, " + columns[s].label);
    }
    return text + plot + "\nunset key\n";
  };
  for (int row = 0; row < 6; ++row) {
    for (size_t c = 0; c < columns.size(); ++c) {
      body += panel(row, c);
      if (row == 0 && c == 0) body += remove_legend;
    }
    if (zoom) body += zoom_panel(row);
  }
  body += "unset multiplot\n";
  return f;
}

FigureSpec SpectrumFigure(const std::string& name, const std::string& group_label,
                          const std::vector<SpectrumCurve>& curves, std::optional<double> cutoff_hz,
                          const std::vector<std::pair<double, double>>& bands_hz) {
  FigureSpec f;
  f.name = name;
  f.width_px = 1100;
  f.height_px = 60 + 3 * 290;
  std::string& body = f.body;
  body += MultiplotGrid(f, 3, 2, "Residual amplitude spectra, " + group_label + " (Welch, Hann windows, 50 % overlap)",
                        95, 25, 50, 60, 120, 95);
  body += "set xlabel 'frequency (Hz)'\nset format y '%.0e'\nset key top right\n";
  if (cutoff_hz)
    body += "set arrow 1 from first " + Num(*cutoff_hz) + ", graph 0 to first " + Num(*cutoff_hz) +
            ", graph 1 nohead dt 2 lc rgb '#888888'\nset label 1 'low-pass cut-off' at first " + Num(*cutoff_hz) +
            ", graph 0.95 right offset -0.5,0 font ',8' tc rgb '#777777'\n";
  int object = 1;
  for (const auto& [low, high] : bands_hz)
    body += "set object " + std::to_string(object++) + " rect from first " + Num(low) + ", graph 0 to first " +
            Num(high) + ", graph 1 behind fc rgb '" + kMarkColour + "' fs solid 1.0 noborder\n";
  int block = 0;
  for (int panel = 0; panel < 6; ++panel) {
    const int component = kPanelOrder[panel];
    body += "set title " + GnuplotString(std::string(kWrenchComponentNames[component]) + " residual") + " font ',10'\n";
    body += "set ylabel " + GnuplotString(std::string(Unit(component)) + "/sqrt(Hz)") + "\n";
    std::string plot;
    for (size_t k = 0; k < curves.size(); ++k) {
      const SpectrumCurve& curve = curves[k];
      if (curve.frequency_hz.size() < 2 || !AnyPositive(curve.asd.col(component))) continue;
      // Skip DC: the mean was removed, and a log axis cannot show zero.
      for (Eigen::Index i = 1; i < curve.frequency_hz.size(); ++i) {
        const double v = curve.asd(i, component);
        f.data += Num(curve.frequency_hz[i]) + " " + (v > 0.0 ? Num(v) : std::string("NaN")) + "\n";
      }
      f.data += "\n\n";
      plot += std::string(plot.empty() ? "plot " : ", ") + "$DATA index " + std::to_string(block++) +
              " using 1:2 with lines lw 1.3 lc rgb '" + Colour(k) + "' title " + GnuplotString(curve.label);
    }
    if (plot.empty()) {
      body += EmptyPanel("no residual");
      continue;
    }
    body += "set logscale y\nset autoscale\n" + plot + "\n";
  }
  body += "unset multiplot\n";
  return f;
}

namespace {
// A ratio with 3 significant digits: "33", "5.01", "-0.00312".
std::string Ratio(double r) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g", r);
  return buffer;
}
}  // namespace

double ParameterAxisHalfWidth(const std::vector<ParameterPoint>& points) {
  // Deviations from the reference (1) of the other sets' ratios and of every error bar's end.
  std::vector<double> deviations;
  for (const ParameterPoint& p : points) {
    const double reference = p.value.empty() || !p.value[0] ? NAN : *p.value[0];
    for (size_t k = 0; k < p.value.size(); ++k) {
      if (k > 0 && p.value[k]) deviations.push_back(std::abs(*p.value[k] / reference - 1.0));
      if (k < p.std.size() && p.std[k]) deviations.push_back(3.0 * *p.std[k] / std::abs(reference));
    }
  }
  deviations.erase(std::remove_if(deviations.begin(), deviations.end(), [](double d) { return !std::isfinite(d); }),
                   deviations.end());
  if (deviations.empty()) return 0.05;
  std::sort(deviations.begin(), deviations.end());
  // The axis holds the bulk (up to 4x the upper quartile); a few far points are marked at its edge
  // instead of squashing the others.
  const double upper_quartile = deviations[(3 * (deviations.size() - 1)) / 4];
  const double cap = 4.0 * std::max(upper_quartile, 0.01);
  return std::max(0.02, std::min(deviations.back(), cap)) * 1.15;
}

FigureSpec ParameterFigure(const std::string& name, const std::vector<std::string>& set_labels,
                           const std::vector<ParameterPoint>& points) {
  FigureSpec f;
  f.name = name;
  f.width_px = std::max(760, 140 + 60 * static_cast<int>(points.size()));
  f.height_px = 480;
  const size_t sets = set_labels.size();
  const double half_width = ParameterAxisHalfWidth(points);
  const double low = 1.0 - half_width, high = 1.0 + half_width;
  int outliers = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const ParameterPoint& p = points[i];
    const double reference = p.value.empty() || !p.value[0] ? NAN : *p.value[0];
    f.data += std::to_string(i) + " " + Token(p.name);
    for (size_t k = 0; k < sets; ++k) {
      // Per set: ratio, 3 std, and for a ratio beyond the axis its marker at the edge (y, point
      // type: 9 up, 11 down) and its value; NaN stands for "absent" and draws nothing.
      const double ratio = k < p.value.size() && p.value[k] ? *p.value[k] / reference : NAN;
      const double err = k < p.std.size() && p.std[k] ? 3.0 * *p.std[k] / std::abs(reference) : 0.0;
      const bool outside = std::isfinite(ratio) && (ratio < low || ratio > high);
      outliers += outside;
      const double edge = ratio > high ? high - 0.06 * half_width : low + 0.06 * half_width;
      f.data += " " + Num(outside ? NAN : ratio) + " " + Num(err) + " " + Num(outside ? edge : NAN) + " " +
                (ratio > high ? "9" : "11") + " " + Token(outside ? Ratio(ratio) + "x" : "");
    }
    f.data += "\n";
  }
  std::string& body = f.body;
  const std::string reference_label =
      sets ? GnuplotString(set_labels[0]).substr(1, GnuplotString(set_labels[0]).size() - 2) : std::string();
  body += "set title 'Parameter estimates +- 3 std, divided by the " + reference_label + " estimate" +
          (outliers ? "; triangles: beyond the axis, with their ratio" : "") + "' font ',12'\n";
  body += "set lmargin 12\nset bmargin 5\n";
  body += "set xtics rotate by -40 nomirror font ',10'\nset ytics nomirror\n";
  body += "set xrange [-0.7:" + Num(static_cast<double>(points.size()) - 0.3) + "]\n";
  body += "set yrange [" + Num(low) + ":" + Num(high) + "]\n";
  // The key outside the frame: markers at the edges must not hide under it.
  body += "set ylabel 'estimate / reference'\nset key outside right top vertical\n";
  body += "set arrow 1 from graph 0, first 1 to graph 1, first 1 nohead dt 3 lc rgb '#888888'\n";
  if (points.empty()) {
    body += EmptyPanel("no essential parameters");
    return f;
  }
  body += "plot ";
  for (size_t k = 0; k < sets; ++k) {
    const double offset = sets > 1 ? -0.15 + 0.3 * static_cast<double>(k) / static_cast<double>(sets - 1) : 0.0;
    const int c = 3 + 5 * static_cast<int>(k);
    const std::string x = "($1+(" + Num(offset) + "))";
    body += std::string(k ? ", " : "") + "$DATA using " + x + ":" + std::to_string(c) + ":" + std::to_string(c + 1) +
            (k == 0 ? ":xtic(2)" : "") + " with yerrorbars pt 7 ps 0.7 lw 1.3 lc rgb '" + Colour(k) + "' title " +
            GnuplotString(set_labels[k]);
    body += ", $DATA using " + x + ":" + std::to_string(c + 2) + ":" + std::to_string(c + 3) +
            " with points pt variable ps 1.4 lc rgb '" + Colour(k) + "' notitle";
    body += ", $DATA using " + x + ":" + std::to_string(c + 2) + ":" + std::to_string(c + 4) +
            " with labels left offset 1.2,0 font ',9' tc rgb '" + Colour(k) + "' notitle";
  }
  body += "\n";
  return f;
}

namespace {

// Components with at least one value in any of the rows.
std::vector<int> UsedComponents(const std::vector<const std::vector<std::optional<double>>*>& rows) {
  std::vector<int> used;
  for (const int j : kPanelOrder) {
    bool any = false;
    for (const auto* r : rows)
      if (j < static_cast<int>(r->size()) && (*r)[j]) any = true;
    if (any) used.push_back(j);
  }
  return used;
}

std::string HistogramStyle() {
  return "set style data histograms\nset style histogram clustered gap 1\n"
         "set style fill solid 0.85 noborder\nset boxwidth 0.9\nset yrange [0:*]\nset xtics nomirror\n";
}

}  // namespace

FigureSpec DiagnosisFigure(const std::string& name, const std::vector<GapSeries>& gaps,
                           const std::vector<RankedEffect>& ranking) {
  FigureSpec f;
  f.name = name;
  std::vector<const std::vector<std::optional<double>>*> rows;
  for (const GapSeries& g : gaps) rows.push_back(&g.per_component);
  const std::vector<int> components = UsedComponents(rows);
  const bool draw_gaps = !components.empty() && !gaps.empty();
  bool draw_ranking = false;
  for (const RankedEffect& r : ranking) draw_ranking = draw_ranking || r.shrink_pct.has_value();
  const int panels = (draw_gaps ? 1 : 0) + (draw_ranking ? 1 : 0);
  f.width_px = panels == 2 ? 1150 : 700;
  f.height_px = 440;
  std::string& body = f.body;
  if (panels == 0) {
    body += EmptyPanel("no diagnosis values");
    return f;
  }
  body += MultiplotGrid(f, 1, panels, "", 85, 30, 80, 40, 110, 0);
  int block = 0;
  if (draw_gaps) {
    for (const int j : components) {
      f.data += std::string("\"") + kWrenchComponentNames[j] + "\"";
      for (const GapSeries& g : gaps)
        f.data += " " + Num(j < static_cast<int>(g.per_component.size()) ? g.per_component[j] : std::nullopt);
      f.data += "\n";
    }
    f.data += "\n\n";
    body += HistogramStyle();
    body += "set title 'Held-out gap per component (relative error, %)' font ',11'\n";
    body += "set ylabel '||rho|| / ||rotor wrench|| (%)'\nset key top right\n";
    body += "plot ";
    for (size_t k = 0; k < gaps.size(); ++k)
      body += std::string(k ? ", " : "") + "$DATA index " + std::to_string(block) + " using " + std::to_string(k + 2) +
              (k == 0 ? ":xtic(1)" : "") + " lc rgb '" + Colour(k) + "' title " + GnuplotString(gaps[k].label);
    body += "\n";
    ++block;
  }
  if (draw_ranking) {
    int i = 0;
    for (const RankedEffect& r : ranking) {
      if (!r.shrink_pct) continue;
      // Selected effects green, confounded orange, implausible red, the rest grey: "lc rgb variable" reads an
      // integer.
      const int colour = r.status == "selected"      ? 0x2ca02c
                         : r.status == "confounded"  ? 0xff7f0e
                         : r.status == "implausible" ? 0xd62728
                                                     : 0xb0b0b0;
      f.data +=
          std::to_string(i++) + " " + Token(r.effect) + " " + Num(*r.shrink_pct) + " " + std::to_string(colour) + "\n";
    }
    f.data += "\n\n";
    body += "set style data boxes\nset style fill solid 0.85 noborder\nset boxwidth 0.6\nset autoscale y\n";
    body += "set xrange [-0.6:" + std::to_string(i) + "-0.4]\nset xtics rotate by -30 nomirror\n";
    body +=
        "set title 'Held-out gap removed by each effect (%): green selected, orange confounded, red implausible' font "
        "',11'\n";
    body += "set ylabel 'shrink (%)'\nunset key\n";
    body += "set arrow 2 from graph 0, first 0 to graph 1, first 0 nohead lc rgb '#555555'\n";
    body += "plot $DATA index " + std::to_string(block) + " using 1:3:4:xtic(2) with boxes lc rgb variable notitle, " +
            "$DATA index " + std::to_string(block) +
            " using 1:3:(sprintf('%.1f', $3)) with labels offset 0, char 0.7 font ',9' notitle\n";
  }
  body += "unset multiplot\n";
  return f;
}

FigureSpec BandFigure(const std::string& name, const std::vector<BandBars>& bands) {
  FigureSpec f;
  f.name = name;
  f.width_px = 1150;
  f.height_px = 380;
  const int components[] = {2, 3, 4, 5};
  std::string& body = f.body;
  body += MultiplotGrid(f, 1, 4, "", 75, 20, 70, 40, 75, 0);
  body += HistogramStyle() + "set xtics rotate by -30 font ',10'\nset key top right font ',9'\nset format y '%.2g'\n";
  for (int p = 0; p < 4; ++p) {
    const int c = components[p];
    for (const BandBars& b : bands)
      f.data += Token(b.label) + " " + Num(c < static_cast<int>(b.before.size()) ? b.before[c] : std::nullopt) + " " +
                Num(c < static_cast<int>(b.after.size()) ? b.after[c] : std::nullopt) + "\n";
    f.data += "\n\n";
    body += "set title " + GnuplotString(std::string(kWrenchComponentNames[c]) + " residual (" + Unit(c) + " RMS)") +
            " font ',11'\n";
    body += std::string(p == 0 ? "set ylabel 'residual RMS'\n" : "unset ylabel\n") + (p == 0 ? "" : "unset key\n");
    body += "plot $DATA index " + std::to_string(p) + " using 2:xtic(1) lc rgb '" + kRigidBodyColour +
            "' title 'linear', $DATA index " + std::to_string(p) + " using 3 lc rgb '#9ecae1' title 'with effects'\n";
  }
  body += "unset multiplot\n";
  return f;
}

FigureSpec SignatureFigure(const std::string& name, const std::vector<SignatureBars>& signatures) {
  FigureSpec f;
  f.name = name;
  size_t labels = 0;
  for (const SignatureBars& s : signatures) labels += s.correlation.size();
  f.width_px = std::max(1000, 480 + 38 * static_cast<int>(labels));
  f.height_px = 420;
  // Left: one bar per effect; right: one bar per parameter, in its effect's colour.
  for (size_t e = 0; e < signatures.size(); ++e)
    f.data += std::to_string(e) + " " + Token(signatures[e].effect) + " " + Num(signatures[e].linearized_shrink_pct) +
              " " + std::to_string(std::stoi(std::string(Colour(e)).substr(1), nullptr, 16)) + "\n";
  f.data += "\n\n";
  int i = 0;
  for (size_t e = 0; e < signatures.size(); ++e)
    for (const auto& [label, correlation] : signatures[e].correlation)
      f.data += std::to_string(i++) + " " + Token(label) + " " + Num(correlation) + " " +
                std::to_string(std::stoi(std::string(Colour(e)).substr(1), nullptr, 16)) + "\n";
  f.data += "\n\n";
  std::string& body = f.body;
  body += "set multiplot\n";
  body += "set style data boxes\nset style fill solid 0.85 noborder\nset boxwidth 0.6\nunset key\n";
  body += "set xtics rotate by -35 nomirror font ',10'\nset ytics nomirror\n";
  const double split = 360.0 / f.width_px;
  body += "set lmargin at screen " + Num(70.0 / f.width_px) + "\nset rmargin at screen " + Num(split - 0.02) +
          "\nset bmargin at screen " + Num(95.0 / f.height_px) + "\nset tmargin at screen " +
          Num(1.0 - 40.0 / f.height_px) + "\n";
  body += "set title 'In-sample shrink of a first-order fit (%)' font ',11'\nset yrange [0:*]\n";
  body += "set xrange [-0.6:" + std::to_string(signatures.size()) + "-0.4]\n";
  body +=
      "plot $DATA index 0 using 1:3:4:xtic(2) with boxes lc rgb variable, $DATA index 0 using 1:3:(sprintf('%.1f', "
      "$3)) with labels offset 0, char 0.7 font ',9'\n";
  body +=
      "set lmargin at screen " + Num(split + 0.05) + "\nset rmargin at screen " + Num(1.0 - 20.0 / f.width_px) + "\n";
  body += "set title 'Correlation of the residual with each parameter signature' font ',11'\nset yrange [-1:1]\n";
  body += "set xrange [-0.6:" + std::to_string(std::max(i, 1)) + "-0.4]\n";
  body += "set arrow 1 from graph 0, first 0 to graph 1, first 0 nohead lc rgb '#555555'\n";
  body += "plot $DATA index 1 using 1:3:4:xtic(2) with boxes lc rgb variable\n";
  body += "unset multiplot\n";
  return f;
}

FigureSpec AblationFigure(const std::string& name, const std::vector<AblationRow>& rows) {
  FigureSpec f;
  f.name = name;
  std::vector<const std::vector<std::optional<double>>*> ident, held;
  for (const AblationRow& r : rows) {
    ident.push_back(&r.identification);
    if (!r.held_out.empty()) held.push_back(&r.held_out);
  }
  const std::vector<int> ident_components = UsedComponents(ident), held_components = UsedComponents(held);
  struct Panel {
    std::string title;
    std::vector<int> components;
    bool held_out;
  };
  std::vector<Panel> panels;
  if (!ident_components.empty()) panels.push_back({"identification flights", ident_components, false});
  if (!held_components.empty()) panels.push_back({"held-out flights", held_components, true});
  f.width_px =
      std::max(700, std::min(1400, 200 + 90 * static_cast<int>(rows.size()) * static_cast<int>(panels.size())));
  f.height_px = 480;
  std::string& body = f.body;
  if (panels.empty()) {
    body += EmptyPanel("no ablation values");
    return f;
  }
  body += MultiplotGrid(f, 1, static_cast<int>(panels.size()), "", 85, 30, 110, 40, 100, 0);
  body += HistogramStyle() + "set xtics rotate by -35 font ',9'\nset key top right\n";
  body += "set ylabel 'relative error (%)'\n";
  for (size_t p = 0; p < panels.size(); ++p) {
    for (const AblationRow& r : rows) {
      const std::vector<std::optional<double>>& values = panels[p].held_out ? r.held_out : r.identification;
      f.data += Token(r.label);
      for (const int j : panels[p].components)
        f.data += " " + Num(j < static_cast<int>(values.size()) ? values[j] : std::nullopt);
      f.data += "\n";
    }
    f.data += "\n\n";
    body +=
        "set title " + GnuplotString("Ablation: relative error per component, " + panels[p].title) + " font ',11'\n";
    body += "plot ";
    for (size_t k = 0; k < panels[p].components.size(); ++k)
      body += std::string(k ? ", " : "") + "$DATA index " + std::to_string(p) + " using " + std::to_string(k + 2) +
              (k == 0 ? ":xtic(1)" : "") + " lc rgb '" + Colour(k) + "' title '" +
              kWrenchComponentNames[panels[p].components[k]] + "'";
    body += "\n";
  }
  body += "unset multiplot\n";
  return f;
}

}  // namespace rotorid::internal

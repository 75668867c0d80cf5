#include "rotorid/report/html_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include "report/diagnosis_section.h"
#include "report/gnuplot.h"
#include "report/html_answer.h"
#include "report/html_text.h"
#include "report/report_figures.h"
#include "report/report_files.h"
#include "report/spectrum.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/parameters.h"
#include "rotorid/report/input_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"
#include "rotorid/report/refine_json.h"
#include "rotorid/report/wrench_split.h"

namespace rotorid {

using internal::ComponentCells;
using internal::ComponentHeader;
using internal::FigureSpec;
using internal::General;
using internal::Html;
using internal::Pct;
using internal::Sci;
using nlohmann::json;

namespace {

// The components with a rotor wrench (Table III's columns).
const std::vector<int> kRotorComponents = {2, 3, 4, 5};

// kt, kd first, then each configuration's parameters in MODEL.md's order, then anything else.
bool ParameterLess(const std::string& a, const std::string& b) {
  auto key = [](const std::string& name) {
    for (int k = 0; k < kNumRotorCoefficients; ++k)
      if (name == kRotorCoefficientNames[k]) return std::make_tuple(0, std::string(), k, name);
    const size_t dot = name.rfind('.');
    if (dot != std::string::npos)
      for (int k = 0; k < kNumBodyParameters; ++k)
        if (name.compare(dot + 1, std::string::npos, kBodyParameterNames[k]) == 0)
          return std::make_tuple(1, name.substr(0, dot), k, name);
    return std::make_tuple(2, std::string(), 0, name);
  };
  return key(a) < key(b);
}

// Dotted keys of every scalar (or array of scalars) below `j`: the run settings are shown as they
// are recorded, whatever options a command adds.
void Flatten(const json& j, const std::string& prefix, std::vector<std::pair<std::string, std::string>>* out) {
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) Flatten(value, prefix.empty() ? key : prefix + "." + key, out);
  } else {
    out->emplace_back(prefix, j.is_string() ? j.get<std::string>() : j.dump());
  }
}

// A number of a result as its JSON shows it: nothing (a dash) when not finite.
std::optional<double> Finite(double v) { return std::isfinite(v) ? std::optional(v) : std::nullopt; }

// "delay + motor_lag", or "none".
std::string AblationLabel(const AblationEntry& entry) {
  std::string label;
  for (EffectKind kind : entry.effects) label += (label.empty() ? "" : " + ") + std::string(EffectName(kind));
  return label.empty() ? "none" : label;
}

// One cell of the input.flights[] table: numbers with 4 digits, lists joined, an object or a list of
// objects (segments) one line per entry.
std::string InputCell(const json& v) {
  if (v.is_number()) return General(v.get<double>());
  if (v.is_string()) return Html(v.get<std::string>());
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_null()) return "&ndash;";
  std::string out;
  if (v.is_object()) {
    for (const auto& [key, value] : v.items())
      out += (out.empty() ? "" : "<br/>") + Html(key) + ": " + InputCell(value);
    return out;
  }
  const bool lines = std::any_of(v.begin(), v.end(), [](const json& e) { return e.is_object(); });
  for (const json& e : v) {
    std::string entry;
    if (e.is_object())
      for (const auto& item : e.items()) entry += (entry.empty() ? "" : ", ") + InputCell(item.value());
    else
      entry = InputCell(e);
    out += (out.empty() ? "" : lines ? "<br/>" : ", ") + entry;
  }
  return out.empty() ? "&ndash;" : out;
}

// ---------------------------------------------------------------------------------------------
// Figures: SVG from gnuplot, inlined with their ids made unique.

// Strips the XML prolog and prefixes every id (and every reference to one), so that several
// gnuplot SVGs can live in one HTML document.
std::string InlineSvg(const std::string& svg, const std::string& prefix) {
  const size_t start = svg.find("<svg");
  std::string text = start == std::string::npos ? svg : svg.substr(start);
  const std::pair<std::string, std::string> patterns[] = {{"id='", "id='" + prefix},
                                                          {"id=\"", "id=\"" + prefix},
                                                          {"href='#", "href='#" + prefix},
                                                          {"href=\"#", "href=\"#" + prefix},
                                                          {"url(#", "url(#" + prefix}};
  for (const auto& [from, to] : patterns) {
    std::string out;
    out.reserve(text.size() + 1024);
    size_t pos = 0;
    for (size_t hit; (hit = text.find(from, pos)) != std::string::npos; pos = hit + from.size()) {
      // Only whole attribute names: " id=", not "grid=" or "data-id=".
      const bool whole = from.rfind("url", 0) == 0 || hit == 0 || text[hit - 1] == ' ' || text[hit - 1] == '\t' ||
                         text[hit - 1] == '\n' || text[hit - 1] == ':';
      out.append(text, pos, hit - pos);
      out += whole ? to : from;
    }
    out.append(text, pos, std::string::npos);
    text = std::move(out);
  }
  return text;
}

struct RenderedFigure {
  FigureSpec spec;
  std::string svg;    // empty when not drawn
  std::string error;  // why not
};

// ---------------------------------------------------------------------------------------------
// The report.

constexpr const char* kCss = R"css(
:root { --ink:#1d2330; --muted:#5f6b7a; --line:#dfe3e8; --accent:#1f5fa8; --warn-bg:#fff6e0; --warn-line:#e8b64c;
        --bad-bg:#fdecea; --bad-line:#d9534f; }
* { box-sizing: border-box; }
body { margin: 0; color: var(--ink); background: #f6f7f9;
       font: 15px/1.5 -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1180px; margin: 0 auto; padding: 28px 32px 60px; background: #fff; min-height: 100vh;
       box-shadow: 0 0 0 1px var(--line); }
h1 { font-size: 26px; margin: 0 0 4px; letter-spacing: -0.01em; }
h2 { font-size: 20px; margin: 40px 0 10px; padding-bottom: 6px; border-bottom: 2px solid var(--line); }
h3 { font-size: 16px; margin: 24px 0 8px; }
p, li { max-width: 860px; }
.meta { color: var(--muted); font-size: 13px; margin-bottom: 18px; }
nav { font-size: 13px; margin: 12px 0 8px; }
nav a { color: var(--accent); text-decoration: none; margin-right: 14px; white-space: nowrap; }
table { border-collapse: collapse; margin: 8px 0 14px; font-size: 13.5px; }
th, td { padding: 4px 10px; border-bottom: 1px solid var(--line); text-align: left; vertical-align: top; }
th { background: #f0f2f5; font-weight: 600; white-space: nowrap; }
thead th { border-bottom: 2px solid #c9ced6; }
th.group { text-align: center; border-left: 2px solid #fff; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.sep, th.sep { border-left: 2px solid #c9ced6; }
tbody tr:nth-child(even) td { background: #fafbfc; }
td.no { color: var(--muted); }
.tag { display: inline-block; padding: 0 7px; border-radius: 9px; font-size: 12px; background: #e8eef7; color: #24507f; }
.tag.held { background: #efe7f7; color: #5b2f86; }
.tag.yes { background: #e3f3e6; color: #22662f; }
.tag.nope { background: #eee; color: #777; }
.tag.warn { background: #fff0d9; color: #8a5300; }
.tag.bad { background: #fdecea; color: #a12a26; }
.verdict { padding: 12px 16px; border-left: 4px solid var(--accent); background: #eef3fa; margin: 10px 0 16px;
           border-radius: 3px; }
.verdict pre { margin: 6px 0 0; white-space: pre-wrap; font: 13.5px/1.5 ui-monospace, SFMono-Regular, Menlo, Consolas,
               monospace; }
tr.total td { font-weight: 600; }
td.note { min-width: 200px; max-width: 280px; }
.tag { white-space: nowrap; }
.scroll { overflow-x: auto; }
.box { padding: 10px 14px; border-left: 4px solid var(--warn-line); background: var(--warn-bg); margin: 10px 0;
       border-radius: 3px; }
.box.bad { border-color: var(--bad-line); background: var(--bad-bg); }
.box.ok { border-color: #5cb85c; background: #eef8ee; }
.box ul { margin: 4px 0; padding-left: 20px; }
figure { margin: 14px 0 26px; }
figure svg { width: 100%; height: auto; display: block; border: 1px solid var(--line); border-radius: 3px; }
figcaption { color: var(--muted); font-size: 13px; margin-top: 6px; max-width: 900px; }
.small { font-size: 12.5px; color: var(--muted); }
code { font: 12.5px/1.4 ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; background: #f0f2f5;
       padding: 1px 4px; border-radius: 3px; }
@media print { body { background: #fff; } main { box-shadow: none; } figure { break-inside: avoid; } }
)css";

class ReportBuilder {
 public:
  ReportBuilder(const std::string& dir, const ReportInput& input, const ReportOptions& options)
      : dir_(dir), input_(input), options_(options) {}

  ReportSummary Build();

 private:
  // Data.
  void ComputeSplits();
  void CollectParameterBlocks();
  void CollectMarks();
  // Figures.
  std::vector<FigureSpec> FigureSpecs();
  std::optional<FigureSpec> ParameterFigureSpec() const;
  std::optional<FigureSpec> AblationFigureSpec() const;
  void RenderFigures(std::vector<FigureSpec> specs);
  // Page.
  std::string Page() const;
  std::string FlightsSection() const;
  std::string WarningsSection() const;
  std::string ParametersSection() const;
  std::string EffectsTable() const;
  std::string RelativeErrorSection() const;
  std::string FigureHtml(const std::string& name) const;
  std::string WrenchSection() const;
  std::string SpectrumSection() const;
  std::string ChecksSection() const;
  std::string InputFlightsTable() const;
  std::string AblationSection() const;
  std::string SettingsSection() const;

  void Warn(const std::string& message) { warnings_.push_back(message); }
  std::vector<size_t> FlightsOfGroup(bool held_out) const;

  const std::string dir_;
  const ReportInput& input_;
  const ReportOptions& options_;

  std::string gnuplot_path_;
  // splits_[flight][set]
  std::vector<std::vector<std::optional<WrenchSplit>>> splits_;
  // Column groups of the parameter table: a parameter set, a TLS result with its statistics, or both.
  struct ParameterBlock {
    std::string label;
    const std::vector<std::string>* names = nullptr;  // of `solution`'s parameters
    const TlsSolution* solution = nullptr;
    const ParameterSet* set = nullptr;
    // The statistics of `name`, when the block has them.
    std::optional<ParameterStatistics> Statistics(const std::string& name) const {
      if (!solution) return std::nullopt;
      const auto it = std::find(names->begin(), names->end(), name);
      if (it == names->end()) return std::nullopt;
      return ParameterStatisticsOf(*names, *solution, static_cast<size_t>(it - names->begin()));
    }
  };
  std::vector<ParameterBlock> blocks_;
  std::string ParameterCells(const ParameterBlock& b, const std::string& name, std::optional<double>* value,
                             std::optional<double>* std_value, bool* discarded) const;
  std::vector<std::vector<internal::TimeMark>> marks_;  // per flight
  std::vector<std::pair<double, double>> bands_hz_;
  std::vector<RenderedFigure> figures_;
  std::vector<std::string> warnings_;
};

std::vector<size_t> ReportBuilder::FlightsOfGroup(bool held_out) const {
  std::vector<size_t> out;
  for (size_t f = 0; f < input_.flights.size(); ++f)
    if (input_.flights[f].held_out == held_out) out.push_back(f);
  return out;
}

void ReportBuilder::ComputeSplits() {
  splits_.assign(input_.flights.size(), std::vector<std::optional<WrenchSplit>>(input_.parameter_sets.size()));
  for (size_t f = 0; f < input_.flights.size(); ++f) {
    for (size_t s = 0; s < input_.parameter_sets.size(); ++s) {
      try {
        splits_[f][s] = ComputeWrenchSplit(*input_.flights[f].flight, input_.parameter_sets[s].values,
                                           input_.parameter_sets[s].effects);
      } catch (const Error& e) {
        Warn("flight '" + input_.flights[f].label + "', parameter set '" + input_.parameter_sets[s].label +
             "': not drawn (" + e.what() + ")");
      }
    }
  }
}

// The TLS results carry statistics: the parameter set of the same label ("linear", "refined") shows
// them, and one that no set stands for is a column group of its own (delay's "refined" beside its
// "with the delay" set).
void ReportBuilder::CollectParameterBlocks() {
  std::vector<std::pair<std::string, const TlsSolution*>> solutions;
  if (input_.linear) solutions.emplace_back("linear", &input_.linear->solution);
  if (input_.refined) solutions.emplace_back("refined", &input_.refined->refined);
  const std::vector<std::string>* names = input_.linear ? &input_.linear->system.parameter_names : nullptr;
  auto solution_of = [&](const std::string& label) -> const TlsSolution* {
    for (const auto& [solution_label, solution] : solutions)
      if (solution_label == label) return solution;
    return nullptr;
  };
  std::set<std::string> seen;
  for (const ParameterSet& set : input_.parameter_sets)
    if (seen.insert(set.label).second) blocks_.push_back({set.label, names, solution_of(set.label), &set});
  for (const auto& [label, solution] : solutions)
    if (seen.insert(label).second) blocks_.push_back({label, names, solution, nullptr});
}

// The diagnosis's worst stretches, shaded on the time axes of the flight they name (by its log
// path), and the band holding most of the residual, shaded on the spectra.
void ReportBuilder::CollectMarks() {
  marks_.assign(input_.flights.size(), {});
  if (!input_.diagnosis) return;
  for (const FlightStretch& stretch : input_.diagnosis->where.worst_stretches)
    for (size_t f = 0; f < input_.flights.size(); ++f)
      if (input_.flights[f].flight->source == stretch.flight)
        marks_[f].push_back({stretch.start_s, stretch.end_s, kWrenchComponentNames[stretch.dominant_component]});
  bands_hz_ = internal::WorstBands(*input_.diagnosis);
}

std::vector<FigureSpec> ReportBuilder::FigureSpecs() {
  std::vector<FigureSpec> specs;
  // (a) The paper's Fig. 3/4, one figure per flight.
  for (size_t f = 0; f < input_.flights.size(); ++f) {
    std::vector<internal::WrenchColumn> columns;
    for (size_t s = 0; s < input_.parameter_sets.size(); ++s)
      columns.push_back({input_.parameter_sets[s].label, splits_[f][s]});
    const ReportFlight& flight = input_.flights[f];
    const std::string role = flight.held_out ? "held-out flight" : "identification flight";
    const std::string title = flight.label + " (" + role + ", configuration " + flight.flight->vehicle.name + ")";
    FigureSpec spec = internal::WrenchFigure("fig_wrench_" + std::to_string(f + 1), title, columns, marks_[f],
                                             options_.max_points_per_series, options_.zoom_window_s);
    spec.title = title;
    spec.caption =
        "Per wrench component, the Newton-Euler wrench m D_m + D chi computed from the IMU (rigid body, blue) and "
        "the rotor model D_k chi_k computed from the rotor speeds (red); their difference rho, the equation error, "
        "is drawn in green against the right-hand axis. One column per parameter set. "
        "When the model holds, blue and red lie on top of each other and the error looks like noise without "
        "structure. The right-hand column zooms into the " +
        FormatValue("%.0f", options_.zoom_window_s) +
        " s where the rotor wrench changes most (dashed frame on the left): there a lead or lag of the rotor model "
        "against the rigid body shows, and a refined set with a delay or motor lag should lie on the blue curve." +
        std::string(marks_[f].empty() ? "" : " Shaded: stretches the diagnosis points at.");
    if (!columns.empty()) specs.push_back(std::move(spec));
  }
  // (b) Residual spectra, identification and held-out flights separately.
  const std::optional<double> cutoff =
      input_.observation ? std::optional(input_.observation->filter.cutoff_hz) : std::nullopt;
  for (const bool held_out : {false, true}) {
    const std::vector<size_t> group = FlightsOfGroup(held_out);
    if (group.empty()) continue;
    std::vector<internal::SpectrumCurve> curves;
    for (size_t s = 0; s < input_.parameter_sets.size(); ++s) {
      // One rate for the group: the first flight's; flights at another rate are left out.
      double rate_hz = 0.0;
      std::vector<std::vector<Eigen::VectorXd>> residual(kNumWrenchComponents);
      size_t longest = 0;
      for (const size_t f : group) {
        const std::optional<WrenchSplit>& split = splits_[f][s];
        if (!split || split->t_s.size() < 16) continue;
        const Eigen::VectorXd& t = split->t_s;
        const double flight_rate = static_cast<double>(t.size() - 1) / (t[t.size() - 1] - t[0]);
        if (!(flight_rate > 0.0) || !std::isfinite(flight_rate)) continue;
        if (rate_hz == 0.0) rate_hz = flight_rate;
        if (std::abs(flight_rate - rate_hz) > 0.01 * rate_hz) {
          Warn("spectrum: flight '" + input_.flights[f].label + "' has rows at " + General(flight_rate) + " Hz, not " +
               General(rate_hz) + " Hz as the others; left out of the spectrum");
          continue;
        }
        for (int c = 0; c < kNumWrenchComponents; ++c) residual[c].push_back(split->error.col(c));
        longest = std::max(longest, static_cast<size_t>(t.size()));
      }
      if (rate_hz == 0.0) continue;
      const int segment =
          std::min(options_.max_spectrum_segment, internal::FloorPowerOfTwo(static_cast<int>(longest / 2)));
      if (segment < 16) continue;
      internal::SpectrumCurve curve;
      curve.label = input_.parameter_sets[s].label;
      for (int c = 0; c < kNumWrenchComponents; ++c) {
        const internal::AmplitudeSpectrum spectrum = internal::WelchAmplitudeSpectrum(residual[c], rate_hz, segment);
        if (c == 0) {
          curve.frequency_hz = spectrum.frequency_hz;
          curve.asd.resize(spectrum.asd.size(), kNumWrenchComponents);
        }
        curve.asd.col(c) = spectrum.asd;
      }
      curves.push_back(std::move(curve));
    }
    if (curves.empty()) continue;
    const std::string group_label = held_out ? "held-out flights" : "identification flights";
    FigureSpec spec = internal::SpectrumFigure(held_out ? "fig_spectrum_held_out" : "fig_spectrum_identification",
                                               group_label, curves, cutoff, bands_hz_);
    spec.title = "Residual spectra, " + group_label;
    spec.caption =
        "Amplitude spectral density of the equation error rho per component, one curve per parameter set (Welch's "
        "averaged periodogram over every flight of the group). A flat floor is sensor noise; peaks and a raised "
        "low-frequency end are structure the model misses. An effect that helps lowers its curve where it acts: a "
        "delay or motor lag at the frequencies of the manoeuvres, a bias at the lowest frequencies. Above the "
        "low-pass cut-off (dashed) the signals were filtered away.";
    specs.push_back(std::move(spec));
  }
  // (c) Parameters with error bars, from the results that carry statistics.
  if (std::optional<FigureSpec> spec = ParameterFigureSpec()) specs.push_back(std::move(*spec));
  // (d) Diagnosis and ablation, when the command has them.
  if (input_.diagnosis)
    for (FigureSpec& spec : internal::DiagnosisFigures(*input_.diagnosis)) specs.push_back(std::move(spec));
  if (std::optional<FigureSpec> spec = AblationFigureSpec()) specs.push_back(std::move(*spec));
  return specs;
}

std::optional<FigureSpec> ReportBuilder::AblationFigureSpec() const {
  if (!input_.ablation || input_.ablation->entries.empty()) return std::nullopt;
  std::vector<internal::AblationRow> table;
  for (const AblationEntry& entry : input_.ablation->entries)
    table.push_back({AblationLabel(entry), entry.relative_error_pct, entry.held_out_relative_error_pct});
  return internal::Titled(internal::AblationFigure("fig_ablation", table), "Ablation",
                          "Relative error per component for each combination of effects, on the identification "
                          "flights and, when given, on held-out flights. An effect earns its place when it lowers "
                          "the held-out bars, not only the identification ones.");
}

std::optional<FigureSpec> ReportBuilder::ParameterFigureSpec() const {
  std::vector<std::string> labels;
  std::vector<const ParameterBlock*> with_statistics;
  for (const ParameterBlock& b : blocks_)
    if (b.solution) {
      labels.push_back(b.label);
      with_statistics.push_back(&b);
    }
  if (with_statistics.empty()) return std::nullopt;
  std::vector<std::string> names;
  for (const std::string& name : *with_statistics[0]->names) {
    const ParameterStatistics p = *with_statistics[0]->Statistics(name);
    if (p.essential && std::isfinite(p.value) && p.value != 0.0) names.push_back(name);
  }
  std::sort(names.begin(), names.end(), ParameterLess);
  std::vector<internal::ParameterPoint> points;
  for (const std::string& name : names) {
    internal::ParameterPoint p;
    p.name = name;
    for (const ParameterBlock* b : with_statistics) {
      const std::optional<ParameterStatistics> statistics = b->Statistics(name);
      p.value.push_back(statistics ? Finite(statistics->value) : std::nullopt);
      p.std.push_back(statistics ? Finite(statistics->std) : std::nullopt);
    }
    points.push_back(std::move(p));
  }
  FigureSpec spec = internal::ParameterFigure("fig_parameters", labels, points);
  spec.title = "Parameter estimates";
  spec.caption = "Each essential parameter of the " + labels[0] +
                 " estimate, divided by that estimate, with error bars of 3 standard deviations; other sets are "
                 "divided by the same value so that every parameter shares one axis. A refined value outside the "
                 "linear error bar means the effects changed the estimate by more than its uncertainty.";
  return spec;
}

namespace {

// The figure's complete script, reading `data_path` and writing `output_path` (both quoted).
std::string FigureScript(const FigureSpec& spec, const std::string& output_path, const std::string& data_path) {
  std::string body = spec.body;
  for (size_t pos = 0; (pos = body.find("$DATA", pos)) != std::string::npos; pos += data_path.size())
    body.replace(pos, 5, data_path);
  return internal::ScriptHead(spec, output_path) + body;
}

}  // namespace

void ReportBuilder::RenderFigures(std::vector<FigureSpec> specs) {
  for (FigureSpec& spec : specs) figures_.push_back({std::move(spec), "", ""});
  if (gnuplot_path_.empty()) return;
  internal::TempDir temp("rotorid-report");
  const std::string kept_dir = (std::filesystem::path(dir_) / "gnuplot").string();
  if (options_.keep_gnuplot_files && !figures_.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(kept_dir, ec);
    if (ec) throw Error(kept_dir + ": cannot create: " + ec.message());
  }
  for (RenderedFigure& figure : figures_) {
    const std::string& name = figure.spec.name;
    const std::string base = temp.path() + "/" + name;
    WriteFileAtomically(base + ".dat", figure.spec.data);
    WriteFileAtomically(base + ".gp", FigureScript(figure.spec, internal::GnuplotPath(base + ".svg"),
                                                   internal::GnuplotPath(base + ".dat")));
    if (options_.keep_gnuplot_files) {
      // Relative paths: the copy runs from its own folder, wherever the report is moved.
      WriteFileAtomically(kept_dir + "/" + name + ".dat", figure.spec.data);
      WriteFileAtomically(kept_dir + "/" + name + ".gp",
                          FigureScript(figure.spec, "'" + name + ".svg'", "'" + name + ".dat'"));
    }
    const internal::ProcessResult run =
        internal::RunGnuplotScript(gnuplot_path_, base + ".gp", base + ".err", options_.gnuplot_timeout_s);
    if (!run.ok) {
      figure.error = run.error_text;
      Warn("figure " + figure.spec.name + " was not drawn: " + run.error_text);
      continue;
    }
    std::string svg;
    try {
      svg = ReadFile(base + ".svg");
    } catch (const Error& e) {
      figure.error = e.what();
    }
    if (svg.find("<svg") == std::string::npos || svg.find("</svg>") == std::string::npos) {
      figure.error = "gnuplot produced no complete SVG";
      Warn("figure " + figure.spec.name + " was not drawn: " + figure.error);
      continue;
    }
    figure.svg = std::move(svg);
  }
}

std::string ReportBuilder::FlightsSection() const {
  if (input_.flights.empty()) return "";
  std::string html =
      "<h2 id=\"flights\">Flights</h2>\n<table><thead><tr><th>flight</th><th>role</th><th>log</th>"
      "<th>configuration</th><th class=\"num\">mass (kg)</th><th class=\"num\">duration (s)</th>"
      "<th class=\"num\">row samples</th><th class=\"num\">weight</th></tr></thead><tbody>\n";
  for (const ReportFlight& f : input_.flights) {
    const ProcessedFlight& p = *f.flight;
    const double duration = p.t_s.size() > 1 ? p.t_s[p.t_s.size() - 1] - p.t_s[0] : 0.0;
    html += "<tr><td>" + Html(f.label) + "</td><td>" +
            (f.held_out ? "<span class=\"tag held\">held-out</span>" : "<span class=\"tag\">identification</span>") +
            "</td><td><code>" + Html(p.source) + "</code></td><td>" + Html(p.vehicle.name) + "</td><td class=\"num\">" +
            General(p.vehicle.mass_kg) + "</td><td class=\"num\">" + FormatValue("%.1f", duration) +
            "</td><td class=\"num\">" + std::to_string(p.num_rows_samples()) + "</td><td class=\"num\">" +
            General(p.weight) + "</td></tr>\n";
  }
  return html + "</tbody></table>\n" + InputFlightsTable();
}

std::string ReportBuilder::InputFlightsTable() const {
  if (input_.inputs.empty() && input_.validate_inputs.empty()) return "";
  // Identification flights, then the held-out ones; each as input.flights[] records it.
  std::vector<std::pair<std::string, json>> flights;
  for (const FlightInputSummary& f : input_.inputs) flights.emplace_back("identification", FlightInputJson(f));
  for (const FlightInputSummary& f : input_.validate_inputs) flights.emplace_back("held-out", FlightInputJson(f));
  // The columns are what the command recorded per log (INTERFACE.md: file, format, span, rates,
  // rotor signal, columns or topics, segments).
  std::vector<std::string> keys;
  for (const auto& [role, f] : flights)
    for (const auto& item : f.items())
      if (std::find(keys.begin(), keys.end(), item.key()) == keys.end()) keys.push_back(item.key());
  std::string html =
      "<h3>What was read</h3>\n<div class=\"scroll\"><table id=\"input_flights\"><thead><tr><th>role</th>";
  for (const std::string& key : keys) html += "<th>" + Html(key) + "</th>";
  html += "</tr></thead><tbody>\n";
  for (const auto& [role, f] : flights) {
    html += "<tr><td>" + role + "</td>";
    for (const std::string& key : keys)
      html += "<td class=\"small\">" + (f.contains(key) ? InputCell(f[key]) : "&ndash;") + "</td>";
    html += "</tr>\n";
  }
  return html + "</tbody></table></div>\n";
}

std::string ReportBuilder::ChecksSection() const {
  if (!input_.checks) return "";
  std::string rows;
  int not_ok = 0;
  for (const Check& check : internal::ChecksFailuresFirst(*input_.checks)) {
    not_ok += check.status != CheckStatus::kOk;
    const char* cls = check.status == CheckStatus::kOk ? "yes" : check.status == CheckStatus::kWarning ? "warn" : "bad";
    rows += "<tr><td><code>" + Html(check.name) + "</code></td><td><span class=\"tag " + cls + "\">" +
            Html(CheckStatusName(check.status)) + "</span></td><td>" + Html(check.message) + "</td></tr>\n";
  }
  const std::string summary = not_ok ? "<div class=\"box bad\">" + std::to_string(not_ok) + " plausibility check" +
                                           (not_ok > 1 ? "s" : "") + " did not pass (listed first).</div>\n"
                                     : "<div class=\"box ok\">Every plausibility check passed.</div>\n";
  return "<h2 id=\"checks\">Plausibility checks</h2>\n" + summary +
         "<table id=\"checks_table\"><thead><tr><th>check</th><th>status</th><th>message</th></tr></thead><tbody>\n" +
         rows + "</tbody></table>\n";
}

std::string ReportBuilder::WarningsSection() const {
  // The analysis's warnings, from the results that carry them, and the report's own.
  std::vector<std::string> analysis = input_.warnings;
  auto collect = [&](const std::vector<std::string>& list, const std::string& prefix) {
    for (const std::string& w : list) analysis.push_back(prefix + w);
  };
  if (input_.diagnosis) collect(input_.diagnosis->warnings, "");
  if (input_.linear) collect(input_.linear->warnings, "linear: ");
  if (input_.refined) collect(input_.refined->warnings, "refined: ");
  std::string html = "<h2 id=\"warnings\">Warnings</h2>\n";
  if (analysis.empty() && warnings_.empty())
    return html + "<div class=\"box ok\">No warnings: the identification reported nothing suspicious.</div>\n";
  if (!analysis.empty()) {
    html += "<div class=\"box bad\"><strong>From the analysis</strong><ul>\n";
    for (const std::string& w : analysis) html += "<li>" + Html(w) + "</li>\n";
    html += "</ul></div>\n";
  }
  if (!warnings_.empty()) {
    html += "<div class=\"box\"><strong>About this report</strong><ul>\n";
    for (const std::string& w : warnings_) html += "<li>" + Html(w) + "</li>\n";
    html += "</ul></div>\n";
  }
  return html;
}

// The cells of one parameter in one block: value, std, %sigma, essential (with why it was
// discarded on hover); `value`/`std_value` return what was shown for the change/sigma column.
std::string ReportBuilder::ParameterCells(const ParameterBlock& b, const std::string& name,
                                          std::optional<double>* value, std::optional<double>* std_value,
                                          bool* discarded) const {
  *value = std::nullopt;
  *std_value = std::nullopt;
  *discarded = false;
  std::optional<double> rel;
  std::string essential_cell = "&ndash;";
  if (const std::optional<ParameterStatistics> p = b.Statistics(name)) {
    *value = Finite(p->value);
    *std_value = Finite(p->std);
    rel = Finite(p->rel_std_pct);
    *discarded = !p->essential;
    // What the parameter looked like when it was dropped (only parameters the selection dropped
    // carry it; fixed ones do not).
    std::string why;
    if (p->discarded && std::isfinite(p->discarded->value))
      why = "estimate when discarded: " + FormatValue("%.4g", p->discarded->value);
    if (p->discarded && !p->discarded->most_correlated.empty())
      why += std::string(why.empty() ? "" : "; ") + "most correlated with " + p->discarded->most_correlated +
             (std::isfinite(p->discarded->correlation) ? " (r = " + FormatValue("%.3f", p->discarded->correlation) + ")"
                                                       : "");
    essential_cell = *discarded ? "<span class=\"tag nope\"" + (why.empty() ? "" : " title=\"" + Html(why) + "\"") +
                                      ">discarded</span>"
                                : "<span class=\"tag yes\">yes</span>";
  } else if (b.set) {
    const auto it = b.set->values.find(name);
    if (it != b.set->values.end()) *value = it->second;
  }
  const std::string cls = *discarded ? "num no" : "num";
  return "<td class=\"" + cls + " sep\">" + Sci(*value) + "</td><td class=\"" + cls + "\">" + Sci(*std_value) +
         "</td><td class=\"" + cls + "\">" + Pct(rel) + "</td><td>" + essential_cell + "</td>";
}

std::string ReportBuilder::ParametersSection() const {
  if (blocks_.empty()) return "";
  std::vector<std::string> names;
  for (const ParameterBlock& b : blocks_) {
    if (b.solution) names.insert(names.end(), b.names->begin(), b.names->end());
    if (b.set)
      for (const auto& item : b.set->values) names.push_back(item.first);
  }
  std::sort(names.begin(), names.end(), ParameterLess);
  names.erase(std::unique(names.begin(), names.end()), names.end());
  std::string html =
      "<h2 id=\"parameters\">Parameters</h2>\n<p>SI units (kg m, kg m&sup2;, N s&sup2;, N m s&sup2;). "
      "<em>%&sigma;</em> is the standard deviation in percent of the value (the paper's %&sigma;); a parameter "
      "that is not essential was discarded (held at 0) because the data cannot tell it apart from the others. "
      "<em>change/&sigma;</em> is the difference to the first set in units of the first set's standard "
      "deviation.</p>\n<table id=\"parameters_table\"><thead><tr><th rowspan=\"2\">parameter</th>";
  for (size_t k = 0; k < blocks_.size(); ++k)
    html +=
        "<th class=\"group sep\" colspan=\"" + std::string(k ? "5" : "4") + "\">" + Html(blocks_[k].label) + "</th>";
  html += "</tr><tr>";
  for (size_t k = 0; k < blocks_.size(); ++k)
    html += std::string(
                "<th class=\"num sep\">value</th><th class=\"num\">std</th><th class=\"num\">%&sigma;</th>"
                "<th>essential</th>") +
            (k ? "<th class=\"num\">change/&sigma;</th>" : "");
  html += "</tr></thead><tbody>\n";
  for (const std::string& name : names) {
    html += "<tr><td><code>" + Html(name) + "</code></td>";
    std::optional<double> first_value, first_std;
    for (size_t k = 0; k < blocks_.size(); ++k) {
      std::optional<double> value, std_value;
      bool discarded = false;
      html += ParameterCells(blocks_[k], name, &value, &std_value, &discarded);
      if (k == 0) {
        first_value = value;
        first_std = std_value;
      } else {
        const bool comparable = value && first_value && first_std && *first_std > 0.0 && !discarded;
        html += "<td class=\"num\">" +
                (comparable ? FormatValue("%+.2f", (*value - *first_value) / *first_std) : std::string("&ndash;")) +
                "</td>";
      }
    }
    html += "</tr>\n";
  }
  return html + "</tbody></table>\n" + EffectsTable();
}

// The effect parameters of the refined result, each in its unit, in name order (as refined.effects
// lists them).
std::string ReportBuilder::EffectsTable() const {
  if (!input_.refined) return "";
  const RefineResult& refined = *input_.refined;
  std::vector<EffectParameterEstimate> estimates =
      EffectParameterEstimates(refined.effects, refined.effects_std, refined.enabled, refined.on_bound);
  std::sort(estimates.begin(), estimates.end(),
            [](const EffectParameterEstimate& a, const EffectParameterEstimate& b) { return a.name < b.name; });
  std::string rows;
  for (const EffectParameterEstimate& e : estimates) {
    // Effects that were not estimated are held at their initial value: say so rather than "0 +- 0".
    const std::vector<double> value(e.value.data(), e.value.data() + e.value.size());
    const std::vector<double> std_dev =
        e.enabled ? std::vector<double>(e.std.data(), e.std.data() + e.std.size()) : std::vector<double>();
    rows += "<tr><td><code>" + Html(e.name) + "</code></td><td class=\"num" + std::string(e.enabled ? "" : " no") +
            "\">" + internal::ValueWithStd(value, std_dev, internal::EffectParameterUnit(e.name)) + "</td><td>" +
            (e.enabled ? (e.on_bound ? "<span class=\"tag warn\">on its bound</span>"
                                     : "<span class=\"tag yes\">estimated</span>")
                       : "<span class=\"tag nope\">not estimated</span>") +
            (e.enabled && !e.held.empty() ? " <span class=\"tag nope\">" + Html(Join(e.held, ", ")) + " held</span>"
                                          : std::string()) +
            "</td></tr>\n";
  }
  if (rows.empty()) return "";
  return "<h3>Unmodelled effects (refined)</h3>\n<table id=\"effects_table\"><thead><tr><th>effect parameter</th>"
         "<th class=\"num\">value &plusmn; std</th><th></th></tr></thead><tbody>\n" +
         rows + "</tbody></table>\n";
}

std::string ReportBuilder::RelativeErrorSection() const {
  std::string rows;
  // Per flight, computed here with each parameter set (and its effects).
  for (size_t f = 0; f < input_.flights.size(); ++f) {
    for (size_t s = 0; s < input_.parameter_sets.size(); ++s) {
      const std::optional<WrenchSplit>& split = splits_[f][s];
      if (!split) continue;
      const Eigen::Vector3d mean_force = split->error.leftCols<3>().colwise().mean().transpose();
      rows += "<tr><td>" + Html(input_.flights[f].label) + "</td><td>" +
              (input_.flights[f].held_out ? "<span class=\"tag held\">held-out</span>"
                                          : "<span class=\"tag\">identification</span>") +
              "</td><td>" + Html(input_.flights[f].flight->vehicle.name) + "</td><td>" +
              Html(input_.parameter_sets[s].label) + "</td>" + ComponentCells(split->relative_error_pct, {2, 3, 4, 5}) +
              "<td class=\"num sep\">" + FormatValue("%+.3f", mean_force[0]) + "</td><td class=\"num\">" +
              FormatValue("%+.3f", mean_force[1]) + "</td><td class=\"num\">" + FormatValue("%+.3f", mean_force[2]) +
              "</td></tr>\n";
    }
  }
  // All flights together, as the command computed them.
  std::string combined;
  auto add = [&](const RelativeErrorRow& row) {
    combined += "<tr><td>" + Html(row.data) + "</td><td>" + Html(row.parameters) + "</td>" +
                ComponentCells(row.relative_error_pct, kRotorComponents) + "</tr>\n";
  };
  if (input_.linear) add({"identification flights", "linear", input_.linear->relative_error_pct});
  if (input_.refined) add({"identification flights", "refined", input_.refined->relative_error_pct});
  for (const RelativeErrorRow& row : input_.relative_errors) add(row);
  if (rows.empty() && combined.empty()) return "";
  std::string html =
      "<h2 id=\"table3\">Relative errors (the paper's Table III)</h2>\n<p>||&rho;<sub>j</sub>|| / "
      "||W<sub>k</sub>&chi;<sub>k</sub>(j)|| in percent per wrench component: the size of the equation error "
      "relative to the rotor wrench. Fx and Fy have no rotor wrench (left out), nor has Mz when k<sub>d</sub> is "
      "not identified. The paper's cross-validation reached about 4&ndash;10 % on Fz, 10&ndash;47 % on Mx, My and "
      "45&ndash;68 % on Mz. The mean force error is the average of &rho; over the flight: far from zero means a "
      "systematic force error (accelerometer bias, a wrong mass, a misplaced IMU).</p>\n";
  if (!rows.empty())
    html +=
        "<table id=\"table3_flights\"><thead><tr><th>flight</th><th>role</th><th>configuration</th>"
        "<th>parameters</th>" +
        ComponentHeader({2, 3, 4, 5}) +
        "<th class=\"num sep\">mean Fx error (N)</th><th class=\"num\">mean Fy (N)</th>"
        "<th class=\"num\">mean Fz (N)</th></tr></thead><tbody>\n" +
        rows + "</tbody></table>\n";
  if (!combined.empty())
    html +=
        "<h3>All flights together (from the command's report)</h3>\n<table id=\"table3_combined\"><thead><tr>"
        "<th>data</th>"
        "<th>parameters</th>" +
        ComponentHeader({2, 3, 4, 5}) + "</tr></thead><tbody>\n" + combined + "</tbody></table>\n";
  return html;
}

std::string ReportBuilder::FigureHtml(const std::string& name) const {
  for (const RenderedFigure& f : figures_) {
    if (f.spec.name != name) continue;
    std::string html = "<figure id=\"" + Html(name) + "\">\n<h3>" + Html(f.spec.title) + "</h3>\n";
    if (!f.svg.empty())
      html += InlineSvg(f.svg, name + "_") + "\n";
    else if (!f.error.empty())
      html += "<div class=\"box\">Not drawn: " + Html(f.error) + "</div>\n";
    else
      html += "<div class=\"box\">Not drawn: gnuplot is not installed.</div>\n";
    html += "<figcaption>" + Html(f.spec.caption) +
            (f.svg.empty() ? "" : " File: <code>" + Html(name) + ".svg</code>.") + "</figcaption>\n</figure>\n";
    return html;
  }
  return "";
}

std::string ReportBuilder::WrenchSection() const {
  std::string html;
  for (const RenderedFigure& f : figures_)
    if (f.spec.name.rfind("fig_wrench_", 0) == 0) html += FigureHtml(f.spec.name);
  if (html.empty()) return "";
  return "<h2 id=\"wrench\">Rigid body against rotor model (the paper's Fig. 3 and 4)</h2>\n" + html;
}

std::string ReportBuilder::SpectrumSection() const {
  std::string html = FigureHtml("fig_spectrum_identification") + FigureHtml("fig_spectrum_held_out");
  if (html.empty()) return "";
  return "<h2 id=\"spectra\">Residual spectra</h2>\n" + html;
}

std::string ReportBuilder::AblationSection() const {
  if (!input_.ablation) return "";
  const std::vector<AblationEntry>& rows = input_.ablation->entries;
  const bool any_held_out = std::any_of(
      rows.begin(), rows.end(), [](const AblationEntry& entry) { return !entry.held_out_relative_error_pct.empty(); });
  std::string html =
      "<h2 id=\"ablation\">Ablation</h2>\n<table id=\"ablation_table\"><thead><tr><th rowspan=\"2\">effects</th>"
      "<th class=\"num\" rowspan=\"2\">parameters</th><th class=\"num\" rowspan=\"2\">AIC</th>"
      "<th class=\"num\" rowspan=\"2\">BIC</th><th class=\"group sep\" colspan=\"4\">identification (%)</th>" +
      std::string(any_held_out ? "<th class=\"group sep\" colspan=\"4\">held-out (%)</th>" : "") + "</tr><tr>" +
      ComponentHeader(kRotorComponents) + (any_held_out ? ComponentHeader(kRotorComponents) : "") +
      "</tr></thead><tbody>\n";
  for (const AblationEntry& entry : rows)
    html += "<tr><td>" + Html(AblationLabel(entry)) + "</td><td class=\"num\">" + std::to_string(entry.num_parameters) +
            "</td><td class=\"num\">" + General(entry.aic) + "</td><td class=\"num\">" + General(entry.bic) + "</td>" +
            ComponentCells(entry.relative_error_pct, kRotorComponents) +
            (any_held_out ? ComponentCells(entry.held_out_relative_error_pct, kRotorComponents) : "") + "</tr>\n";
  html += "</tbody></table>\n";
  return html + FigureHtml("fig_ablation");
}

std::string ReportBuilder::SettingsSection() const {
  std::vector<std::pair<std::string, std::string>> settings = input_.settings;
  if (!input_.command.empty()) settings.emplace_back("command", input_.command);
  if (!input_.rotorid_version.empty()) settings.emplace_back("rotorid_version", input_.rotorid_version);
  if (settings.empty()) return "";
  std::string html = "<h2 id=\"settings\">Run settings</h2>\n<table><tbody>\n";
  for (const auto& [key, value] : settings)
    html += "<tr><th><code>" + Html(key) + "</code></th><td>" + Html(value) + "</td></tr>\n";
  return html + "</tbody></table>\n";
}

std::string ReportBuilder::Page() const {
  // Answer first (what was found, the checks in one line with failures first, the next step), then a
  // diagnosis's verdict, then the evidence; the full checks table near the end.
  const std::string diagnosis =
      input_.diagnosis
          ? internal::DiagnosisHtml(*input_.diagnosis, [this](const std::string& name) { return FigureHtml(name); })
          : "";
  const std::string sections[] = {internal::AnswerHtml(input_),
                                  diagnosis,
                                  FlightsSection(),
                                  WarningsSection(),
                                  ParametersSection(),
                                  FigureHtml("fig_parameters"),
                                  RelativeErrorSection(),
                                  WrenchSection(),
                                  SpectrumSection(),
                                  AblationSection(),
                                  ChecksSection(),
                                  SettingsSection()};
  std::time_t now = std::time(nullptr);
  char stamp[64] = "";
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n<title>" +
      Html(input_.title) + "</title>\n<style>" + kCss + "</style>\n</head>\n<body>\n<main>\n";
  html += "<h1>" + Html(input_.title) + "</h1>\n<div class=\"meta\">rotorid";
  if (!input_.rotorid_version.empty()) html += " " + Html(input_.rotorid_version);
  if (!input_.command.empty()) html += " &middot; command <code>" + Html(input_.command) + "</code>";
  html += " &middot; written " + Html(stamp) + "</div>\n<nav>";
  const std::pair<const char*, const char*> links[] = {
      {"answer", "Answer"},         {"diagnosis", "Diagnosis"},      {"flights", "Flights"},  {"warnings", "Warnings"},
      {"parameters", "Parameters"}, {"fig_parameters", "Estimates"}, {"table3", "Table III"}, {"wrench", "Fig. 3/4"},
      {"spectra", "Spectra"},       {"ablation", "Ablation"},        {"checks", "Checks"},    {"settings", "Settings"}};
  for (const auto& [id, text] : links) {
    const std::string anchor = std::string("id=\"") + id + "\"";
    for (const std::string& s : sections)
      if (s.find(anchor) != std::string::npos) {
        html += std::string("<a href=\"#") + id + "\">" + text + "</a>";
        break;
      }
  }
  html += "</nav>\n";
  if (gnuplot_path_.empty())
    html +=
        "<div class=\"box bad\">gnuplot was not found, so this report has no figures; the tables are complete. "
        "Install it (Debian/Ubuntu: <code>apt-get install gnuplot-nox</code>) and run the command again.</div>\n";
  for (const std::string& s : sections) html += s;
  html +=
      "<p class=\"small\">Figures drawn with gnuplot; every figure is also a separate SVG file beside this "
      "report.</p>\n</main>\n</body>\n</html>\n";
  return html;
}

ReportSummary ReportBuilder::Build() {
  for (const ReportFlight& f : input_.flights)
    if (!f.flight) throw Error("report: flight '" + f.label + "' has no data (null ProcessedFlight)");
  if (input_.refined && !input_.linear)
    throw Error("report: a refined result needs its linear result (its parameters)");
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec || !std::filesystem::is_directory(dir_))
    throw Error(dir_ + ": cannot create the report folder" + (ec ? ": " + ec.message() : std::string()));

  if (!options_.gnuplot.empty()) {
    gnuplot_path_ = internal::FindExecutable(options_.gnuplot);
    if (gnuplot_path_.empty())
      Warn("gnuplot ('" + options_.gnuplot +
           "') was not found: the report has tables but no figures "
           "(install gnuplot-nox)");
  }
  ComputeSplits();
  CollectParameterBlocks();
  CollectMarks();
  RenderFigures(gnuplot_path_.empty() ? std::vector<FigureSpec>() : FigureSpecs());

  // Composed before any file is written, so that a failure leaves the folder as it was.
  const std::string page = Page();
  ReportSummary summary;
  // Figures an earlier report wrote here would be mistaken for this run's: they go, unless the user
  // changed them; a file the user changed is not written over either (internal::ReportFiles).
  internal::ReportFiles files(dir_);
  for (const RenderedFigure& f : figures_)
    if (!f.svg.empty()) summary.figure_paths.push_back(files.Write(f.spec.name + ".svg", f.svg, &warnings_));
  summary.figures_drawn = !gnuplot_path_.empty() && summary.figure_paths.size() == figures_.size();
  summary.html_path = files.Write("report.html", page, &warnings_);
  files.RemoveStaleAndSave();
  summary.warnings = warnings_;
  if (options_.print_warnings)
    for (const std::string& w : warnings_) std::cerr << "rotorid: report: " << w << "\n";
  return summary;
}

}  // namespace

std::string ReportOptions::Validate() const {
  if (!(gnuplot_timeout_s > 0.0)) return "ReportOptions.gnuplot_timeout_s must be positive";
  if (max_points_per_series < 10) return "ReportOptions.max_points_per_series must be at least 10";
  if (!(zoom_window_s >= 0.0)) return "ReportOptions.zoom_window_s must be 0 (no zoom) or positive";
  if (max_spectrum_segment < 16 || (max_spectrum_segment & (max_spectrum_segment - 1)) != 0)
    return "ReportOptions.max_spectrum_segment must be a power of two >= 16";
  return "";
}

ReportSummary WriteHtmlReport(const std::string& dir, const ReportInput& input, const ReportOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  if (dir.empty()) throw Error("report: no folder given");
  return ReportBuilder(dir, input, options).Build();
}

std::vector<ReportFlight> ReportFlights(const std::vector<ProcessedFlight>& flights, bool held_out) {
  std::vector<ReportFlight> out;
  for (const ProcessedFlight& flight : flights) {
    const std::string file = std::filesystem::path(flight.source).filename().string();
    out.push_back({file.empty() ? flight.source : file, &flight, held_out});
  }
  return out;
}

std::vector<ReportFlight> ReportFlights(const std::vector<ProcessedFlight>& flights,
                                        const std::vector<ProcessedFlight>& held_out) {
  std::vector<ReportFlight> out = ReportFlights(flights, /*held_out=*/false);
  for (const ReportFlight& f : ReportFlights(held_out, /*held_out=*/true)) out.push_back(f);
  return out;
}

std::vector<ParameterSet> ParameterSetsFromReport(const json& report, const std::string& source) {
  std::vector<ParameterSet> sets;
  for (const char* block : {"linear", "refined"}) {
    if (!report.contains(block) || report[block].is_null()) continue;
    // Drawn with the values each model predicts with, as validate's JSON (a discarded inertia at its
    // predicts_with, not at 0).
    PredictedModel model = PredictedParameters(report, source, block);
    sets.push_back({block, std::move(model.values), model.effects});
  }
  return sets;
}

std::vector<std::pair<std::string, std::string>> SettingsRows(const json& settings) {
  std::vector<std::pair<std::string, std::string>> rows;
  Flatten(settings, "", &rows);
  return rows;
}

bool GnuplotAvailable(const std::string& gnuplot) { return !internal::FindExecutable(gnuplot).empty(); }

}  // namespace rotorid

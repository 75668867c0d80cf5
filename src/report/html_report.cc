#include "rotorid/report/html_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <utility>

#include "report/gnuplot.h"
#include "report/report_figures.h"
#include "report/spectrum.h"
#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/parameters.h"
#include "rotorid/report/refine_json.h"
#include "rotorid/report/wrench_split.h"

namespace rotorid {

using internal::FigureSpec;
using nlohmann::json;

namespace {

// ---------------------------------------------------------------------------------------------
// Tolerant JSON readers: the reports of refine, diagnose and ablate evolve; what is absent or of
// an unexpected type is simply not shown.

const json* At(const json& j, const std::string& key) {
  if (!j.is_object()) return nullptr;
  const auto it = j.find(key);
  return it == j.end() || it->is_null() ? nullptr : &*it;
}

const json* At(const json& j, std::initializer_list<const char*> path) {
  const json* node = &j;
  for (const char* key : path) {
    node = At(*node, key);
    if (!node) return nullptr;
  }
  return node;
}

// A number, or the "value" of a {"value": ...} object.
std::optional<double> AsNumber(const json* j) {
  if (!j) return std::nullopt;
  if (j->is_number()) return j->get<double>();
  if (j->is_object()) return AsNumber(At(*j, "value"));
  return std::nullopt;
}

// {"Fx": .., ..., "Mz": ..} as 6 optional values; empty when `j` is not such an object.
std::vector<std::optional<double>> Components(const json* j) {
  if (!j || !j->is_object()) return {};
  std::vector<std::optional<double>> out(kNumWrenchComponents);
  bool any_key = false;
  for (int c = 0; c < kNumWrenchComponents; ++c) {
    if (j->contains(kWrenchComponentNames[c])) any_key = true;
    out[c] = AsNumber(At(*j, kWrenchComponentNames[c]));
  }
  return any_key ? out : std::vector<std::optional<double>>();
}

std::string Str(const json& j) {
  if (j.is_string()) return j.get<std::string>();
  return j.dump();
}

// ---------------------------------------------------------------------------------------------
// HTML text.

std::string Html(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Format(const char* format, double v) {
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), format, v);
  return buffer;
}

// Parameter values: 4 significant digits in scientific notation, as the paper's tables.
std::string Sci(std::optional<double> v) { return v && std::isfinite(*v) ? Format("%.4e", *v) : "&ndash;"; }
std::string Pct(std::optional<double> v, int digits = 2) {
  if (!v || !std::isfinite(*v)) return "&ndash;";
  return Format(digits == 1 ? "%.1f" : "%.2f", *v);
}
std::string General(double v) { return std::isfinite(v) ? Format("%.4g", v) : "&ndash;"; }

// A value or a vector of values, each with its std: "0.0102 &plusmn; 0.0003".
std::string ValueWithStd(const json* value, const json* std_value) {
  auto one = [](const json* v) -> std::optional<double> {
    return v && v->is_number() ? std::optional(v->get<double>()) : std::nullopt;
  };
  if (!value) return "&ndash;";
  if (value->is_array()) {
    std::string out = "[";
    for (size_t k = 0; k < value->size(); ++k) {
      const json* s = std_value && std_value->is_array() && k < std_value->size() ? &(*std_value)[k] : nullptr;
      out += (k ? ", " : "") + ValueWithStd(&(*value)[k], s);
    }
    return out + "]";
  }
  const std::optional<double> v = one(value), s = one(std_value);
  if (!v) return Html(Str(*value));
  return General(*v) + (s ? " &plusmn; " + General(*s) : "");
}

// {"value": .., "std": ..}, or {"name": {"value", "std"}, ...}, or anything else dumped.
std::string Magnitude(const json* m) {
  if (!m) return "&ndash;";
  if (m->is_object() && m->contains("value")) return ValueWithStd(At(*m, "value"), At(*m, "std"));
  if (m->is_object()) {
    std::string out;
    for (const auto& [key, entry] : m->items())
      out += (out.empty() ? "" : "; ") + Html(key) + " = " +
             (entry.is_object() ? ValueWithStd(At(entry, "value"), At(entry, "std")) : ValueWithStd(&entry, nullptr));
    return out;
  }
  return ValueWithStd(m, nullptr);
}

std::string ComponentHeader(const std::vector<int>& components) {
  std::string out;
  for (const int c : components) out += "<th class=\"num\">" + std::string(kWrenchComponentNames[c]) + "</th>";
  return out;
}

std::string ComponentCells(const std::vector<std::optional<double>>& values, const std::vector<int>& components) {
  std::string out;
  for (const int c : components)
    out += "<td class=\"num\">" + Pct(c < static_cast<int>(values.size()) ? values[c] : std::nullopt) + "</td>";
  return out;
}

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

// Dotted keys of every scalar (or array of scalars) below `j`.
void Flatten(const json& j, const std::string& prefix, std::vector<std::pair<std::string, std::string>>* out) {
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) Flatten(value, prefix.empty() ? key : prefix + "." + key, out);
  } else {
    out->emplace_back(prefix, j.is_string() ? j.get<std::string>() : j.dump());
  }
}

// A generic table for an array of flat objects (the union of their keys as columns).
std::string ObjectArrayTable(const json& array) {
  std::vector<std::string> keys;
  for (const json& row : array)
    if (row.is_object())
      for (const auto& [key, value] : row.items())
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  if (keys.empty()) return "<p>" + Html(array.dump()) + "</p>\n";
  std::string html = "<table><thead><tr>";
  for (const std::string& key : keys) html += "<th>" + Html(key) + "</th>";
  html += "</tr></thead><tbody>\n";
  for (const json& row : array) {
    html += "<tr>";
    for (const std::string& key : keys) {
      const json* v = At(row, key);
      if (v && v->is_number()) {
        html += "<td class=\"num\">" + General(v->get<double>()) + "</td>";
      } else if (const std::vector<std::optional<double>> c = Components(v); !c.empty()) {
        // Per-component values in one cell: "Fz 1.2 · Mx 3.4", undefined ones left out.
        std::string cell;
        for (int j = 0; j < kNumWrenchComponents; ++j)
          if (c[j])
            cell += (cell.empty() ? "" : " &middot; ") + std::string(kWrenchComponentNames[j]) + " " + General(*c[j]);
        html += "<td class=\"small\">" + (cell.empty() ? std::string("&ndash;") : cell) + "</td>";
      } else {
        html += "<td>" + (v ? Html(Str(*v)) : std::string("&ndash;")) + "</td>";
      }
    }
    html += "</tr>\n";
  }
  return html + "</tbody></table>\n";
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
      : dir_(dir),
        input_(input),
        options_(options),
        report_(input.report.is_object() ? input.report : json::object()) {}

  ReportSummary Build();

 private:
  // Data.
  void ComputeSplits();
  void CollectParameterBlocks();
  void CollectMarks();
  // Figures.
  std::vector<FigureSpec> FigureSpecs();
  void RenderFigures(std::vector<FigureSpec> specs);
  // Page.
  std::string Page() const;
  std::string FlightsSection() const;
  std::string WarningsSection() const;
  std::string ParametersSection() const;
  std::string RelativeErrorSection() const;
  std::string FigureHtml(const std::string& name) const;
  std::string WrenchSection() const;
  std::string SpectrumSection() const;
  std::string DiagnosisSection() const;
  std::string AblationSection() const;
  std::string SettingsSection() const;

  void Warn(const std::string& message) { warnings_.push_back(message); }
  std::vector<size_t> FlightsOfGroup(bool held_out) const;

  const std::string dir_;
  const ReportInput& input_;
  const ReportOptions& options_;
  const json report_;

  std::string gnuplot_path_;
  // splits_[flight][set]
  std::vector<std::vector<std::optional<WrenchSplit>>> splits_;
  // Parameter blocks of the table: label and the JSON "parameters" object (may be null).
  struct ParameterBlock {
    std::string label;
    const json* parameters = nullptr;
    const ParameterSet* set = nullptr;
  };
  std::vector<ParameterBlock> blocks_;
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

void ReportBuilder::CollectParameterBlocks() {
  std::set<std::string> seen;
  for (const ParameterSet& set : input_.parameter_sets) {
    if (!seen.insert(set.label).second) continue;
    const json* parameters = At(report_, {set.label.c_str(), "parameters"});
    blocks_.push_back({set.label, parameters && parameters->is_object() ? parameters : nullptr, &set});
  }
  // Blocks of the JSON that no parameter set stands for (e.g. a refine report given to identify).
  for (const char* label : {"linear", "refined"}) {
    const json* parameters = At(report_, {label, "parameters"});
    if (parameters && parameters->is_object() && seen.insert(label).second)
      blocks_.push_back({label, parameters, nullptr});
  }
}

// Time stretches ("where" of the diagnosis) to mark on the time axes, and frequency bands to mark
// on the spectra. Any array of objects under "where" with start/end times counts; a
// "flight"/"log"/"source" entry picks the flight, else every flight. Bands (low/high frequencies)
// are marked only from arrays named "worst..." or entries flagged "worst": a plain list of bands
// partitions the spectrum and would shade all of it.
void ReportBuilder::CollectMarks() {
  marks_.assign(input_.flights.size(), {});
  const json* where = At(report_, "where");
  if (!where) return;
  auto first_number = [](const json& o, std::initializer_list<const char*> keys) -> std::optional<double> {
    for (const char* key : keys)
      if (const std::optional<double> v = AsNumber(At(o, key))) return v;
    return std::nullopt;
  };
  auto flight_matches = [&](const json& o, size_t f) {
    for (const char* key : {"flight", "log", "source", "flight_label"}) {
      const json* id = At(o, key);
      if (!id) continue;
      if (id->is_number_integer()) {
        // An index counts among the held-out flights when there are any (the diagnosis's data).
        const std::vector<size_t> held = FlightsOfGroup(true);
        const std::vector<size_t>& pool = held.empty() ? FlightsOfGroup(false) : held;
        const int64_t k = id->get<int64_t>();
        return k >= 0 && static_cast<size_t>(k) < pool.size() && pool[k] == f;
      }
      if (id->is_string()) {
        const std::string name = id->get<std::string>();
        const ReportFlight& flight = input_.flights[f];
        const std::string source = flight.flight->source;
        return name == flight.label || name == source || std::filesystem::path(source).filename() == name ||
               std::filesystem::path(name).filename() == std::filesystem::path(source).filename();
      }
    }
    return true;
  };
  // Walk every array below "where", remembering the key it hangs from.
  std::vector<std::pair<const json*, std::string>> stack = {{where, "where"}};
  while (!stack.empty()) {
    const auto [node, node_key] = stack.back();
    stack.pop_back();
    if (node->is_object()) {
      for (const auto& item : node->items()) stack.emplace_back(&item.value(), item.key());
      continue;
    }
    if (!node->is_array()) continue;
    const bool worst_list = node_key.find("worst") != std::string::npos;
    for (const json& o : *node) {
      if (!o.is_object()) continue;
      const std::optional<double> start =
          first_number(o, {"start_s", "t_start_s", "t_start", "start", "begin_s", "from_s"});
      const std::optional<double> end = first_number(o, {"end_s", "t_end_s", "t_end", "end", "stop_s", "to_s"});
      if (start && end && *end > *start) {
        std::string label;
        for (const char* key : {"label", "phase", "kind", "component"})
          if (const json* l = At(o, key); l && l->is_string()) label = l->get<std::string>();
        for (size_t f = 0; f < input_.flights.size(); ++f)
          if (flight_matches(o, f)) marks_[f].push_back({*start, *end, label});
      }
      std::optional<double> low = first_number(o, {"low_hz", "f_low_hz", "from_hz", "min_hz"});
      std::optional<double> high = first_number(o, {"high_hz", "f_high_hz", "to_hz", "max_hz"});
      if (const json* band = At(o, "band_hz");
          band && band->is_array() && band->size() == 2 && (*band)[0].is_number() && (*band)[1].is_number()) {
        low = (*band)[0].get<double>();
        high = (*band)[1].get<double>();
      }
      const json* worst = At(o, "worst");
      const bool flagged = worst_list || (worst && worst->is_boolean() && worst->get<bool>());
      if (flagged && low && high && *high > *low) bands_hz_.emplace_back(*low, *high);
      stack.emplace_back(&o, node_key);
    }
  }
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
                                             options_.max_points_per_series);
    spec.title = title;
    spec.caption =
        "Per wrench component, the Newton-Euler wrench m D_m + D chi computed from the IMU (rigid body, blue) and "
        "the rotor model D_k chi_k computed from the rotor speeds (red); their difference rho, the equation error, "
        "is drawn in green against the right-hand axis. One column per parameter set. "
        "When the model holds, blue and red lie on top of each other and the error looks like noise without "
        "structure." +
        std::string(marks_[f].empty() ? "" : " Shaded: stretches the diagnosis points at.");
    if (!columns.empty()) specs.push_back(std::move(spec));
  }
  // (b) Residual spectra, identification and held-out flights separately.
  const std::optional<double> cutoff = AsNumber(At(report_, {"settings", "observation", "filter", "cutoff_hz"}));
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
  // (c) Parameters with error bars, from the JSON blocks that carry statistics.
  std::vector<std::string> labels;
  std::vector<const json*> parameter_objects;
  for (const ParameterBlock& b : blocks_)
    if (b.parameters) {
      labels.push_back(b.label);
      parameter_objects.push_back(b.parameters);
    }
  if (!parameter_objects.empty()) {
    std::vector<std::string> names;
    for (const auto& [name, entry] : parameter_objects[0]->items()) {
      const json* essential = At(entry, "essential");
      const std::optional<double> value = AsNumber(&entry);
      if ((!essential || !essential->is_boolean() || essential->get<bool>()) && value && *value != 0.0)
        names.push_back(name);
    }
    std::sort(names.begin(), names.end(), ParameterLess);
    std::vector<internal::ParameterPoint> points;
    for (const std::string& name : names) {
      internal::ParameterPoint p;
      p.name = name;
      for (const json* parameters : parameter_objects) {
        const json* entry = At(*parameters, name);
        p.value.push_back(entry ? AsNumber(entry) : std::nullopt);
        p.std.push_back(entry && entry->is_object() ? AsNumber(At(*entry, "std")) : std::nullopt);
      }
      points.push_back(std::move(p));
    }
    FigureSpec spec = internal::ParameterFigure("fig_parameters", labels, points);
    spec.title = "Parameter estimates";
    spec.caption = "Each essential parameter of the " + labels[0] +
                   " estimate, divided by that estimate, with error bars of 3 standard deviations; other sets are "
                   "divided by the same value so that every parameter shares one axis. A refined value outside the "
                   "linear error bar means the effects changed the estimate by more than its uncertainty.";
    specs.push_back(std::move(spec));
  }
  // (d) Diagnosis and ablation, when the report carries them.
  {
    std::vector<internal::GapSeries> gaps;
    if (auto v = Components(At(report_, {"baseline", "relative_error_pct"})); !v.empty())
      gaps.push_back({"baseline", v});
    std::vector<internal::RankedEffect> ranking;
    if (const json* r = At(report_, "ranking"); r && r->is_array()) {
      for (const json& entry : *r) {
        if (!entry.is_object()) continue;
        internal::RankedEffect effect;
        effect.effect = At(entry, "effect") ? Str(entry["effect"]) : "?";
        effect.shrink_pct = AsNumber(At(entry, "shrink_pct"));
        const json* significant = At(entry, "significant");
        effect.significant = significant && significant->is_boolean() && significant->get<bool>();
        ranking.push_back(effect);
        for (const char* key : {"held_out_relative_error_pct", "relative_error_pct"})
          if (auto v = Components(At(entry, key)); !v.empty()) {
            gaps.push_back({"+ " + effect.effect, v});
            break;
          }
      }
    }
    if (auto v = Components(At(report_, {"final", "relative_error_pct"})); !v.empty()) gaps.push_back({"final", v});
    if (!gaps.empty() || !ranking.empty()) {
      FigureSpec spec = internal::DiagnosisFigure("fig_diagnosis", gaps, ranking);
      spec.title = "Diagnosis";
      spec.caption =
          "Left: the held-out gap (Table III relative error) per component with the linear model (baseline), with "
          "each candidate effect when the report gives it, and with the selected effects (final). Right: how much of "
          "the held-out gap each effect removes; green bars passed the significance test that accounts for the "
          "parameters the effect adds.";
      specs.push_back(std::move(spec));
    }
  }
  if (const json* ablation = At(report_, "ablation"); ablation) {
    const json* rows = ablation->is_array() ? ablation : nullptr;
    if (!rows && ablation->is_object())
      for (const auto& item : ablation->items())
        if (item.value().is_array()) rows = &item.value();
    std::vector<internal::AblationRow> table;
    if (rows)
      for (const json& entry : *rows) {
        if (!entry.is_object()) continue;
        internal::AblationRow row;
        const json* effects = At(entry, "effects");
        if (effects && effects->is_array()) {
          for (const json& e : *effects) row.label += (row.label.empty() ? "" : "+") + Str(e);
        } else if (effects) {
          row.label = Str(*effects);
        }
        if (row.label.empty()) row.label = "none";
        row.identification = Components(At(entry, "relative_error_pct"));
        row.held_out = Components(At(entry, "held_out_relative_error_pct"));
        table.push_back(std::move(row));
      }
    if (!table.empty()) {
      FigureSpec spec = internal::AblationFigure("fig_ablation", table);
      spec.title = "Ablation";
      spec.caption =
          "Relative error per component for each combination of effects, on the identification flights "
          "and, when given, on held-out flights. An effect earns its place when it lowers the held-out "
          "bars, not only the identification ones.";
      specs.push_back(std::move(spec));
    }
  }
  return specs;
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
            General(p.vehicle.mass_kg) + "</td><td class=\"num\">" + Format("%.1f", duration) +
            "</td><td class=\"num\">" + std::to_string(p.num_rows_samples()) + "</td><td class=\"num\">" +
            General(p.weight) + "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

std::string ReportBuilder::WarningsSection() const {
  // The analysis's warnings (from the JSON, block by block) and the report's own.
  std::vector<std::string> analysis;
  auto collect = [&](const json* list, const std::string& prefix) {
    if (!list || !list->is_array()) return;
    for (const json& w : *list) analysis.push_back(prefix + Str(w));
  };
  collect(At(report_, "warnings"), "");
  if (report_.is_object())
    for (const auto& [key, value] : report_.items())
      if (value.is_object()) collect(At(value, "warnings"), key + ": ");
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

std::string ReportBuilder::ParametersSection() const {
  if (blocks_.empty()) return "";
  std::vector<std::string> names;
  for (const ParameterBlock& b : blocks_) {
    if (b.parameters)
      for (const auto& item : b.parameters->items()) names.push_back(item.key());
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
      "deviation.</p>\n<table><thead><tr><th rowspan=\"2\">parameter</th>";
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
      const ParameterBlock& b = blocks_[k];
      const json* entry = b.parameters ? At(*b.parameters, name) : nullptr;
      std::optional<double> value = entry ? AsNumber(entry) : std::nullopt;
      if (!value && b.set) {
        const auto it = b.set->values.find(name);
        if (it != b.set->values.end()) value = it->second;
      }
      const std::optional<double> std_value = entry && entry->is_object() ? AsNumber(At(*entry, "std")) : std::nullopt;
      const std::optional<double> rel =
          entry && entry->is_object() ? AsNumber(At(*entry, "rel_std_pct")) : std::nullopt;
      const json* essential = entry && entry->is_object() ? At(*entry, "essential") : nullptr;
      std::string essential_cell = "&ndash;";
      bool discarded = false;
      if (essential && essential->is_boolean()) {
        discarded = !essential->get<bool>();
        // What the parameter looked like when it was dropped, on hover.
        std::string why;
        if (const std::optional<double> estimate = AsNumber(At(*entry, "estimate_when_discarded")))
          why += "estimate when discarded: " + Format("%.4g", *estimate);
        if (const json* other = At(*entry, "most_correlated_with"); other && other->is_string() && !other->empty())
          why += std::string(why.empty() ? "" : "; ") + "most correlated with " + other->get<std::string>() +
                 (AsNumber(At(*entry, "correlation"))
                      ? " (r = " + Format("%.3f", *AsNumber(At(*entry, "correlation"))) + ")"
                      : std::string());
        essential_cell = discarded ? "<span class=\"tag nope\"" + (why.empty() ? "" : " title=\"" + Html(why) + "\"") +
                                         ">discarded</span>"
                                   : "<span class=\"tag yes\">yes</span>";
      }
      const std::string cls = discarded ? "num no" : "num";
      html += "<td class=\"" + cls + " sep\">" + Sci(value) + "</td><td class=\"" + cls + "\">" + Sci(std_value) +
              "</td><td class=\"" + cls + "\">" + Pct(rel) + "</td><td>" + essential_cell + "</td>";
      if (k == 0) {
        first_value = value;
        first_std = std_value;
      } else {
        const bool comparable = value && first_value && first_std && *first_std > 0.0 && !discarded;
        html += "<td class=\"num\">" +
                (comparable ? Format("%+.2f", (*value - *first_value) / *first_std) : std::string("&ndash;")) + "</td>";
      }
    }
    html += "</tr>\n";
  }
  html += "</tbody></table>\n";
  // Effect parameters of a refined block.
  for (const ParameterBlock& b : blocks_) {
    const json* effects = At(report_, {b.label.c_str(), "effects"});
    if (!effects || !effects->is_object() || effects->empty()) continue;
    html += "<h3>Unmodelled effects (" + Html(b.label) +
            ")</h3>\n<table><thead><tr><th>effect parameter</th>"
            "<th>value &plusmn; std</th></tr></thead><tbody>\n";
    for (const auto& [key, entry] : effects->items()) {
      // Effects that were not estimated are held at their initial value: say so rather than "0 +- 0".
      const json* enabled = At(entry, "enabled");
      const bool off = enabled && enabled->is_boolean() && !enabled->get<bool>();
      html += "<tr><td><code>" + Html(key) + "</code></td><td class=\"num" + std::string(off ? " no" : "") + "\">" +
              (entry.is_object() ? ValueWithStd(At(entry, "value"), off ? nullptr : At(entry, "std"))
                                 : ValueWithStd(&entry, nullptr)) +
              (off ? " (not estimated)" : "") + "</td></tr>\n";
    }
    html += "</tbody></table>\n";
  }
  return html;
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
              "<td class=\"num sep\">" + Format("%+.3f", mean_force[0]) + "</td><td class=\"num\">" +
              Format("%+.3f", mean_force[1]) + "</td><td class=\"num\">" + Format("%+.3f", mean_force[2]) +
              "</td></tr>\n";
    }
  }
  // All flights together, as the command computed them.
  std::string combined;
  auto add = [&](const std::string& what, const std::string& set, const json* values) {
    const std::vector<std::optional<double>> v = Components(values);
    if (v.empty()) return;
    combined +=
        "<tr><td>" + Html(what) + "</td><td>" + Html(set) + "</td>" + ComponentCells(v, {2, 3, 4, 5}) + "</tr>\n";
  };
  for (const char* block : {"linear", "refined"})
    add("identification flights", block, At(report_, {block, "relative_error_pct"}));
  for (const char* block : {"linear", "refined"})
    add("held-out flights", block, At(report_, {"held_out", block, "relative_error_pct"}));
  add("given flights", At(report_, "params") ? "from " + Str(report_["params"]) : "",
      At(report_, "relative_error_pct"));
  if (rows.empty() && combined.empty()) return "";
  std::string html =
      "<h2 id=\"table3\">Relative errors (the paper's Table III)</h2>\n<p>||&rho;<sub>j</sub>|| / "
      "||W<sub>k</sub>&chi;<sub>k</sub>(j)|| in percent per wrench component: the size of the equation error "
      "relative to the rotor wrench. Fx and Fy have no rotor wrench (left out), nor has Mz when k<sub>d</sub> is "
      "not identified. The paper's cross-validation reached about 4&ndash;10 % on Fz, 10&ndash;47 % on Mx, My and "
      "45&ndash;68 % on Mz. The mean force error is the average of &rho; over the flight: far from zero means a "
      "systematic force error (accelerometer bias, a wrong mass, a misplaced IMU).</p>\n";
  if (!rows.empty())
    html += "<table><thead><tr><th>flight</th><th>role</th><th>configuration</th><th>parameters</th>" +
            ComponentHeader({2, 3, 4, 5}) +
            "<th class=\"num sep\">mean Fx error (N)</th><th class=\"num\">mean Fy (N)</th>"
            "<th class=\"num\">mean Fz (N)</th></tr></thead><tbody>\n" +
            rows + "</tbody></table>\n";
  if (!combined.empty())
    html +=
        "<h3>All flights together (from the command's report)</h3>\n<table><thead><tr><th>data</th>"
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

std::string ReportBuilder::DiagnosisSection() const {
  const json* baseline = At(report_, "baseline");
  const json* ranking = At(report_, "ranking");
  const json* final_block = At(report_, "final");
  const json* where = At(report_, "where");
  const json* selected = At(report_, "selected");
  if (!baseline && !ranking && !final_block && !where && !selected) return "";
  std::string html = "<h2 id=\"diagnosis\">Diagnosis of the sim-to-real gap</h2>\n";
  if (selected && selected->is_array()) {
    std::string list;
    for (const json& s : *selected)
      list += (list.empty() ? "" : ", ") + Html(Str(s.is_object() && s.contains("effect") ? s["effect"] : s));
    html += "<p><strong>Selected effects:</strong> " + (list.empty() ? std::string("none") : list) + "</p>\n";
  }
  // Gap per component: baseline, per ranked effect when given, final.
  std::string gap_rows;
  auto gap_row = [&](const std::string& label, const json* values) {
    const std::vector<std::optional<double>> v = Components(values);
    if (!v.empty()) gap_rows += "<tr><td>" + Html(label) + "</td>" + ComponentCells(v, {2, 3, 4, 5}) + "</tr>\n";
  };
  gap_row("baseline (linear model)", At(report_, {"baseline", "relative_error_pct"}));
  if (ranking && ranking->is_array())
    for (const json& entry : *ranking)
      if (entry.is_object())
        gap_row("+ " + (At(entry, "effect") ? Str(entry["effect"]) : std::string("?")),
                At(entry, "held_out_relative_error_pct") ? At(entry, "held_out_relative_error_pct")
                                                         : At(entry, "relative_error_pct"));
  gap_row("final (selected effects)", At(report_, {"final", "relative_error_pct"}));
  if (!gap_rows.empty())
    html += "<h3>Held-out gap per component (%)</h3>\n<table><thead><tr><th>model</th>" +
            ComponentHeader({2, 3, 4, 5}) + "</tr></thead><tbody>\n" + gap_rows + "</tbody></table>\n";
  if (ranking && ranking->is_array() && !ranking->empty()) {
    html +=
        "<h3>Ranking of candidate effects</h3>\n<table><thead><tr><th class=\"num\">#</th><th>effect</th>"
        "<th>significant</th><th class=\"num\">shrink (%)</th><th>magnitude</th><th>details</th></tr></thead><tbody>\n";
    int rank = 0;
    for (const json& entry : *ranking) {
      if (!entry.is_object()) continue;
      const json* significant = At(entry, "significant");
      std::string details;
      for (const auto& [key, value] : entry.items())
        if (key != "effect" && key != "significant" && key != "shrink_pct" && key != "magnitude" &&
            !value.is_object() && !value.is_array())
          details += (details.empty() ? "" : ", ") + Html(key) + " = " +
                     (value.is_number() ? General(value.get<double>()) : Html(Str(value)));
      html +=
          "<tr><td class=\"num\">" + std::to_string(++rank) + "</td><td><code>" +
          Html(At(entry, "effect") ? Str(entry["effect"]) : "?") + "</code></td><td>" +
          (significant && significant->is_boolean() ? (significant->get<bool>() ? "<span class=\"tag yes\">yes</span>"
                                                                                : "<span class=\"tag nope\">no</span>")
                                                    : std::string("&ndash;")) +
          "</td><td class=\"num\">" + Pct(AsNumber(At(entry, "shrink_pct")), 1) + "</td><td>" +
          Magnitude(At(entry, "magnitude")) + "</td><td class=\"small\">" + details + "</td></tr>\n";
    }
    html += "</tbody></table>\n";
  }
  if (where) {
    html += "<h3>Where the gap is</h3>\n";
    std::vector<std::pair<std::string, std::string>> scalars;
    std::string tables;
    if (where->is_object()) {
      for (const auto& [key, value] : where->items()) {
        if (value.is_array() && !value.empty() && value[0].is_object())
          tables += "<p><strong>" + Html(key) + "</strong></p>\n" + ObjectArrayTable(value);
        else
          Flatten(value, key, &scalars);
      }
    } else {
      scalars.emplace_back("where", Str(*where));
    }
    if (!scalars.empty()) {
      html += "<table><tbody>\n";
      for (const auto& [key, value] : scalars)
        html += "<tr><th>" + Html(key) + "</th><td>" + Html(value) + "</td></tr>\n";
      html += "</tbody></table>\n";
    }
    html += tables;
  }
  html += FigureHtml("fig_diagnosis");
  return html;
}

std::string ReportBuilder::AblationSection() const {
  const json* ablation = At(report_, "ablation");
  if (!ablation) return "";
  const json* rows = ablation->is_array() ? ablation : nullptr;
  if (!rows && ablation->is_object())
    for (const auto& item : ablation->items())
      if (item.value().is_array()) rows = &item.value();
  std::string html = "<h2 id=\"ablation\">Ablation</h2>\n";
  if (!rows) return html + "<p>" + Html(ablation->dump()) + "</p>\n";
  bool any_held_out = false;
  for (const json& entry : *rows) any_held_out = any_held_out || At(entry, "held_out_relative_error_pct");
  const std::vector<int> comps = {2, 3, 4, 5};
  html +=
      "<table><thead><tr><th rowspan=\"2\">effects</th><th class=\"num\" rowspan=\"2\">parameters</th>"
      "<th class=\"num\" rowspan=\"2\">AIC</th><th class=\"num\" rowspan=\"2\">BIC</th>"
      "<th class=\"group sep\" colspan=\"4\">identification (%)</th>" +
      std::string(any_held_out ? "<th class=\"group sep\" colspan=\"4\">held-out (%)</th>" : "") + "</tr><tr>" +
      ComponentHeader(comps) + (any_held_out ? ComponentHeader(comps) : "") + "</tr></thead><tbody>\n";
  for (const json& entry : *rows) {
    if (!entry.is_object()) continue;
    std::string label;
    const json* effects = At(entry, "effects");
    if (effects && effects->is_array())
      for (const json& e : *effects) label += (label.empty() ? "" : " + ") + Str(e);
    else if (effects)
      label = Str(*effects);
    const std::optional<double> count = AsNumber(At(entry, "num_parameters"));
    html += "<tr><td>" + (label.empty() ? std::string("none") : Html(label)) + "</td><td class=\"num\">" +
            (count ? Format("%.0f", *count) : "&ndash;") + "</td><td class=\"num\">" +
            General(AsNumber(At(entry, "aic")).value_or(NAN)) + "</td><td class=\"num\">" +
            General(AsNumber(At(entry, "bic")).value_or(NAN)) + "</td>" +
            ComponentCells(Components(At(entry, "relative_error_pct")), comps) +
            (any_held_out ? ComponentCells(Components(At(entry, "held_out_relative_error_pct")), comps) : "") +
            "</tr>\n";
  }
  html += "</tbody></table>\n";
  return html + FigureHtml("fig_ablation");
}

std::string ReportBuilder::SettingsSection() const {
  std::vector<std::pair<std::string, std::string>> settings;
  if (const json* s = At(report_, "settings")) Flatten(*s, "", &settings);
  for (const char* key : {"command", "rotorid_version", "params"})
    if (const json* v = At(report_, key)) settings.emplace_back(key, Str(*v));
  if (settings.empty()) return "";
  std::string html = "<h2 id=\"settings\">Run settings</h2>\n<table><tbody>\n";
  for (const auto& [key, value] : settings)
    html += "<tr><th><code>" + Html(key) + "</code></th><td>" + Html(value) + "</td></tr>\n";
  return html + "</tbody></table>\n";
}

std::string ReportBuilder::Page() const {
  const std::string sections[] = {
      FlightsSection(),  WarningsSection(), ParametersSection(),          RelativeErrorSection(),
      WrenchSection(),   SpectrumSection(), FigureHtml("fig_parameters"), DiagnosisSection(),
      AblationSection(), SettingsSection()};
  std::time_t now = std::time(nullptr);
  char stamp[64] = "";
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n<title>" +
      Html(input_.title) + "</title>\n<style>" + kCss + "</style>\n</head>\n<body>\n<main>\n";
  html += "<h1>" + Html(input_.title) + "</h1>\n<div class=\"meta\">rotorid";
  if (const json* v = At(report_, "rotorid_version")) html += " " + Html(Str(*v));
  if (const json* c = At(report_, "command")) html += " &middot; command <code>" + Html(Str(*c)) + "</code>";
  html += " &middot; written " + Html(stamp) + "</div>\n<nav>";
  const std::pair<const char*, const char*> links[] = {
      {"flights", "Flights"},   {"warnings", "Warnings"}, {"parameters", "Parameters"},    {"table3", "Table III"},
      {"wrench", "Fig. 3/4"},   {"spectra", "Spectra"},   {"fig_parameters", "Estimates"}, {"diagnosis", "Diagnosis"},
      {"ablation", "Ablation"}, {"settings", "Settings"}};
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

  ReportSummary summary;
  std::set<std::string> written;
  for (const RenderedFigure& f : figures_) {
    if (f.svg.empty()) continue;
    const std::string path = (std::filesystem::path(dir_) / (f.spec.name + ".svg")).string();
    WriteFileAtomically(path, f.svg);
    summary.figure_paths.push_back(path);
    written.insert(f.spec.name + ".svg");
  }
  // Figures of an earlier report in this folder would be mistaken for this run's.
  for (const auto& entry : std::filesystem::directory_iterator(dir_, ec)) {
    const std::string file = entry.path().filename().string();
    if (file.rfind("fig_", 0) == 0 && entry.path().extension() == ".svg" && !written.count(file))
      std::filesystem::remove(entry.path(), ec);
  }
  summary.figures_drawn = !gnuplot_path_.empty() && summary.figure_paths.size() == figures_.size();
  summary.html_path = (std::filesystem::path(dir_) / "report.html").string();
  WriteFileAtomically(summary.html_path, Page());
  summary.warnings = warnings_;
  if (options_.print_warnings)
    for (const std::string& w : warnings_) std::cerr << "rotorid: report: " << w << "\n";
  return summary;
}

}  // namespace

std::string ReportOptions::Validate() const {
  if (!(gnuplot_timeout_s > 0.0)) return "ReportOptions.gnuplot_timeout_s must be positive";
  if (max_points_per_series < 10) return "ReportOptions.max_points_per_series must be at least 10";
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

std::vector<ParameterSet> ParameterSetsFromReport(const json& report) {
  std::vector<ParameterSet> sets;
  for (const char* block : {"linear", "refined"}) {
    const json* parameters = At(report, {block, "parameters"});
    if (!parameters || !parameters->is_object()) continue;
    ParameterSet set;
    set.label = block;
    for (const auto& [name, entry] : parameters->items())
      if (const std::optional<double> value = AsNumber(&entry)) set.values[name] = *value;
    if (set.values.empty()) continue;
    if (std::string(block) == "refined") set.effects = EffectsFromReport(report);
    sets.push_back(std::move(set));
  }
  return sets;
}

bool GnuplotAvailable(const std::string& gnuplot) { return !internal::FindExecutable(gnuplot).empty(); }

}  // namespace rotorid

#include "report/diagnosis_section.h"

#include <cmath>

#include "report/html_text.h"
#include "rotorid/core/error.h"
#include "rotorid/model/parameters.h"

namespace rotorid::internal {

namespace {

// The components with a rotor wrench, in the order the paper's tables give them.
const std::vector<int> kRotorComponents = {2, 3, 4, 5};
const std::vector<int> kAllComponents = {0, 1, 2, 3, 4, 5};

int ComponentIndex(const JsonNode& name) {
  const std::string text = name.String();
  for (int c = 0; c < kNumWrenchComponents; ++c)
    if (text == kWrenchComponentNames[c]) return c;
  throw Error("report JSON: '" + name.path() + "' is '" + text + "', not a wrench component (Fx .. Mz)");
}

std::string StatusTag(const std::string& status) {
  const char* cls = status == "selected" ? "yes" : status == "confounded" ? "warn" : "nope";
  return "<span class=\"tag " + std::string(cls) + "\">" + Html(status) + "</span>";
}

std::string BandLabel(const JsonNode& band) {
  return FormatValue("%.0f", band["low_hz"].Number()) + "&ndash;" + FormatValue("%.0f", band["high_hz"].Number()) + " Hz";
}

// "value ± std unit" per parameter of a ranking entry's magnitude, one per line.
std::string MagnitudeCell(const JsonNode& magnitude) {
  std::string out;
  for (const auto& [name, entry] : magnitude.Items())
    out += std::string(out.empty() ? "" : "<br/>") + "<code>" + Html(name) + "</code><br/>" +
           ValueWithStd(entry["value"].Numbers(), entry["std"].Numbers(), EffectParameterUnit(name));
  return out;
}

std::string DetectableCell(const JsonNode& detectable) {
  std::string out;
  for (const auto& [name, entry] : detectable.Items())
    out += std::string(out.empty() ? "" : "<br/>") + ValueWithStd(entry.Numbers(), {}, EffectParameterUnit(name));
  return out;
}

std::string RankingTable(const JsonNode& report) {
  std::string html =
      "<table id=\"diagnosis_ranking\"><thead><tr><th class=\"num\">#</th><th>effect</th><th>status</th>"
      "<th class=\"num\">held-out shrink (%)</th><th>magnitude (value &plusmn; std)</th><th>this data would reveal it "
      "above</th><th class=\"num\">F</th><th class=\"num\">p</th><th>note</th></tr></thead><tbody>\n";
  int rank = 0;
  for (const JsonNode& entry : report["ranking"].Elements()) {
    const JsonNode test = entry["test"];
    html += "<tr><td class=\"num\">" + std::to_string(++rank) + "</td><td><code>" + Html(entry["effect"].String()) +
            "</code></td><td>" + StatusTag(entry["status"].String()) + "</td><td class=\"num\">" +
            Pct(entry["shrink_pct"].Number()) + "</td><td class=\"num\">" + MagnitudeCell(entry["magnitude"]) +
            "</td><td class=\"num\">" + DetectableCell(entry["detectable_above"]) + "</td><td class=\"num\">" +
            General(test["f_statistic"].Number()) + "</td><td class=\"num\">" +
            FormatValue("%.2g", test["p_value"].Number()) + "</td><td class=\"small note\">" + Html(entry["note"].String()) +
            "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

// Held-out Table III per component: the linear model, after each kept effect, and the final model;
// then the noise floor and the part beyond it, and the residual in physical units.
std::string GapTables(const JsonNode& report) {
  const JsonNode baseline = report["baseline"], final_gap = report["final"];
  std::string rows;
  auto row = [&](const std::string& label, const std::vector<std::optional<double>>& values, const char* cls = "") {
    rows += std::string("<tr") + (*cls ? std::string(" class=\"") + cls + "\"" : "") + "><td>" + label + "</td>" +
            ComponentCells(values, kRotorComponents) + "</tr>\n";
  };
  row("linear model (baseline)", baseline["relative_error_pct"].Components());
  for (const JsonNode& step : report["steps"].Elements())
    row("+ <code>" + Html(step["added"].String()) + "</code>", step["after"]["relative_error_pct"].Components());
  row("with the selected effects (final)", final_gap["relative_error_pct"].Components(), "total");
  std::string html =
      "<p>The held-out relative error (the paper's Table III, ||&rho;|| / ||rotor wrench|| in %) per component, "
      "with the effects added one by one as the forward selection kept them.</p>\n"
      "<table id=\"diagnosis_gap\"><thead><tr><th>model</th>" +
      ComponentHeader(kRotorComponents, "%") + "</tr></thead><tbody>\n" + rows + "</tbody></table>\n";
  std::string split;
  for (const auto& [label, block] : {std::pair<const char*, JsonNode>{"baseline", baseline}, {"final", final_gap}}) {
    split += std::string("<tr><td>") + label + ": noise floor</td>" +
             ComponentCells(block["noise_floor_pct"].Components(), kAllComponents) + "</tr>\n";
    split += std::string("<tr><td>") + label + ": model error beyond it</td>" +
             ComponentCells(block["model_error_pct"].Components(), kAllComponents) + "</tr>\n";
  }
  html +=
      "<p>The same gap split into what sensor noise alone explains (noise floor) and the rest, the model error "
      "(Fx, Fy against the thrust, in %):</p>\n<table id=\"diagnosis_noise\"><thead><tr><th>held-out gap (%)</th>" +
      ComponentHeader(kAllComponents) + "</tr></thead><tbody>\n" + split + "</tbody></table>\n";
  std::string rms;
  for (const auto& [label, block] :
       {std::pair<const char*, JsonNode>{"linear model", baseline}, {"with the selected effects", final_gap}}) {
    rms += std::string("<tr><td>") + label + "</td>";
    const std::vector<std::optional<double>> v = block["residual_rms"].Components();
    for (const int c : kAllComponents) rms += "<td class=\"num\">" + FormatValue("%.4g", v[c].value_or(NAN)) + "</td>";
    rms += "</tr>\n";
  }
  std::string header;
  for (const int c : kAllComponents)
    header += "<th class=\"num\">" + std::string(kWrenchComponentNames[c]) + " (" + ComponentUnit(c) + ")</th>";
  html += "<table id=\"diagnosis_rms\"><thead><tr><th>held-out residual RMS</th>" + header + "</tr></thead><tbody>\n" +
          rms + "</tbody></table>\n";
  return html;
}

std::string BandTable(const JsonNode& where, int component) {
  const std::string unit = ComponentUnit(component);
  const std::string name = kWrenchComponentNames[component];
  std::string html = "<table id=\"diagnosis_bands\"><thead><tr><th>band</th><th class=\"num\">" + name +
                     " residual, linear (" + unit + " RMS)</th><th class=\"num\">with the selected effects (" + unit +
                     " RMS)</th><th class=\"num\">energy removed (%)</th><th class=\"num\">share of " + name +
                     "'s residual energy (%)</th><th class=\"num\">residual / rotor wrench in the band (%)</th>"
                     "</tr></thead><tbody>\n";
  for (const JsonNode& band : where["bands"].Elements()) {
    const double before = band["residual_rms"][name].Number(), after = band["final_residual_rms"][name].Number();
    const std::optional<double> removed =
        before > 0.0 ? std::optional(100.0 * (1.0 - after * after / (before * before))) : std::nullopt;
    html += "<tr><td class=\"num\">" + BandLabel(band) + "</td><td class=\"num\">" + FormatValue("%.4g", before) +
            "</td><td class=\"num\">" + FormatValue("%.4g", after) + "</td><td class=\"num\">" + Pct(removed, 1) +
            "</td><td class=\"num\">" + Pct(band["share_pct"][name].Number(), 1) + "</td><td class=\"num\">" +
            Pct(band["residual_to_model_pct"][name].NumberOrNull(), 1) + "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

std::string StretchTable(const JsonNode& where) {
  std::string html =
      "<table id=\"diagnosis_stretches\"><thead><tr><th>flight</th><th class=\"num\">from (s)</th>"
      "<th class=\"num\">to (s)</th><th class=\"num\">mean square / flight's</th><th>mostly</th>" +
      ComponentHeader(kRotorComponents, "%") +
      "<th class=\"num\">rates p/q/r (rad/s RMS)</th><th class=\"num\">mean vertical acc. (m/s&sup2;)</th>"
      "<th>doing</th></tr></thead><tbody>\n";
  for (const JsonNode& s : where["worst_stretches"].Elements()) {
    std::string rates;
    for (const double w : s["angular_velocity_rms"].Numbers())
      rates += (rates.empty() ? "" : " / ") + FormatValue("%.2f", w);
    std::string activities;
    for (const JsonNode& a : s["activities"].Elements())
      activities += (activities.empty() ? "" : ", ") + Html(a.String());
    const std::string flight = s["flight"].String();
    html += "<tr><td><code>" + Html(flight.substr(flight.find_last_of('/') + 1)) + "</code></td><td class=\"num\">" +
            FormatValue("%.1f", s["start_s"].Number()) + "</td><td class=\"num\">" + FormatValue("%.1f", s["end_s"].Number()) +
            "</td><td class=\"num\">" + FormatValue("%.2f", s["mean_square_ratio"].Number()) + "&times;</td><td>" +
            Html(s["dominant_component"].String()) + "</td>" +
            ComponentCells(s["relative_error_pct"].Components(), kRotorComponents) + "<td class=\"num\">" + rates +
            "</td><td class=\"num\">" + FormatValue("%+.2f", s["mean_vertical_acceleration_mps2"].Number()) + "</td><td>" +
            activities + "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

std::string ConfoundedTable(const JsonNode& report) {
  const std::vector<JsonNode> pairs = report["confounded"].Elements();
  if (pairs.empty()) return "";
  std::string html =
      "<h3>Effects the data cannot tell apart</h3>\n<table id=\"diagnosis_confounded\"><thead><tr><th>selected</th>"
      "<th>rival</th><th class=\"num\">shrink, selected (%)</th><th class=\"num\">shrink, rival (%)</th>"
      "<th class=\"num\">parameter correlation</th><th class=\"num\">t</th><th class=\"num\">p</th>"
      "<th>distinguishable</th><th>note</th></tr></thead><tbody>\n";
  for (const JsonNode& c : pairs) {
    const std::optional<double> correlation = c["correlation"].NumberOrNull();
    html += "<tr><td><code>" + Html(c["effects"][0].String()) + "</code></td><td><code>" +
            Html(c["effects"][1].String()) + "</code></td><td class=\"num\">" + Pct(c["shrink_pct"][0].Number()) +
            "</td><td class=\"num\">" + Pct(c["shrink_pct"][1].Number()) + "</td><td class=\"num\">" +
            (correlation ? FormatValue("%.3f", *correlation) : "&ndash;") + "</td><td class=\"num\">" +
            FormatValue("%.2f", c["t_statistic"].Number()) + "</td><td class=\"num\">" +
            FormatValue("%.2g", c["p_value"].Number()) + "</td><td>" + (c["distinguishable"].Bool() ? "yes" : "no") +
            "</td><td class=\"small note\">" + Html(c["note"].String()) + "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

}  // namespace

bool HasDiagnosis(const JsonNode& report) { return report.Has("ranking"); }

std::vector<std::pair<double, double>> WorstBands(const JsonNode& report) {
  if (!HasDiagnosis(report)) return {};
  const JsonNode where = report["where"];
  const std::string name = where["component"].String();
  std::optional<std::pair<double, double>> best;
  double best_share = -1.0;
  for (const JsonNode& band : where["bands"].Elements()) {
    const double share = band["share_pct"][name].Number();
    if (share > best_share) {
      best_share = share;
      best = std::make_pair(band["low_hz"].Number(), band["high_hz"].Number());
    }
  }
  return best ? std::vector<std::pair<double, double>>{*best} : std::vector<std::pair<double, double>>{};
}

std::vector<FigureSpec> DiagnosisFigures(const JsonNode& report) {
  if (!HasDiagnosis(report)) return {};
  std::vector<FigureSpec> specs;
  std::vector<GapSeries> gaps = {{"baseline", report["baseline"]["relative_error_pct"].Components()}};
  for (const JsonNode& step : report["steps"].Elements())
    gaps.push_back({"+ " + step["added"].String(), step["after"]["relative_error_pct"].Components()});
  gaps.push_back({"final", report["final"]["relative_error_pct"].Components()});
  std::vector<RankedEffect> ranking;
  for (const JsonNode& entry : report["ranking"].Elements())
    ranking.push_back({entry["effect"].String(), entry["shrink_pct"].Number(), entry["status"].String()});
  FigureSpec gap = DiagnosisFigure("fig_diagnosis", gaps, ranking);
  gap.title = "How far: the held-out gap, and what each effect removes";
  gap.caption =
      "Left: the held-out gap (Table III relative error) per component with the linear model (baseline), after each "
      "effect the forward selection kept, and with all selected effects (final). Right: how much of the held-out "
      "gap each candidate removes, coloured by its status (green selected, orange confounded with a selected "
      "effect, grey not significant).";
  specs.push_back(std::move(gap));

  const JsonNode where = report["where"];
  std::vector<BandBars> bands;
  for (const JsonNode& band : where["bands"].Elements())
    bands.push_back({FormatValue("%.0f", band["low_hz"].Number()) + "-" + FormatValue("%.0f", band["high_hz"].Number()) + " Hz",
                     band["residual_rms"].Components(), band["final_residual_rms"].Components()});
  if (!bands.empty())
    specs.push_back(Titled(
        BandFigure("fig_diagnosis_bands", bands), "Where: the residual per frequency band",
        "Residual RMS of the identification flights in each frequency band, per component: the linear model (dark) "
        "and with the selected effects (light). A delay or motor lag shows at the manoeuvre frequencies, a bias "
        "in the lowest band; a band where the light bar is much shorter is where the effects act."));
  std::vector<SignatureBars> signatures;
  for (const JsonNode& s : where["signatures"].Elements()) {
    SignatureBars bars{s["effect"].String(), s["linearized_shrink_pct"].Number(), {}};
    for (const auto& [label, parameter] : s["parameters"].Items())
      bars.correlation.emplace_back(label, parameter["residual_correlation"].Number());
    signatures.push_back(std::move(bars));
  }
  if (!signatures.empty())
    specs.push_back(Titled(
        SignatureFigure("fig_diagnosis_signatures", signatures), "Where: the residual against each effect's signature",
        "Left: the in-sample residual a first-order fit of each candidate effect alone removes (%). Right: the "
        "correlation of the residual with each effect parameter's signature (the derivative of the residual with "
        "respect to that parameter, the linear parameters projected out); its square is the share of the residual "
        "that parameter alone removes. Large bars point at the effect; the held-out test above decides."));
  return specs;
}

std::string DiagnosisHtml(const JsonNode& report, const std::function<std::string(const std::string&)>& figure) {
  if (!HasDiagnosis(report)) return "";
  const JsonNode where = report["where"];
  const int component = ComponentIndex(where["component"]);
  std::string html = "<h2 id=\"diagnosis\">Diagnosis of the sim-to-real gap</h2>\n";
  html += "<div class=\"verdict\" id=\"diagnosis_verdict\"><strong>Verdict</strong>\n<pre>" +
          Html(report["verdict"].String()) + "</pre></div>\n";
  std::string selected;
  for (const JsonNode& s : report["selected"].Elements())
    selected += (selected.empty() ? "" : ", ") + ("<code>" + Html(s.String()) + "</code>");
  html += "<p><strong>Selected effects:</strong> " + (selected.empty() ? std::string("none") : selected) +
          ". Judged on " + Html(report["validation"].String()) + " (" +
          std::to_string(static_cast<long>(report["held_out_row_samples"].Number())) + " held-out row samples).</p>\n";
  html += "<h3>Which effect</h3>\n" + RankingTable(report) + ConfoundedTable(report);
  html += "<h3>How far the held-out gap shrinks</h3>\n" + GapTables(report) + figure("fig_diagnosis");
  const std::vector<std::optional<double>> model_error = where["model_error_pct"].Components();
  html += "<h3>Where the gap is</h3>\n<p>The largest held-out gap beyond the noise floor is in <strong>" +
          std::string(kWrenchComponentNames[component]) + "</strong> (model error " + Pct(model_error[component]) +
          " %). Its residual per frequency band on the identification flights:</p>\n" + BandTable(where, component) +
          figure("fig_diagnosis_bands");
  html += "<p>The stretches of the flights where the residual is largest (shaded in the wrench figures):</p>\n" +
          StretchTable(where) + figure("fig_diagnosis_signatures");
  return html;
}

}  // namespace rotorid::internal

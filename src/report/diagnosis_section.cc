#include "report/diagnosis_section.h"

#include <algorithm>
#include <optional>

#include "diagnosis/unexplained.h"
#include "diagnosis/verdict_text.h"
#include "report/html_text.h"
#include "rotorid/core/error.h"
#include "rotorid/model/parameters.h"

namespace rotorid::internal {

namespace {

// The components with a rotor wrench, in the order the paper's tables give them.
const std::vector<int> kRotorComponents = {2, 3, 4, 5};
const std::vector<int> kAllComponents = {0, 1, 2, 3, 4, 5};

// The where-component (the largest baseline model error beyond the noise floor).
int WhereComponent(const Diagnosis& d) {
  if (d.where_component < 0 || d.where_component >= kNumWrenchComponents)
    throw Error("diagnosis: where component " + std::to_string(d.where_component) + " is not a wrench component");
  return d.where_component;
}

std::optional<double> At(const std::vector<std::optional<double>>& values, int c) {
  return c < static_cast<int>(values.size()) ? values[c] : std::nullopt;
}

std::vector<std::optional<double>> Optional(const ComponentVector& v) {
  return std::vector<std::optional<double>>(v.data(), v.data() + v.size());
}

std::vector<double> Values(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

std::string StatusTag(const std::string& status) {
  const char* cls = status == "selected"      ? "yes"
                    : status == "confounded"  ? "warn"
                    : status == "implausible" ? "bad"
                                              : "nope";
  return "<span class=\"tag " + std::string(cls) + "\">" + Html(status) + "</span>";
}

std::string BandLabel(const BandGap& band) {
  return FormatValue("%.0f", band.low_hz) + "&ndash;" + FormatValue("%.0f", band.high_hz) + " Hz";
}

// "value ± std unit" of the effect's parameter.
std::string MagnitudeCell(const EffectVerdict& v) {
  const std::string name = EffectParameterName(v.kind);
  std::string cell = "<code>" + Html(name) + "</code><br/>";
  // Selected by a scale-free test: its value as a ratio to the rotor coefficient (the SI value
  // only where the final fit fixes that coefficient).
  if (v.selected && v.scale_free) {
    cell += Html(ScaleFreeValueText(*v.scale_free));
    if (v.value.size() > 0) cell += "<br/>" + ValueWithStd(Values(v.value), Values(v.std), EffectParameterUnit(name));
    return cell;
  }
  return cell + ValueWithStd(Values(v.value), Values(v.std), EffectParameterUnit(name));
}

std::string DetectableCell(const EffectVerdict& v) {
  return ValueWithStd(Values(v.detectable_above), {}, EffectParameterUnit(EffectParameterName(v.kind)));
}

std::string RankingTable(const Diagnosis& d) {
  std::string html =
      "<table id=\"diagnosis_ranking\"><thead><tr><th class=\"num\">#</th><th>effect</th><th>status</th>"
      "<th class=\"num\">held-out shrink (%)</th><th>magnitude (value &plusmn; std)</th><th>this data would reveal it "
      "above</th><th class=\"num\">F</th><th class=\"num\">p</th><th>note</th></tr></thead><tbody>\n";
  int rank = 0;
  for (const EffectVerdict& v : d.ranking) {
    html += "<tr><td class=\"num\">" + std::to_string(++rank) + "</td><td><code>" + Html(EffectName(v.kind)) +
            "</code></td><td>" + StatusTag(v.status) + "</td><td class=\"num\">" + Pct(v.test.shrink_pct) +
            "</td><td class=\"num\">" + MagnitudeCell(v) + "</td><td class=\"num\">" + DetectableCell(v) +
            "</td><td class=\"num\">" + General(v.test.f_statistic) + "</td><td class=\"num\">" +
            FormatValue("%.2g", v.test.p_value) + "</td><td class=\"small note\">" + Html(v.note) + "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

// Held-out Table III per component: the linear model, after each kept effect, and the final model;
// then the noise floor and the part beyond it, and the residual in physical units.
std::string GapTables(const Diagnosis& d) {
  const HeldOutGap &baseline = d.baseline, &final_gap = d.final_gap;
  std::string rows;
  auto row = [&](const std::string& label, const std::vector<std::optional<double>>& values, const char* cls = "") {
    rows += std::string("<tr") + (*cls ? std::string(" class=\"") + cls + "\"" : "") + "><td>" + label + "</td>" +
            ComponentCells(values, kRotorComponents) + "</tr>\n";
  };
  row("linear model (baseline)", baseline.relative_error_pct);
  for (const SelectionStep& step : d.steps)
    row("+ <code>" + Html(EffectName(step.added)) + "</code>", step.after.relative_error_pct);
  row("with the selected effects (final)", final_gap.relative_error_pct, "total");
  std::string html =
      "<p>The held-out relative error (the paper's Table III, ||&rho;|| / ||rotor wrench|| in %) per component, "
      "with the effects added one by one as the forward selection kept them.</p>\n"
      "<table id=\"diagnosis_gap\"><thead><tr><th>model</th>" +
      ComponentHeader(kRotorComponents, "%") + "</tr></thead><tbody>\n" + rows + "</tbody></table>\n";
  const std::pair<const char*, const HeldOutGap*> gaps[] = {{"baseline", &baseline}, {"final", &final_gap}};
  std::string split;
  for (const auto& [label, gap] : gaps) {
    split += std::string("<tr><td>") + label + ": noise floor</td>" +
             ComponentCells(gap->noise_floor_pct, kAllComponents) + "</tr>\n";
    split += std::string("<tr><td>") + label + ": model error beyond it</td>" +
             ComponentCells(gap->model_error_pct, kAllComponents) + "</tr>\n";
  }
  html +=
      "<p>The same gap split into what sensor noise alone explains (noise floor) and the rest, the model error "
      "(Fx, Fy against the thrust, in %):</p>\n<table id=\"diagnosis_noise\"><thead><tr><th>held-out gap (%)</th>" +
      ComponentHeader(kAllComponents) + "</tr></thead><tbody>\n" + split + "</tbody></table>\n";
  // Each gap divides by its own model's rotor wrench, which an effect can change (thrust scales cancel a
  // static moment): the residual after each step is the comparison no divisor moves.
  std::string rms;
  auto rms_row = [&](const std::string& label, const HeldOutGap& gap, const char* cls = "") {
    rms += std::string("<tr") + (*cls ? std::string(" class=\"") + cls + "\"" : "") + "><td>" + label + "</td>";
    for (const int c : kAllComponents) rms += "<td class=\"num\">" + FormatValue("%.4g", gap.residual_rms[c]) + "</td>";
    rms += "</tr>\n";
  };
  rms_row("linear model (baseline)", baseline);
  for (const SelectionStep& step : d.steps) rms_row("+ <code>" + Html(EffectName(step.added)) + "</code>", step.after);
  rms_row("with the selected effects (final)", final_gap, "total");
  std::string header;
  for (const int c : kAllComponents)
    header += "<th class=\"num\">" + std::string(kWrenchComponentNames[c]) + " (" + ComponentUnit(c) + ")</th>";
  html +=
      "<p>Each gap above divides by its own model's rotor wrench, which an effect can change (per-rotor thrust scales "
      "cancel a static moment that the baseline's first moment balanced); the held-out residual itself, after each "
      "step, is the comparison no divisor moves:</p>\n"
      "<table id=\"diagnosis_rms\"><thead><tr><th>held-out residual RMS</th>" +
      header + "</tr></thead><tbody>\n" + rms + "</tbody></table>\n";
  return html;
}

std::string BandTable(const GapLocation& where, int component) {
  const std::string unit = ComponentUnit(component);
  const std::string name = kWrenchComponentNames[component];
  std::string html = "<table id=\"diagnosis_bands\"><thead><tr><th>band</th><th class=\"num\">" + name +
                     " residual, linear (" + unit + " RMS)</th><th class=\"num\">with the selected effects (" + unit +
                     " RMS)</th><th class=\"num\">energy removed (%)</th><th class=\"num\">share of " + name +
                     "'s residual energy (%)</th><th class=\"num\">residual / rotor wrench in the band (%)</th>"
                     "</tr></thead><tbody>\n";
  for (const BandGap& band : where.bands) {
    const double before = band.residual_rms[component], after = band.final_residual_rms[component];
    const std::optional<double> removed =
        before > 0.0 ? std::optional(100.0 * (1.0 - after * after / (before * before))) : std::nullopt;
    html += "<tr><td class=\"num\">" + BandLabel(band) + "</td><td class=\"num\">" + FormatValue("%.4g", before) +
            "</td><td class=\"num\">" + FormatValue("%.4g", after) + "</td><td class=\"num\">" + Pct(removed, 1) +
            "</td><td class=\"num\">" + Pct(band.share_pct[component], 1) + "</td><td class=\"num\">" +
            Pct(At(band.residual_to_model_pct, component), 1) + "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

std::string StretchTable(const GapLocation& where) {
  std::string html =
      "<table id=\"diagnosis_stretches\"><thead><tr><th>flight</th><th class=\"num\">from (s)</th>"
      "<th class=\"num\">to (s)</th><th class=\"num\">mean square / flight's</th><th>mostly</th>" +
      ComponentHeader(kRotorComponents, "%") +
      "<th class=\"num\">rates p/q/r (rad/s RMS)</th><th class=\"num\">mean vertical acc. (m/s&sup2;)</th>"
      "<th>doing</th></tr></thead><tbody>\n";
  for (const FlightStretch& s : where.worst_stretches) {
    std::string rates;
    for (Eigen::Index k = 0; k < s.angular_velocity_rms.size(); ++k)
      rates += (rates.empty() ? "" : " / ") + FormatValue("%.2f", s.angular_velocity_rms[k]);
    std::string activities;
    for (const std::string& a : s.activities) activities += (activities.empty() ? "" : ", ") + Html(a);
    html += "<tr><td><code>" + Html(s.flight.substr(s.flight.find_last_of('/') + 1)) +
            "</code></td><td class=\"num\">" + FormatValue("%.1f", s.start_s) + "</td><td class=\"num\">" +
            FormatValue("%.1f", s.end_s) + "</td><td class=\"num\">" + FormatValue("%.2f", s.mean_square_ratio) +
            "&times;</td><td>" + Html(kWrenchComponentNames[s.dominant_component]) + "</td>" +
            ComponentCells(s.relative_error_pct, kRotorComponents) + "<td class=\"num\">" + rates +
            "</td><td class=\"num\">" + FormatValue("%+.2f", s.mean_vertical_acceleration_mps2) + "</td><td>" +
            activities + "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

std::string ConfoundedTable(const Diagnosis& d) {
  if (d.confounded.empty()) return "";
  std::string html =
      "<h3>Effects the data cannot tell apart</h3>\n<table id=\"diagnosis_confounded\"><thead><tr><th>selected</th>"
      "<th>rival</th><th class=\"num\">shrink, selected (%)</th><th class=\"num\">shrink, rival (%)</th>"
      "<th class=\"num\">parameter correlation</th><th class=\"num\">t</th><th class=\"num\">p</th>"
      "<th>distinguishable</th><th>note</th></tr></thead><tbody>\n";
  for (const ConfoundedEffects& c : d.confounded) {
    html += "<tr><td><code>" + Html(EffectName(c.selected)) + "</code></td><td><code>" + Html(EffectName(c.other)) +
            "</code></td><td class=\"num\">" + Pct(c.selected_shrink_pct) + "</td><td class=\"num\">" +
            Pct(c.other_shrink_pct) + "</td><td class=\"num\">" +
            (c.correlation ? FormatValue("%.3f", *c.correlation) : "&ndash;") + "</td><td class=\"num\">" +
            FormatValue("%.2f", c.t_statistic) + "</td><td class=\"num\">" + FormatValue("%.2g", c.p_value) +
            "</td><td>" + (c.distinguishable ? "yes" : "no") + "</td><td class=\"small note\">" + Html(c.note) +
            "</td></tr>\n";
  }
  return html + "</tbody></table>\n";
}

}  // namespace

std::vector<std::pair<double, double>> WorstBands(const Diagnosis& d) {
  const int component = WhereComponent(d);
  std::optional<std::pair<double, double>> best;
  double best_share = -1.0;
  for (const BandGap& band : d.where.bands) {
    if (band.share_pct[component] > best_share) {
      best_share = band.share_pct[component];
      best = std::make_pair(band.low_hz, band.high_hz);
    }
  }
  return best ? std::vector<std::pair<double, double>>{*best} : std::vector<std::pair<double, double>>{};
}

std::vector<FigureSpec> DiagnosisFigures(const Diagnosis& d) {
  std::vector<FigureSpec> specs;
  std::vector<GapSeries> gaps = {{"baseline", d.baseline.relative_error_pct}};
  for (const SelectionStep& step : d.steps)
    gaps.push_back({"+ " + std::string(EffectName(step.added)), step.after.relative_error_pct});
  gaps.push_back({"final", d.final_gap.relative_error_pct});
  std::vector<RankedEffect> ranking;
  for (const EffectVerdict& v : d.ranking) ranking.push_back({EffectName(v.kind), v.test.shrink_pct, v.status});
  FigureSpec gap = DiagnosisFigure("fig_diagnosis", gaps, ranking);
  gap.title = "How far: the held-out gap, and what each effect removes";
  gap.caption =
      "Left: the held-out gap (Table III relative error) per component with the linear model (baseline), after each "
      "effect the forward selection kept, and with all selected effects (final). Right: how much of the held-out "
      "gap each candidate removes, coloured by its status (green selected, orange confounded with a selected "
      "effect, red implausible: a value outside its physical range or on a bound of its refinement, grey not "
      "significant or negligible: too small to matter).";
  specs.push_back(std::move(gap));

  std::vector<BandBars> bands;
  for (const BandGap& band : d.where.bands)
    bands.push_back({FormatValue("%.0f", band.low_hz) + "-" + FormatValue("%.0f", band.high_hz) + " Hz",
                     Optional(band.residual_rms), Optional(band.final_residual_rms)});
  if (!bands.empty())
    specs.push_back(Titled(
        BandFigure("fig_diagnosis_bands", bands), "Where: the residual per frequency band",
        "Residual RMS of the identification flights in each frequency band, per component: the linear model (dark) "
        "and with the selected effects (light). A delay or motor lag shows at the manoeuvre frequencies, a bias "
        "in the lowest band; a band where the light bar is much shorter is where the effects act."));
  std::vector<SignatureBars> signatures;
  for (const EffectSignature& s : d.where.signatures) {
    SignatureBars bars{EffectName(s.kind), s.linearized_shrink_pct, {}};
    for (size_t k = 0; k < s.labels.size(); ++k)
      bars.correlation.emplace_back(s.labels[k], s.residual_correlation[static_cast<Eigen::Index>(k)]);
    // In label order, as the JSON's "parameters" object lists them.
    std::sort(bars.correlation.begin(), bars.correlation.end());
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

std::string DiagnosisHtml(const Diagnosis& d, const std::function<std::string(const std::string&)>& figure) {
  const int component = WhereComponent(d);
  std::string html = "<h2 id=\"diagnosis\">Diagnosis of the sim-to-real gap</h2>\n";
  html += "<div class=\"verdict\" id=\"diagnosis_verdict\"><strong>Verdict</strong>\n<pre>" +
          Html(DiagnosisVerdict(d)) + "</pre></div>\n";
  std::string selected;
  for (EffectKind kind : d.selected)
    selected += (selected.empty() ? "" : ", ") + ("<code>" + Html(EffectName(kind)) + "</code>");
  html += "<p><strong>Selected effects:</strong> " + (selected.empty() ? std::string("none") : selected) +
          ". Judged on " + Html(d.validation) + " (" + std::to_string(d.held_out_row_samples) +
          " held-out row samples).</p>\n";
  // What the selected effects leave far above the noise floor, as the verdict says it.
  html +=
      "<p id=\"diagnosis_unexplained\"><strong>Unexplained</strong> (what the selected effects leave far above "
      "the noise floor): ";
  if (d.unexplained.empty()) html += "nothing.";
  for (const UnexplainedResidual& u : d.unexplained) html += "<br/>" + Html(UnexplainedSentence(u)) + ".";
  html += "</p>\n";
  html += "<h3>Which effect</h3>\n" + RankingTable(d) + ConfoundedTable(d);
  html += "<h3>How far the held-out gap shrinks</h3>\n" + GapTables(d) + figure("fig_diagnosis");
  html += "<h3>Where the gap is</h3>\n<p>The largest held-out gap beyond the noise floor is in <strong>" +
          std::string(kWrenchComponentNames[component]) + "</strong> (model error " +
          Pct(At(d.baseline.model_error_pct, component)) +
          " %). Its residual per frequency band on the identification flights:</p>\n" + BandTable(d.where, component) +
          figure("fig_diagnosis_bands");
  html += "<p>The stretches of the flights where the residual is largest (shaded in the wrench figures):</p>\n" +
          StretchTable(d.where) + figure("fig_diagnosis_signatures");
  return html;
}

}  // namespace rotorid::internal

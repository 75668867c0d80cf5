#include "report/html_answer.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <set>

#include "report/html_text.h"
#include "rotorid/core/text.h"
#include "rotorid/ident/tls.h"
#include "rotorid/model/parameters.h"
#include "rotorid/report/predicted_parameters.h"

namespace rotorid::internal {

namespace {

// One parameter as the report's most complete model gives it.
struct Estimate {
  std::optional<double> value, std_dev;
  bool fixed = true;                     // essential: the flights determine it
  std::optional<double> predicted_with;  // a parameter they do not fix: its profiled estimate, or a value a body allows
};

// The most complete model of the report: the diagnosis's final model, else the refinement, else the
// linear TLS, else the first saved parameter set (validate).
struct Model {
  std::string label;
  std::vector<std::string> names;
  std::function<Estimate(const std::string&)> estimate;
  const std::vector<std::optional<double>>* relative_error_pct = nullptr;  // on the identification flights
};

Model FromSolution(const std::string& label, const std::vector<std::string>& names, const TlsSolution& solution,
                   const std::vector<std::optional<double>>* relative_error_pct) {
  const Eigen::VectorXd predicted = PredictionChi(solution);
  auto estimate = [&names, &solution, predicted](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) return Estimate{};
    const int k = static_cast<int>(it - names.begin());
    Estimate e{solution.chi[k], solution.std.size() > k ? std::optional(solution.std[k]) : std::nullopt,
               solution.essential[k], std::nullopt};
    if (!e.fixed && PredictsWithOtherValue(solution, k)) e.predicted_with = predicted[k];
    return e;
  };
  return {label, names, estimate, relative_error_pct};
}

Model ModelOf(const ReportInput& input) {
  if (input.diagnosis && !input.diagnosis->final_parameters.empty()) {
    const Diagnosis& d = *input.diagnosis;
    std::vector<std::string> names;
    for (const auto& [name, value] : d.final_parameters) names.push_back(name);
    auto estimate = [&d](const std::string& name) {
      const auto it = d.final_parameters.find(name);
      if (it == d.final_parameters.end()) return Estimate{};
      const auto s = d.final_parameter_std.find(name);
      Estimate e{it->second, s == d.final_parameter_std.end() ? std::nullopt : std::optional(s->second), true,
                 std::nullopt};
      // A parameter the final model holds at 0 is one the flights do not fix.
      e.fixed = !(it->second == 0.0 && PositiveByPhysics(name));
      if (const auto p = d.final_predicts_with.find(name);
          !e.fixed && p != d.final_predicts_with.end() && p->second != 0.0)
        e.predicted_with = p->second;
      return e;
    };
    return {"the diagnosis's final model", names, estimate, nullptr};
  }
  if (input.refined && input.linear)
    return FromSolution("refined", input.linear->system.parameter_names, input.refined->refined,
                        &input.refined->relative_error_pct);
  if (input.linear)
    return FromSolution("linear", input.linear->system.parameter_names, input.linear->solution,
                        &input.linear->relative_error_pct);
  if (!input.parameter_sets.empty()) {
    const ParameterSet& set = input.parameter_sets.front();
    std::vector<std::string> names;
    for (const auto& [name, value] : set.values) names.push_back(name);
    auto estimate = [&set](const std::string& name) {
      const auto it = set.values.find(name);
      return it == set.values.end() ? Estimate{} : Estimate{it->second, std::nullopt, true, std::nullopt};
    };
    return {set.label, names, estimate, nullptr};
  }
  return {};
}

std::string ValueCell(const Estimate& e, double scale, const std::string& unit) {
  if (!e.value) return "&ndash;";
  if (!e.fixed) {
    std::string text = "not fixed by these flights";
    if (e.predicted_with) text += " (predicted with " + Html(ShortNumber(*e.predicted_with * scale)) + " " + unit + ")";
    return text;
  }
  std::string text = Html(FormatValue("%.4g", *e.value * scale));
  if (e.std_dev && *e.std_dev > 0.0) {
    text += " &plusmn; " + Html(ShortNumber(*e.std_dev * scale));
    if (*e.value != 0.0)
      text += " " + unit + " <span class=\"small\">(" +
              Html(FormatValue("%.2g", 100.0 * *e.std_dev / std::abs(*e.value))) + " %)</span>";
    return text;
  }
  return text + " " + unit;
}

// The owners of first moments among the names: "A" for A.ms_x, "A.flight2" for A.flight2.ms_x.
std::vector<std::string> FirstMomentOwners(const std::vector<std::string>& names) {
  std::vector<std::string> owners;
  for (const std::string& name : names)
    if (EndsWith(name, ".ms_x")) owners.push_back(name.substr(0, name.size() - 5));
  return owners;
}

// A configuration's mass from the flights drawn (the vehicle file's), if any.
std::optional<double> MassOf(const ReportInput& input, const std::string& owner) {
  const std::string config = owner.substr(0, owner.find('.'));
  for (const ReportFlight& f : input.flights)
    if (f.flight && f.flight->vehicle.name == config && f.flight->vehicle.mass_kg > 0.0)
      return f.flight->vehicle.mass_kg;
  return std::nullopt;
}

std::string ParameterRows(const ReportInput& input, const Model& model) {
  std::string rows;
  auto row = [&rows](const std::string& what, const std::string& cell) {
    rows += "<tr><td>" + what + "</td><td>" + cell + "</td></tr>\n";
  };
  row("thrust coefficient <code>kt</code>", ValueCell(model.estimate("kt"), 1.0, "N s&sup2;"));
  row("drag-torque coefficient <code>kd</code>", ValueCell(model.estimate("kd"), 1.0, "N m s&sup2;"));
  for (const std::string& owner : FirstMomentOwners(model.names)) {
    const std::optional<double> mass = MassOf(input, owner);
    if (mass) {
      std::string cell;
      for (const char* axis : {"x", "y", "z"}) {
        Estimate e = model.estimate(owner + ".ms_" + axis);
        cell += std::string(cell.empty() ? "" : "<br/>") + axis + ": " + ValueCell(e, 1e3 / *mass, "mm");
      }
      row("centre of mass of <code>" + Html(owner) + "</code> (from O<sub>d</sub>)", cell);
    }
    const std::string config = owner.substr(0, owner.find('.'));
    if (owner != config) continue;  // the inertia once per configuration
    for (const char* axis : {"I_xx", "I_yy", "I_zz"})
      row("<code>" + Html(config + "." + axis) + "</code>",
          ValueCell(model.estimate(config + "." + axis), 1.0, "kg m&sup2;"));
  }
  return rows;
}

std::string ComponentList(const std::vector<std::optional<double>>& pct) {
  std::string text;
  for (size_t c = 0; c < pct.size() && c < kWrenchComponentNames.size(); ++c)
    if (pct[c]) text += std::string(text.empty() ? "" : ", ") + kWrenchComponentNames[c] + " " + Pct(pct[c], 1) + " %";
  return text.empty() ? "&ndash;" : text;
}

std::string GapItems(const ReportInput& input, const Model& model) {
  std::string items;
  if (model.relative_error_pct)
    items += "<li>On the identification flights (" + Html(model.label) +
             ", the paper's Table III): " + ComponentList(*model.relative_error_pct) + "</li>\n";
  for (const RelativeErrorRow& row : input.relative_errors)
    items += "<li>On the " + Html(row.data) + " (" + Html(row.parameters) +
             "): " + ComponentList(row.relative_error_pct) + "</li>\n";
  if (!input.diagnosis) return items;
  const Diagnosis& d = *input.diagnosis;
  std::string change;
  for (size_t c = 0; c < d.baseline.relative_error_pct.size(); ++c) {
    const auto& before = d.baseline.relative_error_pct[c];
    const auto& after = c < d.final_gap.relative_error_pct.size() ? d.final_gap.relative_error_pct[c] : std::nullopt;
    if (before && after)
      change += std::string(change.empty() ? "" : ", ") + kWrenchComponentNames[c] + " " + Pct(before, 1) + " &rarr; " +
                Pct(after, 1) + " %";
  }
  items += "<li>Held out, the linear model &rarr; with the selected effects: " + (change.empty() ? "&ndash;" : change) +
           "</li>\n";
  std::string closed;
  for (EffectKind kind : d.selected)
    closed += std::string(closed.empty() ? "" : "; ") + "<code>" + Html(kind->name()) + "</code> " +
              Html(kind->Format(d.final_effects.Get(kind), d.final_effects_std.Get(kind)));
  items += "<li>What closes it: " +
           (closed.empty() ? std::string("no candidate effect (the gap is noise, or none of them)") : closed) +
           "</li>\n";
  for (const UnexplainedResidual& u : d.unexplained)
    items += "<li><strong>Unexplained:</strong> " + std::string(kWrenchComponentNames[u.component]) + " " +
             Pct(u.gap_pct, 1) + " % against a noise floor of " + Pct(u.noise_floor_pct, 1) + " %, mostly " +
             Html(FormatValue("%.2g", u.band_low_hz)) + "-" + Html(FormatValue("%.2g", u.band_high_hz)) +
             " Hz: " + Html(u.note) + "</li>\n";
  return items;
}

std::string ChecksLine(const ReportInput& input) {
  if (!input.checks || input.checks->empty()) return "";
  const std::vector<Check> ordered = ChecksFailuresFirst(*input.checks);
  const auto failed =
      std::count_if(ordered.begin(), ordered.end(), [](const Check& c) { return c.status != CheckStatus::kOk; });
  if (failed == 0)
    return "<p class=\"box ok\">Every one of the " + std::to_string(ordered.size()) +
           " plausibility checks passed (<a href=\"#checks\">the checks</a>).</p>\n";
  std::string html = "<div class=\"box bad\"><strong>" + std::to_string(failed) + " of " +
                     std::to_string(ordered.size()) +
                     " plausibility checks did not pass</strong> (<a href=\"#checks\">all checks</a>):<ul>\n";
  for (const Check& check : ordered) {
    if (check.status == CheckStatus::kOk) break;
    html += "<li><code>" + Html(check.name) + "</code> " + CheckStatusName(check.status) + ": " + Html(check.message) +
            "</li>\n";
  }
  return html + "</ul></div>\n";
}

std::string NextStep(const ReportInput& input) {
  const bool error = input.checks && std::any_of(input.checks->begin(), input.checks->end(),
                                                 [](const Check& c) { return c.status == CheckStatus::kError; });
  if (error) return "Fix what the failed checks name (the input, the vehicle file or the flight), then run again.";
  if (input.diagnosis) {
    if (input.diagnosis->selected.empty())
      return "No candidate effect pays for itself on the held-out flights: use the linear parameters, or fly a "
             "flight that excites what the gap's component needs.";
    std::vector<std::string> names;
    for (EffectKind kind : input.diagnosis->selected) names.push_back(kind->name());
    return "Refine with what the diagnosis selected (<code>rotorid refine ... --effects " + Html(Join(names, ",")) +
           "</code>) and fly the result forward against a held-out flight (<code>rotorid predict</code>).";
  }
  if (input.refined)
    return "Check the refined model on a flight it was not fitted to (<code>rotorid validate</code>, "
           "<code>rotorid predict</code>), then export it (<code>rotorid export</code>).";
  if (input.linear)
    return "Find what the model still misses on a held-out flight (<code>rotorid diagnose --validate-vehicle ... "
           "--validate-log ...</code>).";
  return "";
}

}  // namespace

std::vector<Check> ChecksFailuresFirst(const std::vector<Check>& checks) {
  std::vector<Check> ordered = checks;
  auto rank = [](const Check& c) {
    return c.status == CheckStatus::kError ? 0 : c.status == CheckStatus::kWarning ? 1 : 2;
  };
  std::stable_sort(ordered.begin(), ordered.end(),
                   [&rank](const Check& a, const Check& b) { return rank(a) < rank(b); });
  return ordered;
}

std::string AnswerHtml(const ReportInput& input) {
  const Model model = ModelOf(input);
  std::string html = "<h2 id=\"answer\">What was found</h2>\n" + ChecksLine(input);
  if (model.estimate)
    html += "<table id=\"answer_parameters\"><thead><tr><th>the parameters that matter (" + Html(model.label) +
            ")</th><th>value &plusmn; std</th></tr></thead><tbody>\n" + ParameterRows(input, model) +
            "</tbody></table>\n";
  const std::string gap = GapItems(input, model);
  if (!gap.empty()) html += "<p><strong>The gap</strong></p><ul>\n" + gap + "</ul>\n";
  const std::string next = NextStep(input);
  if (!next.empty()) html += "<p><strong>Next step.</strong> " + next + "</p>\n";
  return html;
}

}  // namespace rotorid::internal

#include "rotorid/report/refine_json.h"

#include <algorithm>
#include <cmath>

#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/json.h"

namespace rotorid {

nlohmann::json RefineOptionsJson(const RefineOptions& options) {
  nlohmann::json effects = nlohmann::json::array();
  for (EffectKind k : options.effects) effects.push_back(EffectName(k));
  return {{"effects", effects},
          {"coarse_delay_search", options.coarse_delay_search},
          {"delay_search_s", {options.delay_search.min_s, options.delay_search.max_s, options.delay_search.step_s}},
          {"robust_loss", options.robust_loss},
          {"robust_scale", options.robust_scale},
          {"criterion", options.criterion},
          {"max_iterations", options.max_iterations}};
}

std::vector<EffectParameterEstimate> EffectParameterEstimates(const Effects& value, const Effects& std_dev,
                                                              const std::vector<EffectKind>& enabled,
                                                              const std::vector<EffectKind>& on_bound) {
  std::vector<EffectParameterEstimate> out;
  for (EffectKind kind : AllEffects()) {
    const bool on = std::find(enabled.begin(), enabled.end(), kind) != enabled.end();
    const bool bounded = std::find(on_bound.begin(), on_bound.end(), kind) != on_bound.end();
    const Eigen::VectorXd v = value.Get(kind), s = std_dev.Get(kind);
    const auto at = [](const Eigen::VectorXd& x, size_t k) {
      return static_cast<Eigen::Index>(k) < x.size() ? x[static_cast<Eigen::Index>(k)] : 0.0;
    };
    const std::vector<std::string>& labels = kind->info().labels;
    if (!labels.empty()) {  // one entry per coefficient, as INTERFACE.md names them
      for (size_t k = 0; k < labels.size(); ++k)
        out.push_back({labels[k],
                       Eigen::VectorXd::Constant(1, at(v, k)),
                       Eigen::VectorXd::Constant(1, at(s, k)),
                       true,
                       on,
                       bounded,
                       {},
                       {}});
    } else {
      std::vector<std::string> held = kind->HeldLabels(static_cast<int>(v.size()));
      const std::string why = held.empty() ? std::string() : kind->info().held_why;
      out.push_back({EffectParameterName(kind), v, s, kind->FixedDimension() == 1, on, bounded, std::move(held), why});
    }
  }
  return out;
}

nlohmann::json EffectsJson(const Effects& value, const Effects& std_dev, const std::vector<EffectKind>& enabled,
                           const std::vector<EffectKind>& on_bound) {
  nlohmann::json out = nlohmann::json::object();
  for (const EffectParameterEstimate& e : EffectParameterEstimates(value, std_dev, enabled, on_bound)) {
    out[e.name] = {{"value", e.scalar ? JsonNumber(e.value[0]) : VectorJson(e.value)},
                   {"std", e.scalar ? JsonNumber(e.std[0]) : VectorJson(e.std)},
                   {"enabled", e.enabled},
                   {"on_bound", e.on_bound}};
    if (!e.held.empty()) {
      out[e.name]["held"] = e.held;
      out[e.name]["held_why"] = e.held_why;
    }
  }
  return out;
}

nlohmann::json SolverJson(const SolverReport& solver) {
  return {{"iterations", solver.iterations},
          {"initial_cost", JsonNumber(solver.initial_cost)},
          {"final_cost", JsonNumber(solver.final_cost)},
          {"termination", solver.termination},
          {"message", solver.message},
          {"seconds", JsonNumber(solver.seconds)}};
}

namespace {

nlohmann::json BodyConstraintJson(const BodyConstraint& c) {
  return {{"parameterisation", c.charted.empty() ? "none" : "log-Cholesky of the pseudo-inertia, mass held"},
          {"charted", c.charted},
          {"notes", c.notes},
          {"start_moved", c.start_moved},
          {"start_distance_std", JsonNumber(c.start_distance_std)},
          {"unconstrained_distance_std", JsonNumber(c.unconstrained_distance_std)},
          {"largest_move", c.largest_move}};
}

}  // namespace

nlohmann::json RefinedJson(const IdentificationResult& linear, const RefineResult& refined) {
  nlohmann::json correlation = nlohmann::json::array();
  for (Eigen::Index a = 0; a < refined.effect_correlation.rows(); ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index b = 0; b < refined.effect_correlation.cols(); ++b)
      row.push_back(JsonNumber(refined.effect_correlation(a, b)));
    correlation.push_back(row);
  }
  return {{"parameters", ParametersJson(linear.system.parameter_names, refined.refined)},
          {"bodies", BodiesJson(CheckedFromRefinement(linear, refined))},
          {"effects", EffectsJson(refined.effects, refined.effects_std, refined.enabled, refined.on_bound)},
          {"relative_error_pct", ComponentsJson(refined.relative_error_pct)},
          {"effect_correlation", {{"labels", refined.effect_labels}, {"matrix", correlation}}},
          {"criterion",
           {{"linear", JsonNumber(refined.linear_criterion)}, {"refined", JsonNumber(refined.refined_criterion)}}},
          {"autocorrelation_factor", JsonNumber(refined.autocorrelation_factor)},
          {"body_constraint", BodyConstraintJson(refined.body_constraint)},
          {"solver", SolverJson(refined.solver)},
          {"warnings", refined.warnings}};
}

nlohmann::json AblationJson(const AblationResult& ablation) {
  nlohmann::json rows = nlohmann::json::array();
  for (const AblationEntry& e : ablation.entries) {
    nlohmann::json names = nlohmann::json::array();
    for (EffectKind k : e.effects) names.push_back(EffectName(k));
    nlohmann::json row = {{"effects", names},
                          {"num_parameters", e.num_parameters},
                          {"aic", e.aic},
                          {"bic", e.bic},
                          {"criterion", e.result.refined_criterion},
                          {"relative_error_pct", ComponentsJson(e.relative_error_pct)},
                          {"kt", e.result.refined.chi[0]},
                          {"kd", e.result.refined.chi[1]},
                          {"effects_values", EffectsJson(e.result.effects, e.result.effects_std, e.effects)}};
    if (!e.held_out_relative_error_pct.empty())
      row["held_out_relative_error_pct"] = ComponentsJson(e.held_out_relative_error_pct);
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json DelayJson(const IdentificationResult& linear, const DelayEstimate& estimate) {
  nlohmann::json curve = nlohmann::json::array();
  for (size_t i = 0; i < estimate.grid_s.size(); ++i) curve.push_back({estimate.grid_s[i], estimate.criterion[i]});
  return {{"delay_s", estimate.delay_s},
          {"delay_std_s", estimate.delay_std_s},
          {"grid_best_s", estimate.grid_best_s},
          {"motor_tau_s", estimate.motor_tau_s},
          {"motor_tau_std_s", estimate.motor_tau_std_s},
          {"criterion_curve", curve},
          {"refined", RefinedJson(linear, estimate.refined)},
          {"warnings", estimate.warnings}};
}

Effects EffectsFromReport(const nlohmann::json& report) {
  Effects effects;
  if (!report.contains("refined") || !report["refined"].contains("effects")) return effects;
  const nlohmann::json& block = report["refined"]["effects"];
  for (EffectKind kind : AllEffects()) {
    const std::vector<std::string>& labels = kind->info().labels;
    if (!labels.empty()) {
      Eigen::VectorXd value = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(labels.size()));
      for (size_t k = 0; k < labels.size(); ++k)
        if (block.contains(labels[k]) && block[labels[k]].contains("value") && block[labels[k]]["value"].is_number())
          value[static_cast<Eigen::Index>(k)] = block[labels[k]]["value"].get<double>();
      effects.Set(kind, value);
      continue;
    }
    const char* name = EffectParameterName(kind);
    if (!block.contains(name) || !block[name].contains("value")) continue;
    const nlohmann::json& v = block[name]["value"];
    // A per-rotor effect has as many values as the report's vehicle has rotors.
    const int dimension = kind->FixedDimension();
    Eigen::VectorXd value(dimension >= 0 ? dimension : (v.is_array() ? static_cast<int>(v.size()) : 0));
    if (v.is_number() && value.size() == 1) {
      value[0] = v.get<double>();
    } else if (v.is_array() && static_cast<int>(v.size()) == value.size()) {
      for (int k = 0; k < value.size(); ++k) value[k] = v[k].is_number() ? v[k].get<double>() : 0.0;
    } else {
      continue;
    }
    effects.Set(kind, value);
  }
  return effects;
}

}  // namespace rotorid

#include "rotorid/report/refine_json.h"

#include <cmath>

#include "rotorid/report/json.h"

namespace rotorid {


nlohmann::json RefineOptionsJson(const RefineOptions& options) {
  nlohmann::json effects = nlohmann::json::array();
  for (EffectKind k : options.effects) effects.push_back(EffectName(k));
  return {{"effects", effects},
          {"coarse_delay_search", options.coarse_delay_search},
          {"delay_search_s", {options.delay_search_min_s, options.delay_search_max_s, options.delay_search_step_s}},
          {"robust_loss", options.robust_loss},
          {"robust_scale", options.robust_scale},
          {"criterion", options.criterion},
          {"max_iterations", options.max_iterations}};
}

nlohmann::json EffectsJson(const Effects& value, const Effects& std_dev, const std::vector<EffectKind>& enabled,
                           const std::vector<EffectKind>& on_bound) {
  nlohmann::json out = nlohmann::json::object();
  for (EffectKind kind : AllEffects()) {
    const bool on = std::find(enabled.begin(), enabled.end(), kind) != enabled.end();
    const Eigen::VectorXd v = value.Get(kind), s = std_dev.Get(kind);
    const bool bounded = std::find(on_bound.begin(), on_bound.end(), kind) != on_bound.end();
    const auto entry = [&](nlohmann::json estimate, nlohmann::json spread) {
      return nlohmann::json{{"value", estimate}, {"std", spread}, {"enabled", on}, {"on_bound", bounded}};
    };
    const auto at = [](const Eigen::VectorXd& x, size_t k) {
      return static_cast<Eigen::Index>(k) < x.size() ? x[static_cast<Eigen::Index>(k)] : 0.0;
    };
    const std::vector<std::string>& labels = kind->info().labels;
    if (!labels.empty()) {  // one key per coefficient, as INTERFACE.md names them
      for (size_t k = 0; k < labels.size(); ++k) out[labels[k]] = entry(JsonNumber(at(v, k)), JsonNumber(at(s, k)));
    } else if (kind->FixedDimension() == 1) {
      out[EffectParameterName(kind)] = entry(JsonNumber(v[0]), JsonNumber(s[0]));
    } else {
      out[EffectParameterName(kind)] = entry(VectorJson(v), VectorJson(s));
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

nlohmann::json RefinedJson(const IdentificationResult& linear, const RefineResult& refined) {
  nlohmann::json correlation = nlohmann::json::array();
  for (Eigen::Index a = 0; a < refined.effect_correlation.rows(); ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index b = 0; b < refined.effect_correlation.cols(); ++b)
      row.push_back(JsonNumber(refined.effect_correlation(a, b)));
    correlation.push_back(row);
  }
  return {{"parameters", ParametersJson(linear.system.parameter_names, refined.refined)},
          {"effects", EffectsJson(refined.effects, refined.effects_std, refined.enabled, refined.on_bound)},
          {"relative_error_pct", ComponentsJson(refined.relative_error_pct)},
          {"effect_correlation", {{"labels", refined.effect_labels}, {"matrix", correlation}}},
          {"criterion", {{"linear", JsonNumber(refined.linear_criterion)}, {"refined", JsonNumber(refined.refined_criterion)}}},
          {"autocorrelation_factor", JsonNumber(refined.autocorrelation_factor)},
          {"solver", SolverJson(refined.solver)},
          {"warnings", refined.warnings}};
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

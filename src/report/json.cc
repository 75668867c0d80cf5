#include "rotorid/report/json.h"

#include <cmath>

#include "rotorid/core/error.h"
#include "rotorid/ident/body_consistency.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/parameters.h"
#include "rotorid/report/predicted_parameters.h"

namespace rotorid {

nlohmann::json JsonNumber(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

ParameterStatistics ParameterStatisticsOf(const std::vector<std::string>& names, const TlsSolution& solution,
                                          size_t k) {
  const auto i = static_cast<Eigen::Index>(k);
  ParameterStatistics p{solution.chi[i], solution.std[i], solution.rel_std_pct[i],
                        static_cast<bool>(solution.essential[k]), nullptr};
  for (const DiscardedParameter& d : solution.discarded) {
    if (d.name != names[k]) continue;
    p.std = d.std;
    p.discarded = &d;
  }
  return p;
}

nlohmann::json ParametersJson(const std::vector<std::string>& names, const TlsSolution& solution) {
  nlohmann::json out = nlohmann::json::object();
  const Eigen::VectorXd predicted = PredictionChi(solution);
  for (size_t k = 0; k < names.size(); ++k) {
    const ParameterStatistics p = ParameterStatisticsOf(names, solution, k);
    nlohmann::json entry = {{"value", JsonNumber(p.value)},
                            {"std", JsonNumber(p.std)},
                            {"rel_std_pct", JsonNumber(p.rel_std_pct)},
                            {"essential", p.essential}};
    if (p.discarded) {
      entry["estimate_when_discarded"] = JsonNumber(p.discarded->value);
      entry["most_correlated_with"] = p.discarded->most_correlated;
      entry["correlation"] = JsonNumber(p.discarded->correlation);
    }
    // A discarded parameter the model still estimates and predicts with (PredictionChi): validate
    // predicts with it too.
    const int i = static_cast<int>(k);
    if (PredictsWithOtherValue(solution, i)) entry["predicts_with"] = JsonNumber(predicted[i]);
    // Not an estimate: a value inside the range a body allows, the estimate lying outside it or absent.
    if (solution.PredictsWithinRange(i)) entry["predicts_within_range"] = true;
    // The values a physical body allows a discarded inertia (the others as predicted with).
    if (solution.HasAllowedRange(i))
      entry["allowed_range"] = {JsonNumber(solution.allowed_low[i]), JsonNumber(solution.allowed_high[i])};
    out[names[k]] = entry;
  }
  return out;
}

nlohmann::json BodiesJson(const CheckedParameters& parameters) {
  nlohmann::json out = nlohmann::json::array();
  const auto vector = [](const Eigen::Vector3d& v) { return VectorJson(v); };
  for (const BodyAssessment& a : AssessBodies(parameters)) {
    const PhysicalConsistency& c = a.consistency;
    nlohmann::json body = {{"body", a.name},
                           {"consistent", c.consistent},
                           {"centre_of_mass_m", vector(c.centre_of_mass_m)},
                           {"principal_moments_at_com", vector(c.principal_moments_at_com)},
                           {"rms_extent_m", vector(c.rms_extent_m)},
                           {"distance_std", a.has_projection ? JsonNumber(a.projection.distance_std) : nullptr}};
    if (!c.consistent) body["cause"] = a.cause;
    if (a.has_projection && a.projection.distance_std > 0.0) {
      nlohmann::json nearest = nlohmann::json::object();
      const Eigen::Matrix<double, kNumBodyParameters, 1> chi = a.projection.body.ToVector();
      for (int k = 0; k < kNumBodyParameters; ++k) nearest[kBodyParameterNames[k]] = JsonNumber(chi[k]);
      body["nearest_consistent"] = nearest;
    }
    out.push_back(body);
  }
  return out;
}

nlohmann::json ComponentsJson(const std::vector<std::optional<double>>& values) {
  nlohmann::json out = nlohmann::json::object();
  for (size_t j = 0; j < values.size() && j < kWrenchComponentNames.size(); ++j)
    out[kWrenchComponentNames[j]] = values[j] ? JsonNumber(*values[j]) : nlohmann::json(nullptr);
  return out;
}

nlohmann::json VectorJson(const Eigen::VectorXd& v) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(JsonNumber(v[i]));
  return out;
}

nlohmann::json ObservationOptionsJson(const ObservationOptions& options) {
  return {{"source", DataSourceName(options.source)},
          {"filter", {{"type", "butterworth low-pass, zero-phase"},
                      {"order", options.filter.order},
                      {"cutoff_hz", options.filter.cutoff_hz}}},
          {"row_rate_hz", options.row_rate_hz},
          {"edge_trim_s", options.edge_trim_s}};
}

ObservationOptions ObservationOptionsFromJson(const nlohmann::json& j) {
  ObservationOptions options;
  if (!j.is_object()) return options;
  if (j.contains("source")) options.source = j.at("source").get<std::string>() == "mocap" ? DataSource::kMocap : DataSource::kImu;
  if (j.contains("filter")) {
    options.filter.order = j.at("filter").value("order", options.filter.order);
    options.filter.cutoff_hz = j.at("filter").value("cutoff_hz", options.filter.cutoff_hz);
  }
  options.row_rate_hz = j.value("row_rate_hz", options.row_rate_hz);
  options.edge_trim_s = j.value("edge_trim_s", options.edge_trim_s);
  return options;
}

nlohmann::json TlsOptionsJson(const TlsOptions& options) {
  return {{"method", TlsMethodName(options.method)},
          {"weight_by_component", options.weight_by_component},
          {"select_essential", options.select_essential},
          {"r_sigma", options.r_sigma},
          {"max_rel_std_pct", options.max_rel_std_pct},
          {"fixed_zero", options.fixed_zero}};
}

nlohmann::json FlightFitJson(const FlightFit& fit) {
  const Excitation& e = fit.excitation;
  return {{"log", fit.source},
          {"config", fit.config},
          {"weight", fit.weight},
          {"samples", fit.samples},
          {"row_samples", fit.row_samples},
          {"duration_s", fit.duration_s},
          {"excitation", {{"angular_acceleration_rms", VectorJson(e.angular_acceleration_rms)},
                          {"angular_velocity_rms", VectorJson(e.angular_velocity_rms)},
                          {"thrust_variation_pct", JsonNumber(e.thrust_variation_pct)}}},
          {"relative_error_pct", ComponentsJson(fit.relative_error_pct)},
          {"mean_force_residual_n", VectorJson(fit.mean_force_residual_n)}};
}

nlohmann::json LinearJson(const IdentificationResult& result) {
  const TlsSolution& s = result.solution;
  nlohmann::json discarded = nlohmann::json::array();
  for (const DiscardedParameter& d : s.discarded)
    discarded.push_back({{"name", d.name},
                         {"rel_std_pct", JsonNumber(d.rel_std_pct)},
                         {"most_correlated_with", d.most_correlated},
                         {"correlation", JsonNumber(d.correlation)},
                         {"reason", d.reason}});
  nlohmann::json flights = nlohmann::json::array();
  for (const FlightFit& fit : result.per_flight) flights.push_back(FlightFitJson(fit));
  return {{"method", TlsMethodName(s.method)},
          {"parameters", ParametersJson(result.system.parameter_names, s)},
          {"bodies", BodiesJson(CheckedFromSolution(result, s))},
          {"relative_error_pct", ComponentsJson(result.relative_error_pct)},
          {"discarded", discarded},
          {"flights", flights},
          {"statistics", {{"sigma_w", JsonNumber(s.sigma_w)},
                          {"singular_values", VectorJson(s.singular_values)},
                          {"scale_entry", JsonNumber(s.scale_entry)},
                          {"iterations", s.iterations},
                          {"rows", result.system.num_rows()}}},
          {"warnings", result.warnings}};
}

std::map<std::string, double> ParameterValuesFromReport(const nlohmann::json& report, const std::string& source,
                                                        const std::string& block, bool predicted) {
  const std::string chosen = PredictedBlock(report, block);
  if (!report.is_object() || !report.contains(chosen) || !report[chosen].is_object() ||
      !report[chosen].contains("parameters") || !report[chosen]["parameters"].is_object())
    throw Error(source + ": not a rotorid identify/refine report (no '" + chosen + ".parameters')");
  std::map<std::string, double> values;
  for (const auto& [name, entry] : report[chosen]["parameters"].items()) {
    if (!entry.is_object() || !entry.contains("value") || !entry["value"].is_number())
      throw Error(source + ": parameter '" + name + "' has no numeric value");
    values[name] = entry["value"].get<double>();
    if (predicted && entry.contains("predicts_with") && entry["predicts_with"].is_number())
      values[name] = entry["predicts_with"].get<double>();
  }
  return values;
}

nlohmann::json ReadJsonFile(const std::string& path) {
  const std::string text = ReadFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(path + ": not valid JSON: " + e.what());
  }
}

void WriteJsonFile(const std::string& path, const nlohmann::json& j) { WriteFileAtomically(path, j.dump(2) + "\n"); }

}  // namespace rotorid

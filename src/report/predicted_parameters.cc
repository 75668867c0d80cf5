#include "rotorid/report/predicted_parameters.h"

#include "rotorid/refine/refine.h"
#include "rotorid/report/json.h"
#include "rotorid/report/refine_json.h"

namespace rotorid {

std::map<std::string, double> PredictedParameters(const IdimLayout& system, const TlsSolution& solution) {
  return NamedParameters(system, PredictionChi(solution));
}

bool PredictsWithOtherValue(const TlsSolution& solution, int k) {
  return PredictsWithProfiled(solution, k) || solution.PredictsWithinRange(k);
}

std::map<std::string, double> PredictedParameters(std::map<std::string, double> values,
                                                  const std::map<std::string, double>& predicts_with) {
  for (const auto& [name, value] : predicts_with) values[name] = value;
  return values;
}

std::string PredictedBlock(const nlohmann::json& report, const std::string& block) {
  if (!block.empty()) return block;
  const bool refined = report.is_object() && report.contains("refined") && report["refined"].is_object() &&
                       report["refined"].contains("parameters");
  return refined ? "refined" : "linear";
}

PredictedModel PredictedParameters(const nlohmann::json& report, const std::string& source, const std::string& block) {
  PredictedModel model;
  model.block = PredictedBlock(report, block);
  model.values = ParameterValuesFromReport(report, source, model.block, /*predicted=*/true);
  // Refined parameters are only valid together with their effects.
  if (model.block == "refined") model.effects = EffectsFromReport(report);
  return model;
}

}  // namespace rotorid

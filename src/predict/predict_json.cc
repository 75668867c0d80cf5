#include "predict/predict_json.h"

#include <string>

#include "rotorid/core/text.h"
#include "rotorid/predict/predict.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/input_json.h"
#include "rotorid/report/json.h"

namespace rotorid {
namespace {

// {group: [MAE(1), ..., MAE(N)]} for the verified groups.
nlohmann::json CurvesJson(const std::array<std::vector<double>, kNumPredictionGroups>& curves) {
  nlohmann::json out = nlohmann::json::object();
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    if (curves[g].empty()) continue;
    nlohmann::json values = nlohmann::json::array();
    for (double v : curves[g]) values.push_back(JsonNumber(v));
    out[kPredictionGroupNames[g]] = values;
  }
  return out;
}

// {group: {"<h>": MAE(h) / naive MAE(h)}}.
nlohmann::json RatiosAtSteps(const PredictionCurves& curves, const std::vector<int>& steps) {
  std::array<std::vector<double>, kNumPredictionGroups> ratios;
  for (int g = 0; g < kNumPredictionGroups; ++g)
    for (size_t h = 0; h < curves.mae[g].size(); ++h) ratios[g].push_back(curves.mae[g][h] / curves.naive_mae[g][h]);
  return internal::GroupsAtSteps(ratios, steps);
}

nlohmann::json FlightsJson(const PredictResult& result, const std::vector<int>& steps) {
  nlohmann::json flights = nlohmann::json::array();
  for (const FlightPrediction& f : result.flights) {
    flights.push_back({{"file", f.file},
                       {"windows", f.curves.windows},
                       {"states", f.states},
                       {"mae", internal::GroupsAtSteps(f.curves.mae, steps)},
                       {"naive_mae", internal::GroupsAtSteps(f.curves.naive_mae, steps)},
                       {"ratio_to_naive", RatiosAtSteps(f.curves, steps)}});
  }
  return flights;
}

std::string GroundRule(const PredictOptions& o) {
  if (o.scope == PredictionScope::kWhole) return "every window inside the flight";
  return "every sample of the window airborne: rotor thrust kt sum Omega^2 at least " +
         std::to_string(o.airborne_thrust_share) + " of the weight, or O_d at least " +
         std::to_string(o.ground_clearance_m) + " m above the lowest logged height (or the log's ground_z)";
}

}  // namespace

nlohmann::json PredictJson(const PredictResult& result) {
  const PredictOptions& o = result.options;
  const std::vector<int> steps = PredictionSummarySteps(o.horizon_steps);
  nlohmann::json settings = {{"horizon_steps", o.horizon_steps},
                             {"stride", o.stride},
                             {"dt_s", o.dt_s},
                             {"scope", PredictionScopeName(o.scope)},
                             {"segment", o.segment == SegmentMode::kAuto ? "auto" : "none"},
                             {"rotor_signal", o.source.rotor_signal},
                             {"torque_bias_window_s", o.torque_bias_window_s},
                             {"parameter_overrides", o.parameter_overrides}};
  nlohmann::json prediction = {{"horizon_steps", o.horizon_steps},
                               {"dt_s", o.dt_s},
                               {"scope", PredictionScopeName(o.scope)},
                               {"scope_rule", GroundRule(o)},
                               {"stride", o.stride},
                               {"block", result.block},
                               {"windows", result.pooled.windows},
                               {"mae", CurvesJson(result.pooled.mae)},
                               {"naive_mae", CurvesJson(result.pooled.naive_mae)},
                               {"ratio_to_naive", RatiosAtSteps(result.pooled, steps)},
                               {"flights", FlightsJson(result, steps)}};
  return {{"rotorid_version", kRotoridVersion},
          {"command", "predict"},
          {"params", o.params_path},
          {"block", result.block},
          {"settings", settings},
          {"prediction", prediction},
          {"input", InputJson(result.inputs)},
          {"checks", ChecksJson(result.checks)}};
}

std::string PredictBriefReport(const PredictResult& result) {
  const PredictOptions& o = result.options;
  const std::vector<int> steps = PredictionSummarySteps(o.horizon_steps);
  std::string text = "rotorid predict: " + result.block + " model of " + o.params_path + ", " +
                     std::to_string(result.pooled.windows) + " windows (" + PredictionScopeName(o.scope) + ")" +
                     (o.torque_bias_window_s > 0.0 ? ", torque bias observed over " +
                                                         ShortNumber(o.torque_bias_window_s) + " s before each start"
                                                   : "") +
                     "\nMAE model / naive at h =";
  for (int h : steps) text += " " + std::to_string(h);
  text += " steps\n";
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    if (result.pooled.mae[g].empty()) continue;
    const std::string name = kPredictionGroupNames[g];
    text += "  " + name + std::string(17 - name.size(), ' ');
    for (int h : steps)
      text += "  " + ShortNumber(result.pooled.mae[g][h - 1]) + " / " + ShortNumber(result.pooled.naive_mae[g][h - 1]);
    text += "\n";
  }
  return text;
}

namespace internal {

nlohmann::json GroupsAtSteps(const std::array<std::vector<double>, kNumPredictionGroups>& curves,
                             const std::vector<int>& steps) {
  nlohmann::json out = nlohmann::json::object();
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    if (curves[g].empty()) continue;
    nlohmann::json at = nlohmann::json::object();
    for (int h : steps) at[std::to_string(h)] = JsonNumber(curves[g][h - 1]);
    out[kPredictionGroupNames[g]] = at;
  }
  return out;
}

}  // namespace internal
}  // namespace rotorid

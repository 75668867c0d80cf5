#include "predict/predict_json.h"

#include <algorithm>
#include <cmath>
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

// {roll, pitch, yaw} of a per-axis value (`axes` of them).
nlohmann::json AxesJson(const Eigen::Vector3d& value, int axes = 3) {
  static constexpr const char* kAxes[3] = {"roll", "pitch", "yaw"};
  nlohmann::json out = nlohmann::json::object();
  for (int a = 0; a < axes; ++a) out[kAxes[a]] = JsonNumber(value[a]);
  return out;
}

nlohmann::json TorqueBandsJson(const std::vector<TorqueBand>& bands) {
  nlohmann::json out = nlohmann::json::array();
  for (const TorqueBand& b : bands)
    out.push_back({{"band", TorqueBandName(b)},
                   {"low_hz", b.low_hz},
                   {"high_hz", JsonNumber(b.high_hz)},
                   {"samples", b.samples},
                   {"body_rms_radps2", AxesJson(b.body_rms_radps2)},
                   {"model_rms_radps2", AxesJson(b.model_rms_radps2)},
                   {"error_rms_radps2", AxesJson(b.error_rms_radps2)},
                   {"gain", AxesJson(b.gain)},
                   {"correlation", AxesJson(b.correlation)},
                   {"error_torque_rms_nm", AxesJson(b.error_torque_rms_nm)},
                   {"centre_of_mass_equivalent_mm", AxesJson(b.centre_of_mass_equivalent_mm, 2)}});
  return out;
}

nlohmann::json FlightsJson(const PredictResult& result, const std::vector<int>& steps) {
  nlohmann::json flights = nlohmann::json::array();
  for (const FlightPrediction& f : result.flights) {
    flights.push_back({{"file", f.file},
                       {"windows", f.curves.windows},
                       {"states", f.states},
                       {"mae", internal::GroupsAtSteps(f.curves.mae, steps)},
                       {"naive_mae", internal::GroupsAtSteps(f.curves.naive_mae, steps)},
                       {"ratio_to_naive", RatiosAtSteps(f.curves, steps)},
                       {"torque_bands", TorqueBandsJson(f.torque_bands)}});
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
                               {"torque_bands", TorqueBandsJson(result.torque_bands)},
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

std::string PredictAnswer(const PredictResult& result) {
  const double dt = result.options.dt_s;
  std::string text = "Against the naive predictor x(t+h) = x(t):";
  const char* separator = " ";
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    const std::vector<double>& mae = result.pooled.mae[g];
    if (mae.empty()) continue;
    size_t below = 0;  // steps ahead before the model's error first reaches naive's
    while (below < mae.size() && mae[below] < result.pooled.naive_mae[g][below]) ++below;
    std::string group = kPredictionGroupNames[g];
    std::replace(group.begin(), group.end(), '_', ' ');
    text += separator + group + " " +
            (below == mae.size() ? "below it over the whole " + ShortNumber(dt * mae.size()) + " s"
             : below == 0        ? "above it from the first step"
                                 : "below it up to " + ShortNumber(dt * below) + " s");
    separator = "; ";
  }
  text += ".";
  std::string apart;
  for (const TorqueBand& b : result.torque_bands) {
    if (!std::isfinite(b.gain[0]) || !std::isfinite(b.high_hz)) continue;  // the mean; above 10 Hz: gyro noise
    if (std::min(b.gain[0], b.gain[1]) >= 0.7 && std::max(b.gain[0], b.gain[1]) <= 1.3) continue;
    apart += (apart.empty() ? "" : ", ") + TorqueBandName(b) + " (gain " + TorqueBandGainText(b) + ", error " +
             ShortNumber(b.centre_of_mass_equivalent_mm[0]) + " / " + ShortNumber(b.centre_of_mass_equivalent_mm[1]) +
             " mm of centre of mass)";
  }
  if (!apart.empty())
    text += " The body does not turn as the model's roll / pitch torque says in " + apart +
            ": a torque the model lacks there, which a horizon integrates.";
  return text;
}

std::string PredictBriefReport(const PredictResult& result) {
  const PredictOptions& o = result.options;
  const std::vector<int> steps = PredictionSummarySteps(o.horizon_steps);
  std::string text = PredictAnswer(result) + "\nrotorid predict: " + result.block + " model of " + o.params_path + ", " +
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
  if (result.torque_bands.empty()) return text;
  text += "the model's angular acceleration at the logged states against the body's (roll / pitch, RMS rad/s^2;\n"
          "gain: the body's per unit of the model's; the error as the centre-of-mass shift whose weight exerts it)\n";
  for (const TorqueBand& b : result.torque_bands) {
    const auto pair = [](const Eigen::Vector3d& v) { return ShortNumber(v[0]) + " / " + ShortNumber(v[1]); };
    const std::string name = TorqueBandName(b);
    text += "  " + name + std::string(name.size() < 12 ? 12 - name.size() : 1, ' ') + "body " +
            pair(b.body_rms_radps2) + "  model " + pair(b.model_rms_radps2) + "  error " + pair(b.error_rms_radps2) +
            "  gain " + TorqueBandGainText(b) + "  error " +
            pair(b.centre_of_mass_equivalent_mm) + " mm\n";
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

#include "rotorid/predict/predict.h"

#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "predict/rollout.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/model/physical_consistency.h"
#include "rotorid/report/export.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"

namespace rotorid {

PredictionScope ParsePredictionScope(const std::string& text) {
  if (text == "airborne") return PredictionScope::kAirborne;
  if (text == "whole") return PredictionScope::kWhole;
  throw Error("--scope must be airborne or whole, got '" + text + "'");
}

const char* PredictionScopeName(PredictionScope scope) {
  return scope == PredictionScope::kAirborne ? "airborne" : "whole";
}

std::pair<std::string, double> ParseParameterOverride(const std::string& text) {
  const size_t equals = text.find('=');
  const std::string why = "--set takes NAME=VALUE (a report parameter and a number), got '" + text + "'";
  if (equals == std::string::npos || equals == 0) throw Error(why);
  try {
    size_t used = 0;
    const double value = std::stod(text.substr(equals + 1), &used);
    if (used != text.size() - equals - 1 || !std::isfinite(value)) throw Error(why);
    return {text.substr(0, equals), value};
  } catch (const std::logic_error&) {
    throw Error(why);
  }
}

std::string PredictOptions::Validate() const {
  if (params_path.empty()) return "--params is required";
  if (!block.empty() && block != "linear" && block != "refined")
    return "--block must be linear or refined, got '" + block + "'";
  if (log_paths.empty()) return "give at least one --vehicle/--log pair";
  if (vehicle_paths.size() != log_paths.size())
    return "got " + std::to_string(vehicle_paths.size()) + " vehicle files for " + std::to_string(log_paths.size()) +
           " --log; give one per log, in the same order";
  if (!windows.empty() && windows.size() != log_paths.size())
    return "got " + std::to_string(windows.size()) + " windows for " + std::to_string(log_paths.size()) +
           " --log; give one per log, in the same order";
  if (horizon_steps < 1) return "--horizon must be at least 1 step, got " + std::to_string(horizon_steps);
  if (stride < 1) return "--stride must be at least 1, got " + std::to_string(stride);
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return "--dt must be a positive number of seconds";
  if (!(ground_clearance_m >= 0.0) || !(airborne_thrust_share >= 0.0)) return "the ground-contact rule must be >= 0";
  if (!(torque_bias_window_s >= 0.0) || !std::isfinite(torque_bias_window_s))
    return "--torque-bias-window must be a number of seconds >= 0";
  if (threads < 0) return "threads must be >= 0";
  return source.Validate();
}

std::vector<int> PredictionSummarySteps(int horizon_steps) {
  std::vector<int> steps;
  for (int h : {1, 10, horizon_steps})
    if (h <= horizon_steps && (steps.empty() || h > steps.back())) steps.push_back(h);
  return steps;
}

namespace {

// The model of `vehicle`'s configuration in the report: the values it predicts with (a discarded
// inertia's profiled estimate, INTERFACE.md 5's predicts_with) unless `overrides` replaces them, the
// refined block's effects.
internal::FlownModel FlownModelFromReport(const nlohmann::json& report, const std::string& source,
                                          const Vehicle& vehicle, const std::string& block,
                                          const std::map<std::string, double>& overrides) {
  IdentifiedModel identified = IdentifiedModelFromReport(report, source, vehicle, block);
  const PredictedModel predicted = PredictedParameters(report, source, identified.block);
  for (const auto& [name, value] : predicted.values)
    if (identified.parameters.count(name)) identified.parameters[name].value = value;
  for (const auto& [name, value] : overrides) {
    if (!identified.parameters.count(name))
      throw Error(source + ": no parameter '" + name + "' in its " + identified.block + " block to replace");
    identified.parameters[name].value = value;
  }
  std::map<std::string, double> values;
  for (const auto& [name, entry] : identified.parameters) values[name] = entry.value;
  internal::FlownModel model = internal::FlownModelFromValues(values, predicted.effects, vehicle);
  model.source = source;
  model.block = identified.block;
  return model;
}

Check PhysicalConsistencyCheck(const Vehicle& vehicle, const VehicleParameters& parameters) {
  const PhysicalConsistency consistency = CheckPhysicalConsistency(parameters.mass_kg, parameters.body);
  Check check{"physical_consistency", CheckStatus::kOk, ""};
  const std::string what = "configuration '" + vehicle.name + "', the values the model predicts with";
  if (consistency.consistent) {
    check.message = what + ": a possible body (RMS extents " + ShortNumber(1e3 * consistency.rms_extent_m[0]) + ", " +
                    ShortNumber(1e3 * consistency.rms_extent_m[1]) + ", " +
                    ShortNumber(1e3 * consistency.rms_extent_m[2]) + " mm)";
  } else {
    check.status = CheckStatus::kError;
    check.message = what + ": " + consistency.problem +
                    "; the prediction flies a body no airframe has (MODEL.md 10): do not trust its errors";
  }
  return check;
}

// `rotorid simulate --truth` JSON (plain numbers under "parameters" and "effects") read as a refine
// report whose refined block holds the simulator's true parameters and effects: the model flown is
// then the simulator's own. Any other JSON is returned as it is.
nlohmann::json ReportOrTruth(nlohmann::json report) {
  if (report.contains("linear") || report.contains("refined") || !report.contains("parameters") ||
      !report.contains("effects") || !report["parameters"].is_object())
    return report;
  nlohmann::json refined = {{"parameters", nlohmann::json::object()}, {"effects", nlohmann::json::object()}};
  for (const auto& [name, value] : report["parameters"].items())
    refined["parameters"][name] = {{"value", value}, {"std", 0.0}, {"essential", true}};
  for (const auto& [name, value] : report["effects"].items())
    refined["effects"][name] = {{"value", value}, {"enabled", true}};
  return {{"refined", refined}};
}

// The log read whole, its lowest height kept as the ground for the airborne rule, then cut to its
// window and segmented as every command does.
SelectedFlight ReadFlight(const PredictOptions& options, size_t i, const Vehicle& vehicle) {
  FlightLog log = LoadFlightLog(options.log_paths[i], vehicle, options.source);
  if (log.mocap && !log.metadata.count("ground_z") && log.num_samples() > 0)
    log.metadata["ground_z"] = FormatValue("%.17g", log.mocap->position_w_m.col(2).minCoeff());
  return SelectFlight(std::move(log), options.log_paths[i], options.windows.empty() ? std::nullopt : options.windows[i],
                      options.segment);
}

}  // namespace

namespace internal {

FlownModel FlownModelFromValues(const std::map<std::string, double>& values, const Effects& effects,
                                const Vehicle& vehicle) {
  const auto value = [&values](const std::string& name) {
    const auto it = values.find(name);
    return it == values.end() ? 0.0 : it->second;
  };
  FlownModel model;
  model.parameters.mass_kg = vehicle.mass_kg;
  model.parameters.rotor = {value("kt"), value("kd")};
  Eigen::VectorXd chi(kNumBodyParameters);
  for (int k = 0; k < kNumBodyParameters; ++k) chi[k] = value(vehicle.name + "." + kBodyParameterNames[k]);
  model.parameters.body = BodyParameters::FromVector(chi);
  model.effects = effects;
  return model;
}

ErrorSums ScoreSegments(const std::vector<FlightLog>& segments, const Vehicle& vehicle, const FlownModel& model,
                        const ObservationOptions& observation, const PredictOptions& options, std::string* states) {
  ErrorSums sums(options.horizon_steps, false);
  for (const FlightLog& segment : segments) {
    if (segment.duration_s() < options.horizon_steps * options.dt_s) continue;  // no window fits
    const LoggedStates logged = ReadLoggedStates(segment, vehicle, model, observation, options);
    sums.Add(ScoreFlight(logged, vehicle, model, options));
    if (states) *states = logged.description;
  }
  return sums;
}

}  // namespace internal

PredictResult RunPredict(const PredictOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  PredictResult result;
  result.options = options;
  const nlohmann::json report = ReportOrTruth(ReadJsonFile(options.params_path));
  const ObservationOptions observation = ObservationOptionsFromJson(
      report.contains("settings") && report["settings"].contains("observation") ? report["settings"]["observation"]
                                                                                : nlohmann::json());
  internal::ErrorSums pooled(options.horizon_steps, false);
  std::set<std::string> checked_configs;
  for (size_t i = 0; i < options.log_paths.size(); ++i) {
    const Vehicle vehicle = ReadVehicleYaml(options.vehicle_paths[i]);
    const internal::FlownModel model =
        FlownModelFromReport(report, options.params_path, vehicle, options.block, options.parameter_overrides);
    result.block = model.block;
    if (checked_configs.insert(vehicle.name).second)
      result.checks.push_back(PhysicalConsistencyCheck(vehicle, model.parameters));
    SelectedFlight selected = ReadFlight(options, i, vehicle);
    FlightPrediction flight;
    flight.file = options.log_paths[i];
    const internal::ErrorSums sums =
        internal::ScoreSegments(selected.segments, vehicle, model, observation, options, &flight.states);
    flight.curves = sums.Mean();
    flight.torque_bands = sums.torque.Mean();
    pooled.Add(sums);
    result.flights.push_back(std::move(flight));
    result.inputs.push_back(std::move(selected.summary));
  }
  result.pooled = pooled.Mean();
  result.torque_bands = pooled.torque.Mean();
  if (result.pooled.windows == 0)
    throw Error("no window of " + std::to_string(options.horizon_steps) + " steps of " + ShortNumber(options.dt_s) +
                " s lies in the " + PredictionScopeName(options.scope) +
                " scope of the given flights (shorter --horizon, or --scope whole)");
  return result;
}

}  // namespace rotorid

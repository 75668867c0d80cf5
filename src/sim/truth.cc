#include "rotorid/sim/truth.h"

#include <nlohmann/json.hpp>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"

namespace rotorid {
namespace {

using Json = nlohmann::ordered_json;

Json Vector(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }
Json Range(const Eigen::Vector2d& v) { return Json::array({v.x(), v.y()}); }

Json NoiseJson(const NoiseLevels& noise) {
  return Json{{"preset", noise.name},
              {"gyro_std_radps", noise.gyro_std_radps},
              {"acc_std_mps2", noise.acc_std_mps2},
              {"mocap_position_std_m", noise.mocap_position_std_m},
              {"mocap_angle_std_rad", noise.mocap_angle_std_rad}};
}

Json OptionsJson(const SimulationResult& result) {
  const SimulationOptions& o = result.options;
  Json options{{"duration_s", o.duration_s},
               {"samples", result.log.num_samples()},
               {"log_rate_hz", o.log_rate_hz},
               {"physics_rate_hz", o.physics_rate_hz},
               {"integrator", "RK4"},
               {"gravity_mps2", o.gravity_mps2},
               {"mocap", o.mocap},
               {"jitter_s", o.jitter_s},
               {"excitation", o.excitation},
               {"hover_altitude_m", o.hover_altitude_m},
               {"hover_lead_in_s", o.hover_lead_in_s},
               {"warmup_s", o.warmup_s}};
  // Only when used, so that the paper-like flights' truth files keep their bytes.
  if (o.profile != FlightProfile::kPaper) options["profile"] = FlightProfileName(o.profile);
  if (o.profile == FlightProfile::kCircle) {
    options["circle_radius_m"] = o.circle_radius_m;
    options["circle_speed_mps"] = o.circle_speed_mps;
  }
  if (o.battery.enabled)
    options["battery"] = Json{{"full_v", o.battery.full_v},
                              {"empty_v", o.battery.empty_v},
                              {"hover_sag_v", o.battery.hover_sag_v},
                              {"reference_voltage_v", result.vehicle.command_to_speed_voltage_v.value_or(0.0)},
                              {"command_to_speed", Vector(result.vehicle.command_to_speed->coefficients)}};
  if (o.external_force.active())
    options["external_force"] =
        Json{{"world_n", Vector(o.external_force.world_n)}, {"turn_period_s", o.external_force.turn_period_s}};
  return options;
}

Json ControllerJson(const SimulationResult& result) {
  const ControllerModelSummary& c = result.controller;
  return Json{{"kt", c.kt},
              {"kd", c.kd},
              {"inertia_diagonal", Vector(c.inertia_diagonal)},
              {"first_moment", Json::array({0.0, 0.0, 0.0})},
              {"hover_speed_radps", c.hover_speed_radps}};
}

const Json& Require(const Json& object, const char* key, const std::string& where, const std::string& source) {
  if (!object.is_object() || !object.contains(key))
    throw Error(source + ": missing '" + where + (where.empty() ? "" : ".") + key + "' in the truth file");
  return object.at(key);
}

double Number(const Json& value, const std::string& what, const std::string& source) {
  if (!value.is_number()) throw Error(source + ": '" + what + "' must be a number");
  return value.get<double>();
}

}  // namespace

std::string TruthToJson(const SimulationResult& result) {
  Json parameters;
  parameters["kt"] = result.truth.rotor.kt;
  parameters["kd"] = result.truth.rotor.kd;
  const auto chi = result.truth.body.ToVector();
  for (int j = 0; j < kNumBodyParameters; ++j) parameters[result.vehicle.name + "." + kBodyParameterNames[j]] = chi[j];
  Json effects = Json::object();
  for (EffectKind kind : AllEffects()) {
    const Eigen::VectorXd value = result.effects.Get(kind).size() > 0
                                      ? result.effects.Get(kind)
                                      : Eigen::VectorXd::Zero(kind->Dimension(result.vehicle));
    const std::vector<std::string>& labels = kind->info().labels;
    if (!labels.empty()) {  // one key per coefficient, as INTERFACE.md names them
      for (size_t k = 0; k < labels.size(); ++k) effects[labels[k]] = value[static_cast<Eigen::Index>(k)];
    } else {
      effects[kind->parameter_name()] = kind->FixedDimension() == 1
                                            ? Json(value[0])
                                            : Json(std::vector<double>(value.data(), value.data() + value.size()));
    }
  }

  Json truth;
  truth["vehicle"] = result.vehicle.name;
  truth["mass"] = result.truth.mass_kg;
  truth["parameters"] = parameters;
  truth["effects"] = effects;
  truth["noise"] = NoiseJson(result.noise);
  truth["seed"] = result.options.seed;
  truth["parameters_source"] = result.parameters_source;
  truth["simulation"] = OptionsJson(result);
  truth["controller_model"] = ControllerJson(result);
  return truth.dump(2) + "\n";
}

void WriteTruthJson(const std::string& path, const SimulationResult& result) {
  WriteFileAtomically(path, TruthToJson(result));
}

SimulationTruth ParseTruthJson(const std::string& text, const std::string& source) {
  Json root;
  try {
    root = Json::parse(text);
  } catch (const Json::exception& e) {
    throw Error(source + ": not valid JSON: " + e.what());
  }
  SimulationTruth truth;
  const Json& vehicle = Require(root, "vehicle", "", source);
  if (!vehicle.is_string()) throw Error(source + ": 'vehicle' must be a string");
  truth.vehicle_name = vehicle.get<std::string>();
  truth.parameters.mass_kg = Number(Require(root, "mass", "", source), "mass", source);
  const Json& parameters = Require(root, "parameters", "", source);
  truth.parameters.rotor.kt = Number(Require(parameters, "kt", "parameters", source), "parameters.kt", source);
  truth.parameters.rotor.kd = Number(Require(parameters, "kd", "parameters", source), "parameters.kd", source);
  Eigen::VectorXd chi(kNumBodyParameters);
  for (int j = 0; j < kNumBodyParameters; ++j) {
    const std::string name = truth.vehicle_name + "." + kBodyParameterNames[j];
    chi[j] = Number(Require(parameters, name.c_str(), "parameters", source), "parameters." + name, source);
  }
  truth.parameters.body = BodyParameters::FromVector(chi);
  const Json& effects = Require(root, "effects", "", source);
  if (!effects.is_object()) throw Error(source + ": 'effects' must be an object");
  // Effects a truth file does not list (written before they existed) are absent.
  for (EffectKind kind : AllEffects()) {
    const std::vector<std::string>& labels = kind->info().labels;
    if (!labels.empty()) {
      Eigen::VectorXd v = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(labels.size()));
      bool listed = false;
      for (size_t k = 0; k < labels.size(); ++k)
        if (effects.contains(labels[k])) {
          v[static_cast<Eigen::Index>(k)] = Number(effects.at(labels[k]), "effects." + labels[k], source);
          listed = true;
        }
      if (listed) truth.effects.Set(kind, v);
      continue;
    }
    const std::string& name = kind->parameter_name();
    if (!effects.contains(name)) continue;
    const Json& value = effects.at(name);
    const std::string what = "effects." + name;
    if (kind->FixedDimension() == 1) {
      truth.effects.Set(kind, Number(value, what, source));
    } else {
      if (!value.is_array()) throw Error(source + ": '" + what + "' must be a list of numbers");
      Eigen::VectorXd v(static_cast<Eigen::Index>(value.size()));
      for (size_t k = 0; k < value.size(); ++k) v[static_cast<Eigen::Index>(k)] = Number(value[k], what, source);
      truth.effects.Set(kind, v);
    }
  }
  if (root.contains("seed") && root["seed"].is_number_unsigned()) truth.seed = root["seed"].get<std::uint64_t>();
  if (root.contains("noise") && root["noise"].is_object() && root["noise"].contains("preset") &&
      root["noise"]["preset"].is_string())
    truth.noise_preset = root["noise"]["preset"].get<std::string>();
  return truth;
}

SimulationTruth ReadTruthJson(const std::string& path) { return ParseTruthJson(ReadFile(path), path); }

std::string SimulationReportJson(const SimulationResult& result, const std::map<std::string, std::string>& outputs) {
  const FlightSummary& s = result.summary;
  Json summary{{"duration_s", s.duration_s},
               {"samples", s.num_samples},
               {"roll_range_deg", Range(s.roll_range_deg)},
               {"pitch_range_deg", Range(s.pitch_range_deg)},
               {"yaw_rate_range_radps", Range(s.yaw_rate_range_radps)},
               {"altitude_range_m", Range(s.altitude_range_m)},
               {"max_tilt_deg", s.max_tilt_deg},
               {"max_horizontal_distance_m", s.max_horizontal_distance_m},
               {"angular_acceleration_rms_radps2", Vector(s.angular_acceleration_rms_radps2)},
               {"thrust_rms_variation_pct", s.thrust_rms_variation_pct},
               {"rotor_speed_range_radps", Range(s.rotor_speed_range_radps)}};
  if (result.options.battery.enabled) summary["voltage_range_v"] = Range(s.voltage_range_v);
  Json outputs_json = Json::object();
  for (const auto& [role, path] : outputs) outputs_json[role] = path;
  Json report;
  report["command"] = "simulate";
  report["vehicle"] = result.vehicle.name;
  report["seed"] = result.options.seed;
  report["parameters_source"] = result.parameters_source;
  report["options"] = OptionsJson(result);
  report["noise"] = NoiseJson(result.noise);
  report["summary"] = summary;
  report["outputs"] = outputs_json;
  return report.dump(2) + "\n";
}

}  // namespace rotorid

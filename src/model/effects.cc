#include "rotorid/model/effects.h"

#include <cmath>
#include <sstream>

#include "rotorid/core/error.h"

namespace rotorid {

const char* EffectName(EffectKind kind) {
  switch (kind) {
    case EffectKind::kDelay: return "delay";
    case EffectKind::kMotorLag: return "motor_lag";
    case EffectKind::kAccBias: return "acc_bias";
    case EffectKind::kGyroBias: return "gyro_bias";
    case EffectKind::kMisalignment: return "misalignment";
  }
  return "?";
}

const char* EffectParameterName(EffectKind kind) {
  switch (kind) {
    case EffectKind::kDelay: return "delay_s";
    case EffectKind::kMotorLag: return "motor_tau_s";
    case EffectKind::kAccBias: return "acc_bias";
    case EffectKind::kGyroBias: return "gyro_bias";
    case EffectKind::kMisalignment: return "misalignment_rad";
  }
  return "?";
}

int EffectDimension(EffectKind kind) {
  return kind == EffectKind::kDelay || kind == EffectKind::kMotorLag ? 1 : 3;
}

EffectKind ParseEffectKind(const std::string& name) {
  for (EffectKind kind : kAllEffectKinds)
    if (name == EffectName(kind) || name == EffectParameterName(kind)) return kind;
  std::string valid;
  for (EffectKind kind : kAllEffectKinds) valid += std::string(valid.empty() ? "" : ", ") + EffectName(kind);
  throw Error("unknown effect '" + name + "'; known effects: " + valid);
}

std::vector<EffectKind> ParseEffectList(const std::string& list) {
  if (list == "all") return {kAllEffectKinds.begin(), kAllEffectKinds.end()};
  std::vector<EffectKind> kinds;
  if (list.empty() || list == "none") return kinds;
  std::stringstream stream(list);
  std::string name;
  while (std::getline(stream, name, ',')) {
    const EffectKind kind = ParseEffectKind(name);
    bool seen = false;
    for (EffectKind k : kinds) seen = seen || k == kind;
    if (!seen) kinds.push_back(kind);
  }
  return kinds;
}

Eigen::VectorXd Effects::Get(EffectKind kind) const {
  switch (kind) {
    case EffectKind::kDelay: return Eigen::VectorXd::Constant(1, delay_s);
    case EffectKind::kMotorLag: return Eigen::VectorXd::Constant(1, motor_tau_s);
    case EffectKind::kAccBias: return acc_bias;
    case EffectKind::kGyroBias: return gyro_bias;
    case EffectKind::kMisalignment: return misalignment_rad;
  }
  return {};
}

void Effects::Set(EffectKind kind, const Eigen::Ref<const Eigen::VectorXd>& value) {
  if (value.size() != EffectDimension(kind))
    throw Error(std::string(EffectParameterName(kind)) + " takes " + std::to_string(EffectDimension(kind)) +
                " value(s), got " + std::to_string(value.size()));
  switch (kind) {
    case EffectKind::kDelay: delay_s = value[0]; break;
    case EffectKind::kMotorLag: motor_tau_s = value[0]; break;
    case EffectKind::kAccBias: acc_bias = value; break;
    case EffectKind::kGyroBias: gyro_bias = value; break;
    case EffectKind::kMisalignment: misalignment_rad = value; break;
  }
}

void Effects::Assign(const std::string& assignment) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos) throw Error("effect '" + assignment + "' must be written name=value or name=x,y,z");
  const EffectKind kind = ParseEffectKind(assignment.substr(0, eq));
  std::vector<double> values;
  std::stringstream stream(assignment.substr(eq + 1));
  std::string item;
  while (std::getline(stream, item, ',')) {
    size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v))
      throw Error("effect '" + assignment + "': '" + item + "' is not a number");
    values.push_back(v);
  }
  if (kind == EffectKind::kMotorLag && !values.empty() && values[0] < 0.0)
    throw Error("motor_tau_s must not be negative");
  Set(kind, Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size())));
}

}  // namespace rotorid

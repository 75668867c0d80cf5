#include "rotorid/model/effects.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <locale>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/core/vehicle.h"

namespace rotorid {
namespace {

std::string FormatNumber(double value) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(10) << value;
  return out.str();
}

[[noreturn]] void NotOfStage(const EffectDescriptor& effect, const char* hook) {
  throw Error(std::string("internal: effect '") + effect.name() + "' has no " + hook);
}

}  // namespace

bool FlightInputs::Has(FlightInput input) const {
  switch (input) {
    case FlightInput::kVelocity:
      return velocity;
    case FlightInput::kHeight:
      return height;
    case FlightInput::kVoltage:
      return voltage;
    case FlightInput::kRotorAcceleration:
      return rotor_acceleration;
    case FlightInput::kSpecificForceRates:
      return specific_force_rates;
    case FlightInput::kRotorCommand:
      return rotor_command;
    case FlightInput::kRotorRadius:
      return rotor_radius;
  }
  return false;
}

const char* FlightInputName(FlightInput input) {
  switch (input) {
    case FlightInput::kVelocity:
      return "the velocity (motion capture or velocity columns)";
    case FlightInput::kHeight:
      return "the height above ground (motion capture or a height column)";
    case FlightInput::kVoltage:
      return "the battery voltage";
    case FlightInput::kRotorAcceleration:
      return "the rotor acceleration";
    case FlightInput::kSpecificForceRates:
      return "the accelerometer's derivatives";
    case FlightInput::kRotorCommand:
      return "the raw motor command (a command log with a command-to-speed map)";
    case FlightInput::kRotorRadius:
      return "the propeller radius (rotor_radius in the vehicle file)";
  }
  return "?";
}

int EffectDescriptor::Dimension(const Vehicle& vehicle) const {
  return info_.per_rotor ? vehicle.num_rotors() : info_.dimension;
}

std::string EffectDescriptor::Unavailable(const FlightInputs& available) const {
  std::string missing;
  for (FlightInput input : info_.inputs)
    if (!available.Has(input)) missing += (missing.empty() ? "" : " and ") + std::string(FlightInputName(input));
  return missing.empty() ? std::string() : info_.name + " needs " + missing + ", which this flight lacks";
}

std::vector<std::string> EffectDescriptor::Labels(int dimension) const {
  if (static_cast<int>(info_.labels.size()) == dimension) return info_.labels;
  if (dimension == 1 && !info_.per_rotor) return {info_.parameter_name};
  std::vector<std::string> labels;
  const char* axes[3] = {"_x", "_y", "_z"};
  for (int k = 0; k < dimension; ++k)
    labels.push_back(info_.parameter_name +
                     (dimension == 3 && !info_.per_rotor ? std::string(axes[k]) : "_" + std::to_string(k + 1)));
  return labels;
}

bool EffectDescriptor::Held(int coordinate) const {
  return std::find(info_.held_coordinates.begin(), info_.held_coordinates.end(), coordinate) !=
         info_.held_coordinates.end();
}

std::vector<std::string> EffectDescriptor::HeldLabels(int dimension) const {
  const std::vector<std::string> labels = Labels(dimension);
  std::vector<std::string> held;
  for (int k : info_.held_coordinates)
    if (k < dimension) held.push_back(labels[static_cast<size_t>(k)]);
  return held;
}

std::string EffectDescriptor::Format(const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) const {
  const double unit = info_.display_scale;
  std::ostringstream out;
  auto entry = [&](Eigen::Index k) {
    if (std::isinf(value[k])) {  // a detectable size that none reaches
      out << "unobservable";
      return;
    }
    out << std::setprecision(3) << value[k] * unit;
    if (Held(static_cast<int>(k)))
      out << " held";
    else if (k < std_dev.size())
      out << " +- " << std::setprecision(2) << std_dev[k] * unit;
  };
  if (value.size() == 1) {
    entry(0);
  } else {
    out << "(";
    for (Eigen::Index k = 0; k < value.size(); ++k) {
      if (k) out << ", ";
      entry(k);
    }
    out << ")";
  }
  if (!info_.display_unit.empty()) out << " " << info_.display_unit;
  return out.str();
}

std::string EffectDescriptor::CheckSimulatable(const Eigen::VectorXd& value) const {
  const SimulatorLimit& limit = info_.simulator_limit;
  if (limit.low == 0.0 && limit.high == 0.0 && !value.isZero(0.0))
    return info_.parameter_name + ": rotorid's simulator does not model " + info_.name;
  if (limit.per_coordinate) {
    for (Eigen::Index k = 0; k < value.size(); ++k)
      if (!std::isfinite(value[k]) || value[k] < limit.low || value[k] > limit.high)
        return info_.parameter_name + " must be within [" + FormatNumber(limit.low) + ", " + FormatNumber(limit.high) +
               "] " + info_.unit + " (got " + FormatNumber(value[k]) + ")";
    return {};
  }
  if (!value.allFinite() || value.norm() > limit.high)
    return info_.parameter_name + " must be finite with norm <= " + FormatNumber(limit.high) + " " + info_.unit;
  return {};
}

namespace {

// The size a physical range scales with, for this vehicle.
double PlausibleScaleOf(PlausibleScale scale, const Vehicle& vehicle) {
  const double arm_m = vehicle.MeanArm();
  switch (scale) {
    case PlausibleScale::kNone:
      return 1.0;
    case PlausibleScale::kArmLength:
      return arm_m;
    case PlausibleScale::kMassArmSquared:
      return vehicle.mass_kg * arm_m * arm_m;
  }
  return 1.0;
}

double StdAt(const Eigen::VectorXd& std_dev, Eigen::Index k) { return k < std_dev.size() ? std_dev[k] : 0.0; }

// The norm of `value` and its std along the estimate's direction.
std::pair<double, double> NormAndStd(const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) {
  const double norm = value.norm();
  double variance = 0.0;
  for (Eigen::Index k = 0; k < value.size() && norm > 0.0; ++k)
    variance += std::pow(value[k] / norm * StdAt(std_dev, k), 2);
  return {norm, std::sqrt(variance)};
}

constexpr double kRangeStd = 3.0;  // an estimate within 3 std of a range's edge may lie on its side

std::string Shown(const EffectDescriptor& kind, double v) { return kind.Format(Eigen::VectorXd::Constant(1, v), {}); }

}  // namespace

std::string EffectDescriptor::Implausible(const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev,
                                          const Vehicle& vehicle) const {
  const PlausibleRange& range = info_.plausible;
  const double scale = PlausibleScaleOf(range.scale, vehicle);
  const double low = range.low * scale, high = range.high * scale;
  const std::string because = range.why.empty() ? "" : ": " + range.why;
  if (range.per_coordinate) {
    const std::vector<std::string> labels = Labels(static_cast<int>(value.size()));
    for (Eigen::Index k = 0; k < value.size(); ++k)
      if (value[k] < low - kRangeStd * StdAt(std_dev, k) || value[k] > high + kRangeStd * StdAt(std_dev, k))
        return (value.size() == 1 ? info_.parameter_name : labels[static_cast<size_t>(k)]) + " = " +
               Format(value.segment(k, 1),
                      std_dev.size() > k ? Eigen::VectorXd(std_dev.segment(k, 1)) : Eigen::VectorXd()) +
               " is outside its physical range [" + (std::isfinite(low) ? Shown(*this, low) : "-inf") + ", " +
               (std::isfinite(high) ? Shown(*this, high) : "inf") + "]" + because;
    return {};
  }
  const auto [norm, norm_std] = NormAndStd(value, std_dev);
  if (norm > high + kRangeStd * norm_std)
    return info_.parameter_name + " = " + Format(value, std_dev) + " (norm " + Shown(*this, norm) +
           ") is outside its physical range (norm <= " + Shown(*this, high) + ")" + because;
  return {};
}

std::string EffectDescriptor::UnstatedReference(const Eigen::VectorXd& value, const Vehicle& vehicle) const {
  if (info_.relative_to_known.empty() || vehicle.known_effects.count(info_.relative_to_known) > 0) return "";
  return info_.reads_without_it(value);
}

std::string EffectDescriptor::Negligible(const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) const {
  const PlausibleRange& range = info_.plausible;
  const double floor = info_.negligible.below;
  if (floor <= 0.0) return {};
  Eigen::VectorXd free = value;  // held coordinates are not estimated
  for (int k : info_.held_coordinates)
    if (k < free.size()) free[k] = 0.0;
  double upper = 0.0;  // the estimate's size plus 3 std
  if (range.per_coordinate) {
    for (Eigen::Index k = 0; k < free.size(); ++k)
      upper = std::max(upper, std::abs(free[k]) + kRangeStd * StdAt(std_dev, k));
  } else {
    const auto [norm, norm_std] = NormAndStd(free, std_dev);
    upper = norm + kRangeStd * norm_std;
  }
  if (upper >= floor) return {};
  return info_.parameter_name + " = " + Format(value, std_dev) + " is below " + Shown(*this, floor) +
         (range.per_coordinate ? " in every coordinate" : " in norm") + " (3 std included): " + info_.negligible.why;
}

Eigen::VectorXd EffectDescriptor::Clamp(const Eigen::VectorXd& value) const {
  return value.cwiseMax(info_.lower_bound).cwiseMin(info_.upper_bound);
}

void EffectDescriptor::CorrectImu(const double*, ImuSample<double>*) const { NotOfStage(*this, "IMU model"); }
void EffectDescriptor::CorrectImu(const ImuJet*, ImuSample<ImuJet>*) const { NotOfStage(*this, "IMU model"); }
void EffectDescriptor::CorrectImu(const MidImuJet*, ImuSample<MidImuJet>*) const { NotOfStage(*this, "IMU model"); }
void EffectDescriptor::CorrectImu(const WideImuJet*, ImuSample<WideImuJet>*) const { NotOfStage(*this, "IMU model"); }
void EffectDescriptor::ApplyToSensor(const double*, ImuSample<double>*) const { NotOfStage(*this, "sensor model"); }
void EffectDescriptor::TransformRotorSignal(const double*, const RotorSignalInput&, const Eigen::VectorXd&,
                                            Eigen::VectorXd*) const {
  NotOfStage(*this, "rotor-signal model");
}
void EffectDescriptor::TransformRotorSignal(const RotorJet*, const RotorSignalInput&,
                                            const Eigen::Matrix<RotorJet, -1, 1>&,
                                            Eigen::Matrix<RotorJet, -1, 1>*) const {
  NotOfStage(*this, "rotor-signal model");
}
Eigen::VectorXd EffectDescriptor::FromEquivalentDelay(double) const { NotOfStage(*this, "equivalent delay"); }
void EffectDescriptor::AddRotorWrench(const double*, const RotorSample<double>&, RotorWrenchTerms<double>*) const {
  NotOfStage(*this, "rotor-wrench model");
}
void EffectDescriptor::AddRotorWrench(const ImuJet*, const RotorSample<ImuJet>&, RotorWrenchTerms<ImuJet>*) const {
  NotOfStage(*this, "rotor-wrench model");
}
void EffectDescriptor::AddRotorWrench(const MidImuJet*, const RotorSample<MidImuJet>&,
                                      RotorWrenchTerms<MidImuJet>*) const {
  NotOfStage(*this, "rotor-wrench model");
}
void EffectDescriptor::AddRotorWrench(const WideImuJet*, const RotorSample<WideImuJet>&,
                                      RotorWrenchTerms<WideImuJet>*) const {
  NotOfStage(*this, "rotor-wrench model");
}

std::vector<EffectKind> EffectsOfStage(EffectStage stage) {
  std::vector<EffectKind> out;
  for (EffectKind kind : AllEffects())
    if (kind->stage() == stage) out.push_back(kind);
  std::stable_sort(out.begin(), out.end(),
                   [](EffectKind a, EffectKind b) { return a->info().chain_position < b->info().chain_position; });
  return out;
}

std::vector<const double*> EffectChain::Parameters() const {
  std::vector<const double*> parameters;
  for (const Eigen::VectorXd& v : values) parameters.push_back(v.data());
  return parameters;
}

EffectChain ActingEffects(const Effects& effects, EffectStage stage, const std::vector<EffectKind>& also) {
  EffectChain chain;
  for (EffectKind kind : EffectsOfStage(stage))
    if (!effects.IsZero(kind) || std::find(also.begin(), also.end(), kind) != also.end()) {
      chain.kinds.push_back(kind);
      chain.values.push_back(effects.Get(kind));
    }
  return chain;
}

Effects KnownEffects(const Vehicle& vehicle) {
  Effects known;
  for (const auto& [name, value] : vehicle.known_effects) known.Set(ParseEffectKind(name), value);
  return known;
}

Eigen::MatrixXd HeldDirections(EffectKind kind, const Vehicle& vehicle, bool kd_free) {
  const int dimension = kind->Dimension(vehicle);
  if (kd_free || !kind->info().spin_pattern_needs_kd || dimension != vehicle.num_rotors()) {
    return Eigen::MatrixXd(dimension, 0);
  }
  Eigen::VectorXd spin(dimension);
  for (int i = 0; i < dimension; ++i) spin[i] = vehicle.rotors[static_cast<size_t>(i)].spin;
  spin.array() -= spin.mean();
  if (spin.norm() == 0.0) return Eigen::MatrixXd(dimension, 0);  // every rotor turning one way
  return spin.normalized();
}

int EffectDimension(EffectKind kind) {
  const int dimension = kind->FixedDimension();
  if (dimension < 0) throw Error(std::string("effect '") + kind->name() + "' has one value per rotor");
  return dimension;
}

EffectKind ParseEffectKind(const std::string& name) {
  for (EffectKind kind : AllEffects())
    if (name == kind->name() || name == kind->parameter_name()) return kind;
  std::string valid;
  for (EffectKind kind : AllEffects()) valid += (valid.empty() ? "" : ", ") + kind->name();
  throw Error("unknown effect '" + name + "'; known effects: " + valid);
}

std::vector<EffectKind> DefaultCandidates() {
  std::vector<EffectKind> kinds;
  for (EffectKind kind : AllEffects())
    if (kind->info().default_candidate) kinds.push_back(kind);
  return kinds;
}

std::vector<EffectKind> ParseEffectList(const std::string& list) {
  if (list == "all") return DefaultCandidates();
  if (list == "every") return AllEffects();
  std::vector<EffectKind> kinds;
  if (list.empty() || list == "none") return kinds;
  std::stringstream stream(list);
  std::string name;
  while (std::getline(stream, name, ',')) {
    const EffectKind kind = ParseEffectKind(name);
    if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end()) kinds.push_back(kind);
  }
  return kinds;
}

Eigen::VectorXd Effects::Get(EffectKind kind) const {
  const size_t i = static_cast<size_t>(kind->index());
  if (i < values_.size() && values_[i].size() > 0) return values_[i];
  return Eigen::VectorXd::Zero(std::max(0, kind->FixedDimension()));
}

Eigen::VectorXd Effects::Get(EffectKind kind, const Vehicle& vehicle) const {
  const Eigen::VectorXd value = Get(kind);
  return value.size() > 0 ? value : Eigen::VectorXd::Zero(kind->Dimension(vehicle));
}

void Effects::Set(EffectKind kind, const Eigen::Ref<const Eigen::VectorXd>& value) {
  const int dimension = kind->FixedDimension();
  if (dimension >= 0 && value.size() != dimension)
    throw Error(kind->parameter_name() + " takes " + std::to_string(dimension) + " value(s), got " +
                std::to_string(value.size()));
  const size_t i = static_cast<size_t>(kind->index());
  if (values_.size() <= i) values_.resize(AllEffects().size());
  values_[i] = value;
}

bool Effects::IsZero(EffectKind kind) const {
  const size_t i = static_cast<size_t>(kind->index());
  return i >= values_.size() || values_[i].size() == 0 || values_[i].isZero(0.0);
}

bool Effects::StageIsZero(EffectStage stage) const {
  for (EffectKind kind : AllEffects())
    if (kind->stage() == stage && !IsZero(kind)) return false;
  return true;
}

bool Effects::AllZero() const {
  for (EffectKind kind : AllEffects())
    if (!IsZero(kind)) return false;
  return true;
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
  // The sign convention: an effect whose physical range starts at zero takes no negative value.
  if (kind->info().lower_bound == 0.0)
    for (double v : values)
      if (v < 0.0) throw Error(kind->parameter_name() + " must not be negative");
  Set(kind, Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size())));
}

}  // namespace rotorid

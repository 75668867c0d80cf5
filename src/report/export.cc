#include "rotorid/report/export.h"

#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>

#include "export_text.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"
#include "rotorid/ident/identify.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/model/physical_consistency.h"
#include "rotorid/report/predicted_parameters.h"

namespace rotorid {

namespace {

// Per-flight first moments: a simulator has one centre of mass, so the export takes their mean.
void SetMeanFirstMoment(IdentifiedModel* model) {
  const std::string config = model->vehicle.name;
  if (model->parameters.count(config + ".ms_x")) return;
  std::vector<std::string> names;
  for (const auto& entry : model->parameters) names.push_back(entry.first);
  const std::vector<std::string> owners = OwnFirstMomentOwners(config, names);
  if (owners.empty()) return;
  double spread_m = 0.0;
  for (int a = 0; a < 3; ++a) {
    Eigen::VectorXd values(static_cast<Eigen::Index>(owners.size()));
    for (size_t k = 0; k < owners.size(); ++k)
      values[static_cast<Eigen::Index>(k)] = model->parameters.at(owners[k] + "." + kBodyParameterNames[a]).value;
    const double mean = values.mean();
    const double spread = std::sqrt((values.array() - mean).square().mean());
    model->parameters[config + "." + kBodyParameterNames[a]] = {mean, spread, true};
    spread_m = std::max(spread_m, (values.maxCoeff() - values.minCoeff()) / model->vehicle.mass_kg);
  }
  model->note = "first moment: the mean of " + std::to_string(owners.size()) + " per-flight first moments (" + config +
                ".flight<k>.ms_*; std: their spread), whose centres of mass differ by up to " +
                ShortNumber(1000.0 * spread_m) + " mm along an axis";
}

// The flight (or measurement) that fixes a parameter the report leaves open.
std::string HowToFix(const std::string& name, const std::string& config) {
  if (name == "kd" || name == config + ".I_zz")
    return "kd and I_zz meet only in the yaw rows, where a symmetric vehicle fixes just their ratio: fly a second "
           "configuration with a known extra inertia (a mass moved away from the z axis) and identify both together "
           "(--vehicle A.yaml --log a.csv --vehicle B.yaml --log b.csv, as the paper's A and B), or measure kd on a "
           "thrust stand";
  if (name == config + ".I_xx")
    return "fly roll doublets or a roll multisine (rotor speed differences across the x axis)";
  if (name == config + ".I_yy")
    return "fly pitch doublets or a pitch multisine (rotor speed differences across the y axis)";
  if (name == "kt") return "fly climbs and descents (thrust changes against the known mass)";
  return "fly manoeuvres that excite all three axes and the thrust";
}

// --set names: "kd", "I_zz" or "<config>.I_zz", effect parameters, max_rotor_speed.
std::string CanonicalSetting(const std::string& name, const std::string& config) {
  for (const char* rotor : kRotorCoefficientNames)
    if (name == rotor) return name;
  for (const char* body : kBodyParameterNames)
    if (name == body || name == config + "." + body) return config + "." + body;
  for (const char* other : {"motor_tau_s", "rotor_drag_coefficient", "flapping_moment_coefficient", "max_rotor_speed"})
    if (name == other) return name;
  throw Error("--set " + name + ": not a parameter of configuration '" + config +
              "' (kt, kd, ms_x ... I_yz, motor_tau_s, rotor_drag_coefficient, flapping_moment_coefficient, "
              "max_rotor_speed)");
}

// Every inertial and rotor parameter the simulator needs, each fixed (see ResolveExportModel).
void ResolveParameters(const IdentifiedModel& model, const std::map<std::string, double>& set, ExportModel* out) {
  const std::string config = model.vehicle.name;
  std::vector<std::string> names(kRotorCoefficientNames.begin(), kRotorCoefficientNames.end());
  for (const char* body : kBodyParameterNames) names.push_back(config + "." + body);
  std::map<std::string, double> values;
  std::vector<std::string> open;
  for (const std::string& name : names) {
    const auto given = set.find(name);
    const auto it = model.parameters.find(name);
    if (given != set.end()) {
      values[name] = given->second;
      out->provenance.push_back(name + " = " + ShortNumber(given->second) + ": given by the user (set option)");
    } else if (it != model.parameters.end() && it->second.essential) {
      values[name] = it->second.value;
    } else if (it != model.parameters.end() && it->second.predicts_with && !it->second.predicts_within_range) {
      values[name] = *it->second.predicts_with;
      out->provenance.push_back(name + " = " + ShortNumber(values[name]) +
                                ": discarded as non-essential; the value the model predicts with");
    } else if (PositiveByPhysics(name)) {
      open.push_back(name);  // 0 is no kd and no moment of inertia
    } else {
      values[name] = it != model.parameters.end() ? it->second.value : 0.0;
      out->provenance.push_back(name + " = 0: discarded as non-essential; the model predicts with 0");
    }
  }
  if (!open.empty()) {
    // A body allows a range of it; no flight picked a value in it.
    const auto first = model.parameters.find(open.front());
    const std::string range = first != model.parameters.end() && first->second.allowed_range
                                  ? ", a physically possible body allows " +
                                        ShortNumber(first->second.allowed_range->first) + " to " +
                                        ShortNumber(first->second.allowed_range->second)
                                  : "";
    throw Error(model.source + ": the report does not fix " + Join(open) +
                " (discarded, and the model predicts with no estimate of it" + range + "); " +
                HowToFix(open.front(), config) + "; or give it with --set " + open.front() + "=VALUE");
  }
  VehicleParameters& p = out->parameters;
  p.mass_kg = model.vehicle.mass_kg;
  p.rotor = {values["kt"], values["kd"]};
  Eigen::Matrix<double, kNumBodyParameters, 1> chi;
  for (int k = 0; k < kNumBodyParameters; ++k) chi[k] = values[config + "." + kBodyParameterNames[k]];
  p.body = BodyParameters::FromVector(chi);
  for (const char* rotor : kRotorCoefficientNames)
    if (!(values[rotor] > 0.0) || !std::isfinite(values[rotor]))
      throw Error(model.source + ": " + rotor + " = " + ShortNumber(values[rotor]) + " is no rotor coefficient (" +
                  HowToFix(rotor, config) + "; or give it with --set " + rotor + "=VALUE)");
}

// The body parameters least fixed by the report: the ones not estimated as essential, else the
// inertia entry with the largest relative std.
std::string LeastFixedBodyParameter(const IdentifiedModel& model, const std::map<std::string, double>& set) {
  const std::string config = model.vehicle.name;
  std::string worst;
  double worst_rel = -1.0;
  for (const char* body : {"I_zz", "I_xx", "I_yy", "ms_z", "ms_x", "ms_y"}) {
    const std::string name = config + "." + body;
    const auto it = model.parameters.find(name);
    if (set.count(name) || it == model.parameters.end()) continue;
    if (!it->second.essential) return name;
    const double rel = it->second.std / std::max(std::abs(it->second.value), 1e-300);
    if (rel > worst_rel) worst_rel = rel, worst = name;
  }
  return worst.empty() ? config + ".I_zz" : worst;
}

void CheckBody(const IdentifiedModel& model, const std::map<std::string, double>& set, const ExportModel& out) {
  const PhysicalConsistency c = CheckPhysicalConsistency(out.parameters.mass_kg, out.parameters.body);
  if (c.consistent) return;
  const std::string suspect = LeastFixedBodyParameter(model, set);
  throw Error(model.source + ": configuration '" + model.vehicle.name +
              "' with the values the model predicts with is no physically possible body (" + c.problem +
              "); the least fixed parameter is " + suspect + ": " + HowToFix(suspect, model.vehicle.name) +
              "; or give it with --set " + suspect + "=VALUE");
}

// A scalar effect the simulators hold: --set, else the report's value, else 0 (not identified).
double HeldEffect(const IdentifiedModel& model, const std::map<std::string, double>& set, const std::string& name,
                  ExportModel* out) {
  double value = 0.0;
  if (set.count(name)) {
    value = set.at(name);
    out->provenance.push_back(name + " = " + ShortNumber(value) + ": given by the user (set option)");
  } else if (const auto v = model.Effect(name)) {
    value = *v;
  }
  if (!std::isfinite(value) || value < 0.0)
    throw Error(model.source + ": " + name + " = " + ShortNumber(value) +
                " is not physical (it must be >= 0); refine again, or give it with --set " + name + "=VALUE");
  return value;
}

// `name = value` of an effect parameter as the report has it (a number or a vector).
std::string EffectText(const std::string& name, const nlohmann::json& effect) {
  const nlohmann::json value = effect.value("value", nlohmann::json());
  return name + " = " + (value.is_number() ? ShortNumber(value.get<double>()) : value.dump());
}

}  // namespace

double IdentifiedModel::Value(const std::string& name) const {
  const auto it = parameters.find(name);
  return it == parameters.end() ? 0.0 : it->second.value;
}

std::optional<double> IdentifiedModel::Effect(const std::string& name) const {
  if (!effects.contains(name) || !effects[name].contains("value") || !effects[name]["value"].is_number())
    return std::nullopt;
  return effects[name]["value"].get<double>();
}

IdentifiedModel IdentifiedModelFromReport(const nlohmann::json& report, const std::string& source,
                                          const Vehicle& vehicle, const std::string& block) {
  IdentifiedModel model;
  model.source = source;
  model.vehicle = vehicle;
  model.block = PredictedBlock(report, block);
  if (!report.contains(model.block) || !report[model.block].contains("parameters"))
    throw Error(source + ": no '" + model.block + ".parameters' (an identify or refine report is needed)");
  for (const auto& [name, entry] : report[model.block]["parameters"].items()) {
    if (!entry.is_object() || !entry.contains("value") || !entry["value"].is_number()) continue;
    ExportedValue v{entry["value"].get<double>(),
                    entry.contains("std") && entry["std"].is_number() ? entry["std"].get<double>() : 0.0,
                    entry.value("essential", true)};
    if (entry.contains("predicts_with") && entry["predicts_with"].is_number())
      v.predicts_with = entry["predicts_with"].get<double>();
    v.predicts_within_range = entry.value("predicts_within_range", false);
    if (entry.contains("allowed_range") && entry["allowed_range"].is_array() && entry["allowed_range"].size() == 2 &&
        entry["allowed_range"][0].is_number() && entry["allowed_range"][1].is_number())
      v.allowed_range =
          std::make_pair(entry["allowed_range"][0].get<double>(), entry["allowed_range"][1].get<double>());
    model.parameters[name] = v;
  }
  if (!(model.Value("kt") > 0.0)) throw Error(source + ": the report has no positive kt");
  if (!model.parameters.count(vehicle.name + ".I_xx"))
    throw Error(source + ": no parameters of configuration '" + vehicle.name + "' (the vehicle file's name)");
  SetMeanFirstMoment(&model);
  // Effects the refinement estimated (a report lists the others as disabled).
  if (model.block == "refined" && report["refined"].contains("effects"))
    for (const auto& [name, effect] : report["refined"]["effects"].items())
      if (effect.value("enabled", true)) model.effects[name] = effect;
  if (vehicle.command_to_speed) model.max_rotor_speed_radps = (*vehicle.command_to_speed)(1.0);
  if (report.contains("checks") && report["checks"].is_array())
    for (const nlohmann::json& check : report["checks"])
      if (check.is_object() && check.value("status", "") == "error")
        model.failed_checks.push_back({check.value("name", "?"), check.value("message", "")});
  return model;
}

MassProperties MassPropertiesOf(double mass_kg, const BodyParameters& body) {
  MassProperties p;
  p.mass_kg = mass_kg;
  p.centre_of_mass_m = body.first_moment / mass_kg;
  const Eigen::Vector3d& r = p.centre_of_mass_m;
  p.inertia_at_com = body.inertia - mass_kg * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  return p;
}

MassProperties MassPropertiesOf(const IdentifiedModel& model) {
  const std::string c = model.vehicle.name + ".";
  Eigen::Matrix<double, kNumBodyParameters, 1> chi;
  for (int k = 0; k < kNumBodyParameters; ++k) chi[k] = model.Value(c + kBodyParameterNames[k]);
  return MassPropertiesOf(model.vehicle.mass_kg, BodyParameters::FromVector(chi));
}

double ExportModel::HoverRotorSpeedRadps() const {
  return std::sqrt(parameters.mass_kg * kStandardGravity / (vehicle.num_rotors() * parameters.rotor.kt));
}

ExportModel ResolveExportModel(const IdentifiedModel& model, const ExportOptions& options) {
  if (!model.failed_checks.empty() && !options.force) {
    std::vector<std::string> names;
    for (const FailedCheck& c : model.failed_checks) names.push_back(c.name);
    throw Error(model.source + ": the report failed its checks (" + Join(names) + ": " +
                model.failed_checks.front().message +
                "); fix the input, or export anyway with --force (the failing checks go into the file's header)");
  }
  std::map<std::string, double> set;
  for (const auto& [name, value] : options.set) {
    if (!std::isfinite(value)) throw Error("--set " + name + ": not a finite number");
    set[CanonicalSetting(name, model.vehicle.name)] = value;
  }
  ExportModel out;
  out.source = model.source;
  out.block = model.block;
  out.vehicle = model.vehicle;
  out.failed_checks = model.failed_checks;
  out.report_parameters = model.parameters;
  out.report_effects = model.effects;
  out.note = model.note;
  if (!model.note.empty()) out.provenance.push_back(model.note);
  ResolveParameters(model, set, &out);
  CheckBody(model, set, out);
  out.motor_tau_s = HeldEffect(model, set, "motor_tau_s", &out);
  out.rotor_drag_coefficient = HeldEffect(model, set, "rotor_drag_coefficient", &out);
  out.flapping_moment_coefficient = HeldEffect(model, set, "flapping_moment_coefficient", &out);
  out.max_rotor_speed_radps = set.count("max_rotor_speed") ? set.at("max_rotor_speed") : model.max_rotor_speed_radps;
  for (const auto& [name, effect] : model.effects.items())
    if (name != "motor_tau_s" && name != "rotor_drag_coefficient" && name != "flapping_moment_coefficient")
      out.other_effects.push_back(EffectText(name, effect));
  return out;
}

std::pair<std::string, double> ParseExportSetting(const std::string& assignment) {
  const size_t eq = assignment.find('=');
  size_t used = 0;
  double value = 0.0;
  try {
    if (eq != std::string::npos) value = std::stod(assignment.substr(eq + 1), &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (eq == std::string::npos || eq == 0 || used == 0 || used != assignment.size() - eq - 1 || !std::isfinite(value))
    throw Error("--set " + assignment + ": expected NAME=VALUE with a finite number (e.g. kd=1.2e-8)");
  return {assignment.substr(0, eq), value};
}

namespace {

// Every name --format takes, each format's own name first; v2's "gazebo" writes gazebo-classic.
const std::pair<const char*, ExportFormat> kExportFormatNames[] = {{"gz", ExportFormat::kGz},
                                                                   {"gazebo-classic", ExportFormat::kGazeboClassic},
                                                                   {"px4", ExportFormat::kPx4},
                                                                   {"px4-sih", ExportFormat::kPx4Sih},
                                                                   {"ardupilot", ExportFormat::kArduPilot},
                                                                   {"yaml", ExportFormat::kYaml},
                                                                   {"gazebo", ExportFormat::kGazeboClassic}};

}  // namespace

std::vector<std::string> ExportFormatNames() {
  std::vector<std::string> names;
  for (const auto& [name, format] : kExportFormatNames) names.push_back(name);
  return names;
}

ExportFormat ParseExportFormat(const std::string& name) {
  for (const auto& [known, format] : kExportFormatNames)
    if (name == known) return format;
  throw Error("unknown export format '" + name + "' (" + Join(ExportFormatNames()) + ")");
}

const char* ExportFormatName(ExportFormat format) {
  for (const auto& [name, known] : kExportFormatNames)
    if (format == known) return name;
  return "?";
}

bool ExportWritesDirectory(ExportFormat format) {
  return format == ExportFormat::kGz || format == ExportFormat::kGazeboClassic;
}

namespace {

// Every parameter of the report with its std, and the resolved model a simulator would get.
std::string ModelYaml(const ExportModel& model) {
  using internal::ExportNumber;
  internal::ExportHeader header{"rotorid model YAML (every resolved number, for scripts)",
                                "SI: kg, m, kg m^2, N s^2, N m s^2, rad/s, s; body frame F_d (FLU, origin at the rotor "
                                "cross), inertia at O_d",
                                "none: rotor speeds in rad/s (the vehicle file's command_to_speed, if any, is copied)",
                                {"every effect the report holds, with its value"},
                                {}};
  std::ostringstream out;
  for (const std::string& line : internal::HeaderLines(model, header)) out << "# " << line << "\n";
  const VehicleParameters& p = model.parameters;
  const Eigen::Matrix3d& I = p.body.inertia;
  const Eigen::Vector3d& ms = p.body.first_moment;
  out << "source: " << nlohmann::json(model.source).dump() << "\nblock: " << model.block
      << "\nvehicle: " << nlohmann::json(model.vehicle.name).dump() << "\n";
  if (!model.note.empty()) out << "note: " << nlohmann::json(model.note).dump() << "\n";
  out << "mass: " << ExportNumber("mass", p.mass_kg) << "\nkt: " << ExportNumber("kt", p.rotor.kt)
      << "\nkd: " << ExportNumber("kd", p.rotor.kd) << "\nfirst_moment: [" << ExportNumber("ms_x", ms.x()) << ", "
      << ExportNumber("ms_y", ms.y()) << ", " << ExportNumber("ms_z", ms.z()) << "]\ninertia: [";
  for (int r = 0; r < 3; ++r)
    out << (r ? ", " : "") << "[" << ExportNumber("inertia", I(r, 0)) << ", " << ExportNumber("inertia", I(r, 1))
        << ", " << ExportNumber("inertia", I(r, 2)) << "]";
  const Eigen::Vector3d c = model.Mass().centre_of_mass_m;
  out << "]\ncentre_of_mass: [" << ExportNumber("c", c.x()) << ", " << ExportNumber("c", c.y()) << ", "
      << ExportNumber("c", c.z()) << "]\nmotor_tau_s: " << ExportNumber("motor_tau_s", model.motor_tau_s)
      << "\nrotor_drag_coefficient: " << ExportNumber("rotor_drag_coefficient", model.rotor_drag_coefficient)
      << "\nflapping_moment_coefficient: "
      << ExportNumber("flapping_moment_coefficient", model.flapping_moment_coefficient)
      << "\nmax_rotor_speed: " << ExportNumber("max_rotor_speed", model.max_rotor_speed_radps) << "\nrotors:\n";
  for (const Rotor& r : model.vehicle.rotors)
    out << "  - {position: [" << ExportNumber("position", r.position_m.x()) << ", "
        << ExportNumber("position", r.position_m.y()) << ", " << ExportNumber("position", r.position_m.z())
        << "], spin: " << r.spin << "}\n";
  out << "parameters:\n";
  for (const auto& [name, v] : model.report_parameters) {
    out << "  " << name << ": {value: " << ExportNumber(name, v.value) << ", std: " << ExportNumber(name, v.std)
        << ", essential: " << (v.essential ? "true" : "false");
    if (v.predicts_with) out << ", predicts_with: " << ExportNumber(name, *v.predicts_with);
    out << "}\n";
  }
  out << "effects:" << (model.report_effects.empty() ? " {}" : "") << "\n";
  for (const auto& [name, e] : model.report_effects.items())
    out << "  " << name << ": {value: " << e.value("value", nlohmann::json()).dump()
        << ", std: " << e.value("std", nlohmann::json()).dump() << "}\n";
  return out.str();
}

}  // namespace

std::vector<ExportedFile> ExportFiles(const ExportModel& model, ExportFormat format) {
  switch (format) {
    case ExportFormat::kGz:
      return internal::GzModel(model);
    case ExportFormat::kGazeboClassic:
      return internal::GazeboClassicModel(model);
    case ExportFormat::kPx4:
      return internal::Px4Parameters(model);
    case ExportFormat::kPx4Sih:
      return internal::Px4SihParameters(model);
    case ExportFormat::kArduPilot:
      return internal::ArduPilotFrame(model);
    case ExportFormat::kYaml:
      return {{"", ModelYaml(model)}};
  }
  return {};
}

void WriteExportedFiles(const std::vector<ExportedFile>& files, const std::string& out, bool directory) {
  std::error_code error;
  if (directory && (std::filesystem::create_directories(out, error), error))
    throw Error(out + ": cannot create the model directory (" + error.message() + ")");
  for (const ExportedFile& file : files)
    WriteFileAtomically(directory && !file.name.empty() ? out + "/" + file.name : out, file.text);
}

}  // namespace rotorid

#pragma once

// An identified model (an identify/refine report plus its vehicle file) written for simulators
// (INTERFACE.md 6): a gz-sim or Gazebo Classic model directory, a PX4 parameter file, PX4 SIH
// parameters, an ArduPilot SITL JSON frame, or a YAML of every parameter and effect.
//
// Never a non-physical model: ResolveExportModel fixes every number a simulator needs from the
// report (a discarded parameter takes the value the model predicts with) or from the user
// (`--set`), refuses (rotorid::Error naming the parameter and the flight that fixes it) what the
// report leaves open, and checks the body with CheckPhysicalConsistency (MODEL.md 10). Each format
// then writes that one resolved model, naming its units, the command-to-speed mapping it assumes
// and which identified effects the target holds. docs/cli.md and docs/simulators.md give the
// mapping of each format.

#include <Eigen/Core>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/core/vehicle.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

struct ExportedValue {
  double value = 0.0;
  double std = 0.0;
  bool essential = true;
  // The value the model predicts with when it is not `value` (a discarded inertia the TLS still
  // estimates: the report's `predicts_with`).
  std::optional<double> predicts_with = std::nullopt;
  // predicts_with is no estimate but a value inside the range a physical body allows (the report's
  // predicts_within_range, with allowed_range): the flights do not fix the parameter.
  std::optional<std::pair<double, double>> allowed_range = std::nullopt;
  bool predicts_within_range = false;
};

// A check of the report whose status is "error".
struct FailedCheck {
  std::string name;
  std::string message;
};

struct IdentifiedModel {
  std::string source;                                 // the report's file
  std::string block;                                  // "linear" or "refined"
  Vehicle vehicle;                                    // mass, rotor positions and spins
  std::map<std::string, ExportedValue> parameters;    // "kt", "kd", "<config>.I_xx", ...
  nlohmann::json effects = nlohmann::json::object();  // "<effect parameter>": {"value", "std"} (refined only)
  // Rotor speed at full command (rad/s), 0 when unknown: maxRotVelocity, SIH_T_MAX and SIH_Q_MAX.
  double max_rotor_speed_radps = 0.0;
  // What the export had to decide (a report with per-flight first moments: their mean is exported);
  // written into each format's header. Empty when nothing.
  std::string note;
  // The report's checks[] with status "error" (an export refuses them unless forced).
  std::vector<FailedCheck> failed_checks;

  double Value(const std::string& name) const;  // 0 for a parameter the report lacks
  // A scalar effect parameter (e.g. "motor_tau_s"), when the report has it.
  std::optional<double> Effect(const std::string& name) const;
};

// Reads `block` ("" = refined when present, else linear) of an identify or refine report. Throws
// rotorid::Error naming `source` when the block, kt or the vehicle's configuration is missing. A
// report with per-flight first moments (`<config>.flight<k>.ms_x`) gives the configuration their
// mean as `<config>.ms_x` (std: their spread over the flights), with a note.
IdentifiedModel IdentifiedModelFromReport(const nlohmann::json& report, const std::string& source,
                                          const Vehicle& vehicle, const std::string& block = "");

// Mass properties about the centre of mass: c = ms / m and I_c = I_O - m (|c|^2 E - c c^T).
struct MassProperties {
  double mass_kg = 0.0;
  Eigen::Vector3d centre_of_mass_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_at_com = Eigen::Matrix3d::Zero();
};
MassProperties MassPropertiesOf(const IdentifiedModel& model);
MassProperties MassPropertiesOf(double mass_kg, const BodyParameters& body);

enum class ExportFormat { kGz, kGazeboClassic, kPx4, kPx4Sih, kArduPilot, kYaml };

// The names `export --format` accepts: gz, gazebo-classic, px4, px4-sih, ardupilot, yaml and v2's
// gazebo (= gazebo-classic).
std::vector<std::string> ExportFormatNames();
// Throws rotorid::Error listing the names on an unknown one.
ExportFormat ParseExportFormat(const std::string& name);
const char* ExportFormatName(ExportFormat format);
// gz and gazebo-classic write a model directory (model.sdf + model.config); the others one file.
bool ExportWritesDirectory(ExportFormat format);

struct ExportOptions {
  // --set NAME=VALUE: a parameter ("kd", "I_zz" or "<config>.I_zz"), an effect parameter
  // ("motor_tau_s", "rotor_drag_coefficient", "flapping_moment_coefficient") or
  // "max_rotor_speed" (rad/s); each replaces what the report says.
  std::map<std::string, double> set;
  // Export a report whose checks failed; the failing checks go into the file's header.
  bool force = false;
};

// "NAME=VALUE" of --set; throws rotorid::Error when it is not that or VALUE is no finite number.
std::pair<std::string, double> ParseExportSetting(const std::string& assignment);

// The one model every format writes: each number fixed and the body physically possible.
struct ExportModel {
  std::string source;                   // the report's file
  std::string block;                    // "linear" or "refined"
  Vehicle vehicle;                      // name, mass, rotors (and the command_to_speed map, rotor radius when given)
  VehicleParameters parameters;         // m, ms and I at O_d in F_d, kt, kd
  double motor_tau_s = 0.0;             // 0: the model has no motor lag
  double rotor_drag_coefficient = 0.0;  // N s/m per rad/s (rotor_drag), 0 when not identified
  double flapping_moment_coefficient = 0.0;  // N m s/m per rad/s, 0 when not identified
  double max_rotor_speed_radps = 0.0;        // rotor speed at full command; 0 unknown
  std::string note;                          // IdentifiedModel::note
  // Where each value came from when not from an essential estimate ("kd: --set", "B.I_zz:
  // discarded, the value the model predicts with"), and the report's note.
  std::vector<std::string> provenance;
  // Effects the report identified that no simulator format holds (delay, sensor effects, ...), as
  // "name = value".
  std::vector<std::string> other_effects;
  std::vector<FailedCheck> failed_checks;  // exported with --force
  // The report's parameters and effects as it gives them (the yaml format lists them with std).
  std::map<std::string, ExportedValue> report_parameters;
  nlohmann::json report_effects = nlohmann::json::object();

  MassProperties Mass() const { return MassPropertiesOf(parameters.mass_kg, parameters.body); }
  // Rotor speed at hover, each rotor carrying m g / N (rad/s).
  double HoverRotorSpeedRadps() const;
};

// Fixes every number of `model` (see the header comment); throws rotorid::Error naming the
// parameter and the flight (or --set) that fixes it when the report leaves one open, when the
// body is not physically possible, or when the report failed its checks and !options.force.
ExportModel ResolveExportModel(const IdentifiedModel& model, const ExportOptions& options);

struct ExportedFile {
  std::string name;  // inside the --out directory; empty: the --out file itself
  std::string text;
};
// The files of `format`. Throws rotorid::Error naming the missing input (the rotor speed at full
// command for every simulator format) or the layout a target cannot fly (px4-sih: X quad and X
// hexa only).
std::vector<ExportedFile> ExportFiles(const ExportModel& model, ExportFormat format);

// Writes `files` atomically: into the directory `out` (created) when `directory`, else the one
// file to `out`. Throws rotorid::Error naming the path on failure.
void WriteExportedFiles(const std::vector<ExportedFile>& files, const std::string& out, bool directory);

}  // namespace rotorid

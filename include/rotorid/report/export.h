#pragma once

// An identified model (an identify/refine report plus its vehicle file) written for simulators:
// a Gazebo SDF fragment, PX4 SIH parameters, or a plain YAML of every parameter and effect.
// docs/cli.md gives the mapping of each format.

#include <Eigen/Core>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "rotorid/core/vehicle.h"

namespace rotorid {

struct ExportedValue {
  double value = 0.0;
  double std = 0.0;
  bool essential = true;
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

std::string GazeboSdf(const IdentifiedModel& model);
std::string Px4SihParameters(const IdentifiedModel& model);
std::string ModelYaml(const IdentifiedModel& model);

}  // namespace rotorid

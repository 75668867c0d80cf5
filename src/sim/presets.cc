#include "rotorid/sim/presets.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <cmath>

#include "io/yaml_fields.h"
#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/vehicle_yaml.h"

namespace rotorid {
namespace {

// The paper's vehicle (MODEL.md section 6), products of inertia small but non-zero.
constexpr double kPaperArmM = 0.225;
constexpr double kPaperKt = 3.6e-6;
constexpr double kPaperKd = 5.1e-8;

Vehicle PlusQuad(const std::string& name, double mass_kg, double arm_m) {
  Vehicle vehicle;
  vehicle.name = name;
  vehicle.mass_kg = mass_kg;
  vehicle.rotors = {{Eigen::Vector3d(0.0, -arm_m, 0.0), +1},
                    {Eigen::Vector3d(0.0, arm_m, 0.0), +1},
                    {Eigen::Vector3d(arm_m, 0.0, 0.0), -1},
                    {Eigen::Vector3d(-arm_m, 0.0, 0.0), -1}};
  return vehicle;
}

BodyParameters InertiaFromProducts(const Eigen::Vector3d& first_moment, double ixx, double iyy, double izz, double ixy,
                                   double ixz, double iyz) {
  Eigen::Matrix<double, kNumBodyParameters, 1> chi;
  chi << first_moment, ixx, iyy, izz, ixy, ixz, iyz;
  return BodyParameters::FromVector(chi);
}

Eigen::VectorXd ReadNumbers(const std::string& source, const YAML::Node& node, const std::string& what, int count) {
  if (!node.IsSequence() || static_cast<int>(node.size()) != count)
    internal::FailAt(source, node, what + " must be a list of " + std::to_string(count) + " numbers");
  Eigen::VectorXd values(count);
  for (int i = 0; i < count; ++i) values[i] = internal::ReadYamlNumber(source, node[i], what);
  return values;
}

// The Crazyflie 2.1 brushed as the IMRC Lab flew it (data/vehicles/crazyflie21_brushed.yaml: layout,
// mass with its decks; ../shared/data/real/crazyflie-imrc-rpm/SOURCE.md: kt on the Bitcraze stand
// and in flight). kd from Foerster's (ETH 2015) torque-to-thrust ratio of 0.006 m, rounded down to
// 5 mm: 1e-10. Inertia from the literature's 1.4-1.6e-5 / 2.9e-5 kg m^2, products a few percent.
SimulationVehicle CrazyflieVehicle() {
  constexpr double kHalfDiagonalM = 0.0325;  // 92 mm motor to motor on the diagonal: arm 0.046 m
  constexpr double kMassKg = 0.0347;
  SimulationVehicle cf;
  cf.vehicle.name = "CF";
  cf.vehicle.mass_kg = kMassKg;
  cf.vehicle.rotors = {{Eigen::Vector3d(kHalfDiagonalM, -kHalfDiagonalM, 0.0), +1},
                       {Eigen::Vector3d(-kHalfDiagonalM, -kHalfDiagonalM, 0.0), -1},
                       {Eigen::Vector3d(-kHalfDiagonalM, kHalfDiagonalM, 0.0), +1},
                       {Eigen::Vector3d(kHalfDiagonalM, kHalfDiagonalM, 0.0), -1}};
  cf.vehicle.rotor_radius_m = 0.0225;  // 45 mm propellers
  // Concave like the stand fit of the data file (c2 / c1 = -0.22 there, -0.2 here), scaled so that the
  // full command gives 3000 rad/s at the reference voltage (the stand fit gives 2440 rad/s at 3.8-3.9 V
  // with the decks' weight; 3000 leaves the simulated controller room for the yaw-spin profile).
  cf.vehicle.command_to_speed = CommandToSpeed{Eigen::Vector3d(0.0, 3750.0, -750.0)};
  cf.vehicle.command_to_speed_voltage_v = 3.8;
  cf.parameters.mass_kg = kMassKg;
  cf.parameters.rotor = {2.0e-8, 1.0e-10};
  // Centre of mass 1 mm behind, 0.5 mm right of and 2 mm below O_d (the battery under the board).
  cf.parameters.body = InertiaFromProducts(kMassKg * Eigen::Vector3d(-1e-3, -0.5e-3, -2e-3), 1.6e-5, 1.65e-5, 2.9e-5,
                                           1.5e-7, -2e-7, 1e-7);
  cf.parameters_source =
      "preset CF (Crazyflie 2.1 brushed-like: data/vehicles/crazyflie21_brushed.yaml, crazyflie-imrc-rpm/SOURCE.md)";
  cf.log_rate_hz = 500.0;
  cf.noise = "bmi088";
  return cf;
}

}  // namespace

SimulationVehicle PresetVehicle(const std::string& name) {
  SimulationVehicle a;
  a.vehicle = PlusQuad("A", 1.285, kPaperArmM);
  a.vehicle.rotor_radius_m = 0.127;  // 10-inch propellers
  a.parameters.mass_kg = 1.285;
  a.parameters.rotor = {kPaperKt, kPaperKd};
  a.parameters.body =
      InertiaFromProducts(Eigen::Vector3d(-4e-3, -2e-3, -6e-3), 1.8e-2, 1.9e-2, 2.9e-2, 2e-5, -4e-5, 1e-5);
  a.parameters_source = "preset A (the paper's configuration A, MODEL.md section 6)";
  if (name == "A") return a;
  if (name == "B") {
    // Two point masses on rods (MODEL.md section 6), added exactly to A's first moment and inertia.
    constexpr double kMassOnX = 0.125, kMassOnMinusY = 0.042;
    SimulationVehicle b = a;
    b.vehicle.name = "B";
    b.parameters.body = AddPointMass(a.parameters.body, kMassOnX, Eigen::Vector3d(0.375, 0.0, -0.04));
    b.parameters.body = AddPointMass(b.parameters.body, kMassOnMinusY, Eigen::Vector3d(0.0, -0.43, -0.04));
    b.parameters.mass_kg = a.parameters.mass_kg + kMassOnX + kMassOnMinusY;
    b.vehicle.mass_kg = b.parameters.mass_kg;
    b.parameters_source =
        "preset B (A plus 0.125 kg at (0.375, 0, -0.04) m and 0.042 kg at (0, -0.43, -0.04) m, added exactly)";
    return b;
  }
  if (name == "CF") return CrazyflieVehicle();
  throw Error("unknown preset '" + name + "'; known presets: A, B, CF");
}

VehicleParameters DeriveSimulationParameters(const Vehicle& vehicle) {
  if (const std::string problem = vehicle.Validate(); !problem.empty()) throw Error(problem);
  double arm_m = 0.0;
  for (const Rotor& rotor : vehicle.rotors) arm_m += rotor.position_m.head<2>().norm();
  arm_m /= vehicle.num_rotors();
  if (!(arm_m > 0.01)) throw Error("cannot derive simulation parameters: the rotors' mean arm length is below 1 cm");
  const double scale = arm_m / kPaperArmM;

  VehicleParameters parameters;
  parameters.mass_kg = vehicle.mass_kg;
  parameters.rotor.kt = kPaperKt * std::pow(scale, 4.0) * 4.0 / vehicle.num_rotors();
  parameters.rotor.kd = parameters.rotor.kt * (kPaperKd / kPaperKt) * scale;

  // Motors and arms as point masses at the rotors, the rest as a central box of side 0.6 arm.
  const double rotor_mass = 0.4 * vehicle.mass_kg / vehicle.num_rotors();
  const double core_mass = 0.6 * vehicle.mass_kg;
  const double core_side = 0.6 * arm_m;
  BodyParameters body;
  body.inertia = core_mass * core_side * core_side / 6.0 * Eigen::Matrix3d::Identity();
  for (const Rotor& rotor : vehicle.rotors) body = AddPointMass(body, rotor_mass, rotor.position_m);
  // The centre of mass a few millimetres off O_d, mostly below it (battery under the frame).
  const Eigen::Vector3d com_offset_m = Eigen::Vector3d(-3e-3, -1.5e-3, -5e-3) * scale;
  body.first_moment += vehicle.mass_kg * com_offset_m;
  // A small asymmetry so that the products of inertia are not exactly zero.
  body.inertia(0, 1) = body.inertia(1, 0) = 1e-3 * body.inertia(0, 0);
  body.inertia(0, 2) = body.inertia(2, 0) = -2e-3 * body.inertia(0, 0);
  parameters.body = body;
  return parameters;
}

SimulationVehicle ParseSimulationVehicle(const std::string& text, const std::string& source) {
  SimulationVehicle result;
  result.vehicle = ParseVehicleYaml(text, source);
  result.parameters = DeriveSimulationParameters(result.vehicle);
  const YAML::Node root = YAML::Load(text);  // valid: ParseVehicleYaml accepted it
  const YAML::Node simulation = root["simulation"];
  if (!simulation) {
    result.parameters_source =
        "derived from the mass and arm length of " + source + " (no simulation: mapping in the vehicle file)";
    return result;
  }
  if (!simulation.IsMap()) internal::FailAt(source, simulation, "simulation must be a mapping {kt, kd, ms, inertia}");
  std::string missing;
  for (const char* key : {"kt", "kd", "ms", "inertia"})
    if (!simulation[key]) missing += std::string(missing.empty() ? "" : ", ") + key;
  for (const auto& entry : simulation) {
    const std::string key = entry.first.as<std::string>();
    if (key != "kt" && key != "kd" && key != "ms" && key != "inertia")
      internal::FailAt(source, entry.first, "unknown key '" + key + "' in simulation (known: kt, kd, ms, inertia)");
  }
  if (const YAML::Node kt = simulation["kt"]) {
    result.parameters.rotor.kt = internal::ReadYamlNumber(source, kt, "simulation.kt");
    if (!(result.parameters.rotor.kt > 0.0)) internal::FailAt(source, kt, "simulation.kt must be positive (N s^2)");
  }
  if (const YAML::Node kd = simulation["kd"]) {
    result.parameters.rotor.kd = internal::ReadYamlNumber(source, kd, "simulation.kd");
    if (!(result.parameters.rotor.kd > 0.0)) internal::FailAt(source, kd, "simulation.kd must be positive (N m s^2)");
  }
  if (const YAML::Node ms = simulation["ms"])
    result.parameters.body.first_moment = ReadNumbers(source, ms, "simulation.ms", 3);
  if (const YAML::Node inertia = simulation["inertia"]) {
    const Eigen::VectorXd i = ReadNumbers(source, inertia, "simulation.inertia [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]", 6);
    result.parameters.body =
        InertiaFromProducts(result.parameters.body.first_moment, i[0], i[1], i[2], i[3], i[4], i[5]);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(result.parameters.body.inertia);
    if (!(eigen.eigenvalues().minCoeff() > 0.0))
      internal::FailAt(source, inertia, "simulation.inertia is not positive definite");
  }
  result.parameters_source = "simulation: mapping of " + source;
  if (!missing.empty()) result.parameters_source += " (" + missing + " derived from mass and arm length)";
  return result;
}

SimulationVehicle LoadSimulationVehicle(const std::string& path) {
  return ParseSimulationVehicle(ReadFile(path, kMaxYamlFileBytes), path);
}

}  // namespace rotorid

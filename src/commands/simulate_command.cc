#include "rotorid/commands/simulate_command.h"

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/sim/truth.h"

namespace rotorid {

ResolvedSimulateCommand ResolveSimulateCommand(const SimulateCommandOptions& options) {
  if (options.out_path.empty()) throw Error("simulate needs --out FILE (the flight log to write)");
  if (options.preset_given && !options.vehicle_path.empty()) throw Error("give either --preset or --vehicle, not both");
  const std::string& seed = options.seed;
  if (seed.empty() || seed.size() > 19 || seed.find_first_not_of("0123456789") != std::string::npos)
    throw Error("--seed must be a non-negative integer below 10^19 (got '" + seed + "')");
  ResolvedSimulateCommand resolved{options, options.simulation, std::nullopt};
  SimulationOptions& simulation = resolved.simulation;
  simulation.seed = std::stoull(seed);
  // An unknown preset is a usage error; a bad vehicle file is bad input (RunSimulateCommand).
  if (options.vehicle_path.empty()) resolved.preset = PresetVehicle(options.preset);
  // A preset logs at its own rate and noise unless told otherwise (CF: 500 Hz, bmi088).
  if (resolved.preset && !options.rate_given) simulation.log_rate_hz = resolved.preset->log_rate_hz;
  simulation.noise = NoiseLevels::Preset(!options.noise.empty() ? options.noise
                                         : resolved.preset      ? resolved.preset->noise
                                                                : "pixhawk");
  simulation.profile = ParseFlightProfile(options.profile);
  for (const std::string& effect : options.effects) simulation.effects.Assign(effect);
  const std::vector<double>& force = options.external_force;
  if (!force.empty()) {
    if (force.size() != 3) throw Error("--external-force needs x,y,z in N");
    simulation.external_force.world_n = Eigen::Vector3d(force[0], force[1], force[2]);
  }
  if (const std::string problem = simulation.Validate(); !problem.empty()) throw Error(problem);
  return resolved;
}

SimulateCommandResult RunSimulateCommand(const ResolvedSimulateCommand& command) {
  const SimulateCommandOptions& options = command.options;
  const SimulationVehicle simulated = command.preset ? *command.preset : LoadSimulationVehicle(options.vehicle_path);
  SimulateCommandResult result;
  SimulationResult& simulation = result.simulation;
  simulation = Simulate(simulated.vehicle, simulated.parameters, command.simulation);
  simulation.parameters_source = simulated.parameters_source;
  if (options.vehicle_path.empty())
    simulation.log.metadata["preset"] = options.preset;
  else
    simulation.log.metadata["vehicle_file"] = options.vehicle_path;

  result.outputs["log"] = options.out_path;
  WriteFlightCsv(options.out_path, simulation.log);
  if (!options.truth_path.empty()) {
    WriteTruthJson(options.truth_path, simulation);
    result.outputs["truth"] = options.truth_path;
  }
  if (!options.vehicle_out_path.empty()) {
    WriteFileAtomically(options.vehicle_out_path, VehicleToYaml(simulation.vehicle));
    result.outputs["vehicle"] = options.vehicle_out_path;
  }
  if (!options.json_path.empty()) {
    result.outputs["json"] = options.json_path;
    WriteFileAtomically(options.json_path, SimulationReportJson(simulation, result.outputs));
  }
  return result;
}

std::string SimulateConsoleText(const SimulateCommandResult& result) {
  std::string text = SummaryLine(result.simulation) + "\nwrote";
  for (const auto& [role, path] : result.outputs) text += " " + role + "=" + path;
  return text + "\n";
}

}  // namespace rotorid

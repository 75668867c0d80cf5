#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"
#include "rotorid/sim/truth.h"

namespace rotorid::cli {
namespace {

struct SimulateArguments {
  std::string out_path;
  std::string truth_path;
  std::string vehicle_out_path;
  std::string json_path;
  std::string preset = "A";
  std::string vehicle_path;
  std::string noise;  // empty: the preset's (pixhawk for A, B and vehicle files)
  std::string profile = "paper";
  std::vector<std::string> effects;
  std::vector<double> external_force;  // world x, y, z in N
  std::string seed = "1";              // parsed here: CLI11 would wrap "-1" around to 2^64 - 1
  SimulationOptions options;
  bool quiet = false;
};

int RunSimulate(const CLI::App& app, const SimulateArguments& args) {
  if (args.out_path.empty()) throw Error("simulate needs --out FILE (the flight log to write)");
  if (app.count("--preset") > 0 && !args.vehicle_path.empty())
    throw Error("give either --preset or --vehicle, not both");

  SimulationOptions options = args.options;
  if (args.seed.empty() || args.seed.size() > 19 || args.seed.find_first_not_of("0123456789") != std::string::npos)
    throw Error("--seed must be a non-negative integer below 10^19 (got '" + args.seed + "')");
  options.seed = std::stoull(args.seed);
  // An unknown preset is a usage error; a bad vehicle file is bad input.
  std::optional<SimulationVehicle> preset;
  if (args.vehicle_path.empty()) preset = PresetVehicle(args.preset);
  // A preset logs at its own rate and noise unless told otherwise (CF: 500 Hz, bmi088).
  if (preset && app.count("--rate") == 0) options.log_rate_hz = preset->log_rate_hz;
  options.noise = NoiseLevels::Preset(!args.noise.empty() ? args.noise : preset ? preset->noise : "pixhawk");
  options.profile = ParseFlightProfile(args.profile);
  for (const std::string& effect : args.effects) options.effects.Assign(effect);
  if (!args.external_force.empty())
    options.external_force.world_n =
        Eigen::Vector3d(args.external_force[0], args.external_force[1], args.external_force[2]);
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  MarkOptionsValidated();
  const SimulationVehicle simulated = preset ? *preset : LoadSimulationVehicle(args.vehicle_path);
  SimulationResult result = Simulate(simulated.vehicle, simulated.parameters, options);
  result.parameters_source = simulated.parameters_source;
  if (args.vehicle_path.empty())
    result.log.metadata["preset"] = args.preset;
  else
    result.log.metadata["vehicle_file"] = args.vehicle_path;

  std::map<std::string, std::string> outputs{{"log", args.out_path}};
  WriteFlightCsv(args.out_path, result.log);
  if (!args.truth_path.empty()) {
    WriteTruthJson(args.truth_path, result);
    outputs["truth"] = args.truth_path;
  }
  if (!args.vehicle_out_path.empty()) {
    WriteFileAtomically(args.vehicle_out_path, VehicleToYaml(result.vehicle));
    outputs["vehicle"] = args.vehicle_out_path;
  }
  if (!args.json_path.empty()) {
    outputs["json"] = args.json_path;
    WriteFileAtomically(args.json_path, SimulationReportJson(result, outputs));
  }
  if (!args.quiet) {
    std::cout << SummaryLine(result) << "\n";
    std::cout << "wrote";
    for (const auto& [role, path] : outputs) std::cout << " " << role << "=" << path;
    std::cout << "\n";
  }
  return 0;
}

}  // namespace

Command AddSimulateCommand(CLI::App& root) {
  auto args = std::make_shared<SimulateArguments>();
  Command command;
  CLI::App* app = root.add_subcommand(
      "simulate",
      "Simulates a closed-loop, pilot-like flight with known parameters and effects: writes the flight log (--out), "
      "its ground truth (--truth) and the vehicle file (--vehicle-out). See docs/simulator.md.");
  command.app = app;
  app->add_option("--out", args->out_path, "flight log CSV to write (required)");
  app->add_option("--truth", args->truth_path, "ground-truth JSON to write (parameters, effects, noise, seed)");
  app->add_option("--vehicle-out", args->vehicle_out_path, "vehicle YAML to write (name, mass, rotors)");
  app->add_option("--json", args->json_path, "run summary JSON to write");
  app->add_option("--preset", args->preset,
                  "A or B (the paper's configurations) or CF (Crazyflie-like: 34.7 g, X, arm 0.046 m, 500 Hz, bmi088 "
                  "noise) (default A)");
  app->add_option("--vehicle", args->vehicle_path,
                  "vehicle YAML to fly instead of a preset; true parameters from its optional simulation: mapping "
                  "(kt, kd, ms: [3], inertia: [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]), else derived from mass and arm length");
  app->add_option("--seconds", args->options.duration_s, "logged flight length in s (default 90)");
  app->add_option("--seed", args->seed, "random seed, a non-negative integer: same seed, same bytes (default 1)");
  std::string effect_names;
  for (EffectKind kind : AllEffects()) effect_names += (effect_names.empty() ? "" : ", ") + kind->parameter_name();
  app->add_option("--effect", args->effects,
                  "unmodelled effect name=value, vectors name=x,y,z (repeatable): " + effect_names)
      ->allow_extra_args(false);
  app->add_option("--noise", args->noise,
                  "sensor noise preset: none, low, pixhawk or bmi088 (default the preset's: pixhawk, CF: bmi088)");
  app->add_option("--rate", args->options.log_rate_hz, "log (and controller) rate in Hz (default 200, CF: 500)");
  app->add_option("--profile", args->profile,
                  "what the pilot flies: paper (default), yaw-spin (large yaw-rate swings), circle (constant "
                  "horizontal speed), takeoff-landing (low hover near the ground, climbs to 0.5 m and back)");
  app->add_option("--circle-radius", args->options.circle_radius_m, "circle profile: radius in m (default 2)");
  app->add_option("--circle-speed", args->options.circle_speed_mps, "circle profile: speed in m/s (default 2)");
  app->add_flag("--battery", args->options.battery.enabled,
                "simulate the battery: log the motor commands (rotor_signal: command) and a voltage column (4.2 -> "
                "3.7 V over the flight, 0.3 V sag at hover thrust); the vehicle file gets the command_to_speed map");
  app->add_option(
         "--external-force", args->external_force,
         "a force rotorid does not model (tether, payload, wind) at O_d in the world frame (z up): x,y,z in N, "
         "at most 0.3 m g")
      ->delimiter(',')
      ->expected(3);
  app->add_option("--external-force-period", args->options.external_force.turn_period_s,
                  "its horizontal part turns about z with this period in s (default 0: constant)");
  app->add_option("--physics-rate", args->options.physics_rate_hz, "RK4 integration rate in Hz (default 2000)");
  app->add_flag("--mocap", args->options.mocap, "also log motion capture: pos_x,pos_y,pos_z,roll,pitch,yaw");
  app->add_option("--jitter-s", args->options.jitter_s, "standard deviation of the sampling instants in s (default 0)");
  app->add_option("--excitation", args->options.excitation, "scale of the pilot's references, 0 = hover (default 1)");
  app->add_option("--hover-altitude", args->options.hover_altitude_m,
                  "height above the ground (z = 0) the pilot hovers about, in m (default 1.5; low for ground_effect)");
  app->add_option("--hover-lead-in-s", args->options.hover_lead_in_s,
                  "logged hover before the pilot's references fade in, in s (default 1)");
  app->add_option("--warmup-s", args->options.warmup_s,
                  "unlogged flight before t = 0 so that the controller has settled, in s (default 1)");
  app->add_option("--gravity", args->options.gravity_mps2, "g in m/s^2 (default 9.80665)");
  app->add_flag("--quiet,-q", args->quiet, "print nothing on success");
  command.run = [app, args]() { return RunSimulate(*app, *args); };
  return command;
}

}  // namespace rotorid::cli

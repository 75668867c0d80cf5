#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/simulate_command.h"

namespace rotorid::cli {

Command AddSimulateCommand(CLI::App& root) {
  auto o = std::make_shared<SimulateCommandOptions>();
  auto quiet = std::make_shared<bool>(false);
  Command command;
  CLI::App* app = command.app = root.add_subcommand(
      "simulate",
      "Simulates a closed-loop, pilot-like flight with known parameters and effects: writes the flight log (--out), "
      "its ground truth (--truth) and the vehicle file (--vehicle-out). See docs/simulator.md.");
  SimulationOptions& s = o->simulation;
  app->add_option("--out", o->out_path, "flight log CSV to write (required)");
  app->add_option("--truth", o->truth_path, "ground-truth JSON to write (parameters, effects, noise, seed)");
  app->add_option("--vehicle-out", o->vehicle_out_path, "vehicle YAML to write (name, mass, rotors)");
  app->add_option("--json", o->json_path, "run summary JSON to write");
  app->add_option("--preset", o->preset,
                  "A or B (the paper's configurations) or CF (Crazyflie-like: 34.7 g, X, arm 0.046 m, 500 Hz, bmi088 "
                  "noise) (default A)");
  app->add_option("--vehicle", o->vehicle_path,
                  "vehicle YAML to fly instead of a preset; true parameters from its optional simulation: mapping "
                  "(kt, kd, ms: [3], inertia: [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]), else derived from mass and arm length");
  app->add_option("--seconds", s.duration_s, "logged flight length in s (default 90)");
  app->add_option("--seed", o->seed, "random seed, a non-negative integer: same seed, same bytes (default 1)");
  std::string effect_names;
  for (EffectKind kind : AllEffects()) effect_names += (effect_names.empty() ? "" : ", ") + kind->parameter_name();
  app->add_option("--effect", o->effects,
                  "unmodelled effect name=value, vectors name=x,y,z (repeatable): " + effect_names)
      ->allow_extra_args(false);
  app->add_option("--noise", o->noise,
                  "sensor noise preset: none, low, pixhawk or bmi088 (default the preset's: pixhawk, CF: bmi088)");
  app->add_option("--rate", s.log_rate_hz, "log (and controller) rate in Hz (default 200, CF: 500)");
  app->add_option("--profile", o->profile,
                  "what the pilot flies: paper (default), yaw-spin (large yaw-rate swings), circle (constant "
                  "horizontal speed), takeoff-landing (low hover near the ground, climbs to 0.5 m and back)");
  app->add_option("--circle-radius", s.circle_radius_m, "circle profile: radius in m (default 2)");
  app->add_option("--circle-speed", s.circle_speed_mps, "circle profile: speed in m/s (default 2)");
  app->add_flag("--battery", s.battery.enabled,
                "simulate the battery: log the motor commands (rotor_signal: command) and a voltage column (4.2 -> "
                "3.7 V over the flight, 0.3 V sag at hover thrust); the vehicle file gets the command_to_speed map");
  app->add_option("--external-force", o->external_force,
                  "a force rotorid does not model (tether, payload, wind) at O_d in the world frame (z up): x,y,z in "
                  "N, at most 0.3 m g")
      ->delimiter(',')
      ->expected(3);
  app->add_option("--external-force-period", s.external_force.turn_period_s,
                  "its horizontal part turns about z with this period in s (default 0: constant)");
  app->add_option("--physics-rate", s.physics_rate_hz, "RK4 integration rate in Hz (default 2000)");
  app->add_flag("--mocap", s.mocap, "also log motion capture: pos_x,pos_y,pos_z,roll,pitch,yaw");
  app->add_option("--jitter-s", s.jitter_s, "standard deviation of the sampling instants in s (default 0)");
  app->add_option("--excitation", s.excitation, "scale of the pilot's references, 0 = hover (default 1)");
  app->add_option("--hover-altitude", s.hover_altitude_m,
                  "height above the ground (z = 0) the pilot hovers about, in m (default 1.5; low for ground_effect)");
  app->add_option("--hover-lead-in-s", s.hover_lead_in_s,
                  "logged hover before the pilot's references fade in, in s (default 1)");
  app->add_option("--warmup-s", s.warmup_s,
                  "unlogged flight before t = 0 so that the controller has settled, in s (default 1)");
  app->add_option("--gravity", s.gravity_mps2, "g in m/s^2 (default 9.80665)");
  app->add_flag("--quiet,-q", *quiet, "print nothing on success");
  command.run = [app, o, quiet]() {
    o->preset_given = app->count("--preset") > 0;
    o->rate_given = app->count("--rate") > 0;
    const ResolvedSimulateCommand resolved = ResolveSimulateCommand(*o);
    MarkOptionsValidated();
    const SimulateCommandResult result = RunSimulateCommand(resolved);
    if (!*quiet) std::cout << SimulateConsoleText(result);
    return 0;
  };
  return command;
}

}  // namespace rotorid::cli

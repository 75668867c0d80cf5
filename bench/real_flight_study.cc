// Real Crazyflie flights with both the PWM command and the measured rotor speed (IMRC Lab, RPM
// deck; ../shared/data/real/crazyflie-imrc-rpm): the motors' delay and time constant measured
// directly (command -> RPM), against what the refinement estimates when it is driven by the PWM
// command alone (as recorded, and through the vehicle file's command_to_speed map), and by the
// measured RPM (where they should mostly vanish).
//
//   real_flight_study [data folder=../shared/data/real/crazyflie-imrc-rpm] [vehicle file]

#include <cstdio>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/refine/motor_response.h"
#include "rotorid/refine/refine.h"

using namespace rotorid;

namespace {

void Report(const char* flight, const char* signal, const IdentificationResult& linear, const RefineResult& refined) {
  auto pct = [](const std::optional<double>& v) { return v ? *v : -1.0; };
  std::printf(
      "  %-8s %-8s refined delay %6.1f +- %4.1f ms, motor tau %6.1f +- %4.1f ms | "
      "Table III Fz/Mx/My/Mz linear %5.1f/%5.1f/%5.1f/%5.1f %% -> refined %5.1f/%5.1f/%5.1f/%5.1f %%\n",
      flight, signal, 1e3 * refined.effects.Scalar("delay_s"), 1e3 * refined.effects_std.Scalar("delay_s"),
      1e3 * refined.effects.Scalar("motor_tau_s"), 1e3 * refined.effects_std.Scalar("motor_tau_s"),
      pct(linear.relative_error_pct[2]), pct(linear.relative_error_pct[3]), pct(linear.relative_error_pct[4]),
      pct(linear.relative_error_pct[5]), pct(refined.relative_error_pct[2]), pct(refined.relative_error_pct[3]),
      pct(refined.relative_error_pct[4]), pct(refined.relative_error_pct[5]));
}

}  // namespace

int main(int argc, char** argv) {
  const std::string root = argc > 1 ? argv[1] : "../shared/data/real/crazyflie-imrc-rpm";
  const std::string vehicle_path = argc > 2 ? argv[2] : "data/vehicles/crazyflie21_brushed.yaml";
  try {
    const Vehicle vehicle = ReadVehicleYaml(vehicle_path);
    for (const char* flight : {"jana01", "jana04"}) {
      const std::string path = root + "/brushed/raw/" + flight;
      FlightSourceOptions rpm_source, command_source;
      rpm_source.rotor_signal = "rpm";
      command_source.rotor_signal = "command";
      const FlightLog rpm = LoadFlightLog(path, vehicle, rpm_source);
      const FlightLog pwm = LoadFlightLogAsRecorded(path, vehicle, command_source);
      const MotorResponse direct = EstimateMotorResponse(rpm.t_s, pwm.rotor_radps, rpm.rotor_radps);
      std::printf(
          "%s: measured directly (PWM -> RPM, %d samples): delay %.1f ms, motor tau %.1f ms, "
          "RPM explained %.1f %% (residual %.0f rad/s)\n",
          flight, direct.samples, 1e3 * direct.delay_s, 1e3 * direct.motor_tau_s, direct.explained_pct,
          direct.residual_rms);
      std::vector<std::pair<const char*, FlightLog>> signals = {{"rpm", rpm}, {"pwm", pwm}};
      if (vehicle.command_to_speed) signals.push_back({"pwm->map", LoadFlightLog(path, vehicle, command_source)});
      for (const auto& [signal, log] : signals) {
        IdentifyOptions identify;
        identify.allow_partial = true;
        const IdentificationResult linear = Identify({{vehicle, log, 1.0}}, identify);
        RefineOptions options;
        options.effects = {ParseEffectKind("delay"), ParseEffectKind("motor_lag")};
        options.num_threads = 2;
        const RefineResult refined = Refine(linear, options);
        Report(flight, signal, linear, refined);
        std::printf("  %-8s %-8s kt linear %.4g, refined %.4g (unit: N per rotor-signal unit squared)\n", flight,
                    signal, linear.solution.chi[0], refined.refined.chi[0]);
      }
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "real_flight_study: %s\n", e.what());
    return 1;
  }
  return 0;
}

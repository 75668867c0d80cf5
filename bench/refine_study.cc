// Effect recovery study: simulated flights of the paper's vehicle with one (or two) unmodelled
// effects at realistic magnitudes; the refinement must recover them and un-bias the parameters.
//
//   refine_study [seeds=5] [seconds=90] [config=B]
//   refine_study --delay [flights=50] [seconds=90] [config=B]
//
// --delay: `rotorid delay`'s estimator on random flights whose command-to-IMU delay is drawn
// uniformly over its whole search range, -100..+200 ms: the simulator's sub-sample delay (0-40 ms)
// plus a whole-sample shift of the logged rotor columns against the IMU.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/model/rotation.h"
#include "rotorid/refine/delay.h"
#include "rotorid/refine/refine.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/realistic_effects.h"
#include "rotorid/sim/simulator.h"

using namespace rotorid;

namespace {

struct Case {
  std::string label;
  std::vector<EffectKind> kinds;
};

double RelErr(double estimate, double truth) { return 100.0 * std::abs(estimate - truth) / std::abs(truth); }

// Shifts the logged rotor columns by `samples` against the IMU: positive makes the log's rotor
// signal lead (a larger command-to-IMU delay). Both ends lose |samples| rows.
FlightLog ShiftRotorColumns(const FlightLog& log, int samples) {
  const int n = log.num_samples(), k = std::abs(samples);
  FlightLog shifted = log.Slice(samples > 0 ? 0 : k, samples > 0 ? n - k : n);
  shifted.rotor_radps = log.rotor_radps.middleRows(samples > 0 ? k : 0, n - k);
  return shifted;
}

int DelayStudy(int flights, double seconds, const std::string& config) {
  const SimulationVehicle v = PresetVehicle(config);
  DelayOptions options;
  std::printf("%6s %10s %10s %10s %10s %9s\n", "flight", "truth ms", "grid ms", "estimate", "std ms", "error ms");
  int within = 0, failed = 0;
  double worst = 0.0;
  for (int flight = 1; flight <= flights; ++flight) {
    RandomStream random = EffectDrawStream(flight, {ParseEffectKind("delay")});
    const double total_s = random.Uniform(options.search.min_s + 0.005, options.search.max_s - 0.005);
    SimulationOptions sim;
    sim.duration_s = seconds;
    sim.seed = 900 + flight;
    sim.effects.Set("delay_s", random.Uniform(0.0, 0.04));
    const SimulationResult simulated = Simulate(v.vehicle, v.parameters, sim);
    const double dt = simulated.log.MedianDt();
    const int shift = static_cast<int>(std::lround((total_s - sim.effects.Scalar("delay_s")) / dt));
    const double truth_s = sim.effects.Scalar("delay_s") + shift * dt;
    try {
      IdentifyOptions identify;
      identify.allow_partial = true;
      const IdentificationResult linear =
          Identify({{simulated.vehicle, ShiftRotorColumns(simulated.log, shift), 1.0}}, identify);
      const DelayEstimate estimate = EstimateDelay(linear, options);
      const double error_ms = 1e3 * (estimate.delay_s - truth_s);
      worst = std::max(worst, std::abs(error_ms));
      within += std::abs(error_ms) <= 2.0;
      std::printf("%6d %10.2f %10.1f %10.2f %10.3f %9.3f\n", flight, 1e3 * truth_s, 1e3 * estimate.grid_best_s,
                  1e3 * estimate.delay_s, 1e3 * estimate.delay_std_s, error_ms);
    } catch (const std::exception& e) {
      ++failed;
      std::printf("%6d %10.2f failed: %s\n", flight, 1e3 * truth_s, e.what());
    }
    std::fflush(stdout);
  }
  std::printf("\n%d flights, delays drawn in [%.0f, %.0f] ms: %d within 2 ms, %d failed, largest error %.3f ms\n",
              flights, 1e3 * options.search.min_s, 1e3 * options.search.max_s, within, failed, worst);
  return within == flights ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--delay") {
    return DelayStudy(argc > 2 ? std::atoi(argv[2]) : 50, argc > 3 ? std::atof(argv[3]) : 90.0,
                      argc > 4 ? argv[4] : "B");
  }
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 5;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 90.0;
  const std::string config = argc > 3 ? argv[3] : "B";
  const std::vector<Case> cases = {
      {"delay", {ParseEffectKind("delay")}},
      {"motor_lag", {ParseEffectKind("motor_lag")}},
      {"acc_bias", {ParseEffectKind("acc_bias")}},
      {"gyro_bias", {ParseEffectKind("gyro_bias")}},
      {"misalignment", {ParseEffectKind("misalignment")}},
      {"delay+motor_lag", {ParseEffectKind("delay"), ParseEffectKind("motor_lag")}},
      {"acc_bias+misalignment", {ParseEffectKind("acc_bias"), ParseEffectKind("misalignment")}},
      {"delay+acc_bias", {ParseEffectKind("delay"), ParseEffectKind("acc_bias")}},
  };
  const SimulationVehicle v = PresetVehicle(config);
  std::printf("%-22s %4s | %-44s | %-44s | %7s %7s %7s | %7s %7s %7s\n", "case", "seed", "effect truth",
              "effect estimate (+-std)", "kt lin%", "Ixx lin", "Izz lin", "kt ref%", "Ixx ref", "Izz ref");
  for (const Case& c : cases) {
    for (int seed = 1; seed <= seeds; ++seed) {
      RandomStream random = EffectDrawStream(seed, c.kinds);
      SimulationOptions options;
      options.duration_s = seconds;
      options.seed = 500 + seed;
      options.effects = DrawRealisticEffects(c.kinds, &random);
      const SimulationResult sim = Simulate(v.vehicle, v.parameters, options);
      IdentifyOptions identify;
      identify.allow_partial = true;
      std::string line;
      char buffer[512];
      try {
        const IdentificationResult linear = Identify({{sim.vehicle, sim.log, 1.0}}, identify);
        RefineOptions refine;
        refine.effects = c.kinds;
        const RefineResult refined = Refine(linear, refine);
        std::string truth, estimate;
        for (EffectKind k : c.kinds) {
          const Eigen::VectorXd t = sim.effects.Get(k), e = refined.effects.Get(k), s = refined.effects_std.Get(k);
          const double unit = k == ParseEffectKind("misalignment")
                                  ? 180 / M_PI
                                  : (k == ParseEffectKind("delay") || k == ParseEffectKind("motor_lag") ? 1000 : 1);
          for (int i = 0; i < t.size(); ++i) {
            std::snprintf(buffer, sizeof(buffer), "%.3g ", t[i] * unit);
            truth += buffer;
            std::snprintf(buffer, sizeof(buffer), "%.3g(%.2g) ", e[i] * unit, s[i] * unit);
            estimate += buffer;
          }
        }
        const double kt = v.parameters.rotor.kt;
        const double ixx = v.parameters.body.inertia(0, 0), izz = v.parameters.body.inertia(2, 2);
        const int xx = linear.system.flight_body_columns[0][3], zz = linear.system.flight_body_columns[0][5];
        std::snprintf(buffer, sizeof(buffer), "%-22s %4d | %-44s | %-44s | %7.3f %7.3f %7.3f | %7.3f %7.3f %7.3f",
                      c.label.c_str(), seed, truth.c_str(), estimate.c_str(), RelErr(linear.solution.chi[0], kt),
                      RelErr(linear.solution.chi[xx], ixx), RelErr(linear.solution.chi[zz], izz),
                      RelErr(refined.refined.chi[0], kt), RelErr(refined.refined.chi[xx], ixx),
                      RelErr(refined.refined.chi[zz], izz));
        line = buffer;
      } catch (const std::exception& e) {
        line = c.label + " seed " + std::to_string(seed) + ": " + e.what();
      }
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    }
  }
  return 0;
}

// Effect recovery study: simulated flights of the paper's vehicle with one (or two) unmodelled
// effects at realistic magnitudes; the refinement must recover them and un-bias the parameters.
//
//   refine_study [seeds=5] [seconds=90] [config=B]

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/model/rotation.h"
#include "rotorid/refine/refine.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"

using namespace rotorid;

namespace {

struct Case {
  std::string label;
  std::vector<EffectKind> kinds;
};

// Realistic random magnitudes (issue 4): delay 5-40 ms, tau 20-60 ms, acc bias 0.1-0.5 m/s^2 per
// axis, gyro bias 0.005-0.03 rad/s, misalignment 1-4 deg.
Effects Draw(const std::vector<EffectKind>& kinds, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto sign = [&]() { return u(rng) < 0.5 ? -1.0 : 1.0; };
  Effects e;
  for (EffectKind k : kinds) {
    switch (k) {
      case EffectKind::kDelay: e.delay_s = 0.005 + 0.035 * u(rng); break;
      case EffectKind::kMotorLag: e.motor_tau_s = 0.02 + 0.04 * u(rng); break;
      case EffectKind::kAccBias:
        for (int a = 0; a < 3; ++a) e.acc_bias[a] = sign() * (0.1 + 0.4 * u(rng));
        break;
      case EffectKind::kGyroBias:
        for (int a = 0; a < 3; ++a) e.gyro_bias[a] = sign() * (0.005 + 0.025 * u(rng));
        break;
      case EffectKind::kMisalignment: {
        Eigen::Vector3d axis(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
        e.misalignment_rad = axis.normalized() * (1.0 + 3.0 * u(rng)) * M_PI / 180.0;
        break;
      }
    }
  }
  return e;
}

double RelErr(double estimate, double truth) { return 100.0 * std::abs(estimate - truth) / std::abs(truth); }

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 5;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 90.0;
  const std::string config = argc > 3 ? argv[3] : "B";
  const std::vector<Case> cases = {
      {"delay", {EffectKind::kDelay}},
      {"motor_lag", {EffectKind::kMotorLag}},
      {"acc_bias", {EffectKind::kAccBias}},
      {"gyro_bias", {EffectKind::kGyroBias}},
      {"misalignment", {EffectKind::kMisalignment}},
      {"delay+motor_lag", {EffectKind::kDelay, EffectKind::kMotorLag}},
      {"acc_bias+misalignment", {EffectKind::kAccBias, EffectKind::kMisalignment}},
      {"delay+acc_bias", {EffectKind::kDelay, EffectKind::kAccBias}},
  };
  const SimulationVehicle v = PresetVehicle(config);
  std::printf("%-22s %4s | %-44s | %-44s | %7s %7s %7s | %7s %7s %7s\n", "case", "seed", "effect truth",
              "effect estimate (+-std)", "kt lin%", "Ixx lin", "Izz lin", "kt ref%", "Ixx ref", "Izz ref");
  for (const Case& c : cases) {
    for (int seed = 1; seed <= seeds; ++seed) {
      std::mt19937_64 rng(seed * 7919 + c.label.size());
      SimulationOptions options;
      options.duration_s = seconds;
      options.seed = 500 + seed;
      options.effects = Draw(c.kinds, rng);
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
          const double unit = k == EffectKind::kMisalignment ? 180 / M_PI : (k == EffectKind::kDelay || k == EffectKind::kMotorLag ? 1000 : 1);
          for (int i = 0; i < t.size(); ++i) {
            std::snprintf(buffer, sizeof(buffer), "%.3g ", t[i] * unit);
            truth += buffer;
            std::snprintf(buffer, sizeof(buffer), "%.3g(%.2g) ", e[i] * unit, s[i] * unit);
            estimate += buffer;
          }
        }
        const double kt = v.parameters.rotor.kt;
        const double ixx = v.parameters.body.inertia(0, 0), izz = v.parameters.body.inertia(2, 2);
        const int c0 = IdimSystem::ConfigColumn(0);
        std::snprintf(buffer, sizeof(buffer), "%-22s %4d | %-44s | %-44s | %7.3f %7.3f %7.3f | %7.3f %7.3f %7.3f",
                      c.label.c_str(), seed, truth.c_str(), estimate.c_str(), RelErr(linear.solution.chi[0], kt),
                      RelErr(linear.solution.chi[c0 + 3], ixx), RelErr(linear.solution.chi[c0 + 5], izz),
                      RelErr(refined.refined.chi[0], kt), RelErr(refined.refined.chi[c0 + 3], ixx),
                      RelErr(refined.refined.chi[c0 + 5], izz));
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

// Accuracy study of the identification on simulated flights of the paper's vehicle: errors against
// the simulator's truth for both methods, and the reported std against the spread over seeds.
//
//   identification_study [seeds=20] [seconds=90] [noise=pixhawk] [effect=value ...]

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"

using namespace rotorid;

namespace {

std::map<std::string, double> TruthValues(const std::vector<SimulationResult>& flights) {
  std::map<std::string, double> truth;
  for (const SimulationResult& f : flights) {
    truth["kt"] = f.truth.rotor.kt;
    truth["kd"] = f.truth.rotor.kd;
    const Eigen::Matrix<double, 9, 1> chi = f.truth.body.ToVector();
    for (int k = 0; k < 9; ++k) truth[f.vehicle.name + "." + kBodyParameterNames[k]] = chi[k];
  }
  return truth;
}

struct Accumulator {
  std::vector<double> values, stds;
  int essential = 0, within3 = 0;
};

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 20;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 90.0;
  const std::string noise = argc > 3 ? argv[3] : "pixhawk";
  Effects effects;
  for (int a = 4; a < argc; ++a) effects.Assign(argv[a]);
  for (const char* method_name : {"noise-aware", "paper"}) {
    for (const char* setup : {"A", "B", "A+B"}) {
      std::map<std::string, Accumulator> acc;
      std::map<std::string, double> truth;
      int failures = 0;
      std::string failure_message;
      for (int seed = 1; seed <= seeds; ++seed) {
        std::vector<SimulationResult> sims;
        std::vector<FlightData> flights;
        for (const std::string config : {"A", "B"}) {
          if (std::string(setup).find(config) == std::string::npos) continue;
          const SimulationVehicle v = PresetVehicle(config);
          SimulationOptions options;
          options.duration_s = seconds;
          options.seed = 1000 * seed + (config == "B");
          options.noise = NoiseLevels::Preset(noise);
          options.effects = effects;
          sims.push_back(Simulate(v.vehicle, v.parameters, options));
          flights.push_back({sims.back().vehicle, sims.back().log, config == "B" && std::string(setup) == "A+B" ? 2.0 : 1.0});
        }
        truth = TruthValues(sims);
        IdentifyOptions options;
        options.tls.method = ParseTlsMethod(method_name);
        options.allow_partial = true;
        try {
          const IdentificationResult r = Identify(flights, options);
          for (int k = 0; k < r.system.num_parameters(); ++k) {
            Accumulator& a = acc[r.system.parameter_names[k]];
            if (!r.solution.essential[k]) continue;
            ++a.essential;
            a.values.push_back(r.solution.chi[k]);
            a.stds.push_back(r.solution.std[k]);
            if (std::abs(r.solution.chi[k] - truth[r.system.parameter_names[k]]) <= 3 * r.solution.std[k]) ++a.within3;
          }
        } catch (const std::exception& e) {
          ++failures;
          failure_message = e.what();
        }
      }
      std::printf("\n== method %s, flights %s, %d seeds x %.0f s, noise %s: %d failed%s%s\n", method_name, setup, seeds,
                  seconds, noise.c_str(), failures, failures ? ": " : "", failures ? failure_message.c_str() : "");
      std::printf("%-10s %12s %10s %10s %10s %9s %9s %8s\n", "parameter", "truth", "mean err%", "max err%",
                  "spread", "mean std", "std/sprd", "in 3std");
      for (const auto& [name, a] : acc) {
        if (a.values.empty()) {
          std::printf("%-10s %12.4e   never essential\n", name.c_str(), truth[name]);
          continue;
        }
        const double t = truth[name];
        double mean = 0, max_err = 0, mean_std = 0;
        for (size_t i = 0; i < a.values.size(); ++i) {
          mean += a.values[i] / a.values.size();
          mean_std += a.stds[i] / a.values.size();
          max_err = std::max(max_err, std::abs(a.values[i] - t));
        }
        double spread = 0;
        for (double v : a.values) spread += (v - mean) * (v - mean);
        spread = a.values.size() > 1 ? std::sqrt(spread / (a.values.size() - 1)) : 0.0;
        std::printf("%-10s %12.4e %10.3f %10.3f %10.2e %9.2e %9.2f %5d/%-3d\n", name.c_str(), t,
                    100 * (mean - t) / std::abs(t), 100 * max_err / std::abs(t), spread, mean_std,
                    spread > 0 ? mean_std / spread : 0.0, a.within3, a.essential);
      }
    }
  }
  return 0;
}

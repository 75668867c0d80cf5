#pragma once

// The ground truth of a simulated flight as JSON (INTERFACE.md section 5, `simulate --truth`):
//
//   {"vehicle": "A", "mass": 1.285,
//    "parameters": {"kt": .., "kd": .., "A.ms_x": .., ..., "A.I_yz": ..},      plain numbers
//    "effects": {<parameter name>: value or [values], one per registered effect},
//    "noise": {"preset": .., "gyro_std_radps": .., "acc_std_mps2": .., ...}, "seed": 1,
//    "parameters_source": "...", "simulation": {...options...}, "controller_model": {...}}

#include <cstdint>
#include <map>
#include <string>

#include "rotorid/model/effects.h"
#include "rotorid/model/parameters.h"
#include "rotorid/sim/simulator.h"

namespace rotorid {

std::string TruthToJson(const SimulationResult& result);
// Atomic write of TruthToJson; throws rotorid::Error naming the path on failure.
void WriteTruthJson(const std::string& path, const SimulationResult& result);

// What a truth file says, read back (for tests comparing estimates with the truth).
struct SimulationTruth {
  std::string vehicle_name;
  VehicleParameters parameters;
  Effects effects;
  std::uint64_t seed = 0;
  std::string noise_preset;
};
// Throws rotorid::Error naming the file and the missing or malformed key.
SimulationTruth ParseTruthJson(const std::string& text, const std::string& source_name);
SimulationTruth ReadTruthJson(const std::string& path);

// The `simulate --json` run summary: options, flight summary and the files written
// (`outputs`: role -> path, e.g. {"log": "A.csv"}).
std::string SimulationReportJson(const SimulationResult& result, const std::map<std::string, std::string>& outputs);

}  // namespace rotorid

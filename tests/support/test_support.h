#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/model/effects.h"
#include "rotorid/sim/simulator.h"

namespace rotorid::testing {

// The project's source folder (set by CTest), and ../shared beside it.
std::string SourceDir();
std::string SharedDir();
// A path under ../shared/data, or nullopt when that data is absent (tests then GTEST_SKIP()).
std::optional<std::string> SharedDataPath(const std::string& relative);
// A simulated flight of a preset vehicle ("A" or "B", MODEL.md section 6) with these effects, at the
// simulator's default (Pixhawk-level) noise.
SimulationResult SimulatePreset(const std::string& preset, double seconds, std::uint64_t seed,
                                const Effects& effects = {});
// The identification of one simulated flight (roll/pitch inertia allowed to be unidentifiable).
IdentificationResult IdentifySimulated(const SimulationResult& sim);

// The whole content of a file ("" when it cannot be read).
std::string Slurp(const std::string& path);

// A fresh temporary directory for one test.
std::string MakeTempDir(const std::string& prefix);

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
// Runs the rotorid binary under test with these arguments (no shell quoting issues: args are passed as argv).
CommandResult RunRotorid(const std::vector<std::string>& args);

}  // namespace rotorid::testing

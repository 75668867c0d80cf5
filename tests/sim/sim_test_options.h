#pragma once

// Flight lengths for the simulator tests. Debug (sanitizer) builds run Eigen unoptimised, about
// 100 times slower, so there the flights are short and integrated at the minimum 1 kHz: those runs
// check memory safety and exactness, the optimised build checks the statistics of long flights.

#include "rotorid/sim/simulator.h"

namespace rotorid::testing {

#ifdef NDEBUG
inline constexpr bool kOptimisedBuild = true;
#else
inline constexpr bool kOptimisedBuild = false;
#endif

inline double TestSeconds(double optimised_s, double debug_s) { return kOptimisedBuild ? optimised_s : debug_s; }

// Default options, made lighter in Debug builds (1 kHz physics, 0.2 s warm-up).
inline SimulationOptions TestOptions(double optimised_s, double debug_s) {
  SimulationOptions options;
  options.duration_s = TestSeconds(optimised_s, debug_s);
  if (!kOptimisedBuild) {
    options.physics_rate_hz = 1000.0;
    options.warmup_s = 0.2;
  }
  return options;
}

}  // namespace rotorid::testing

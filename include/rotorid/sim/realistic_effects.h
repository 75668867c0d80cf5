#pragma once

// Unmodelled effects at random realistic sizes, as the studies and benchmarks inject them (the
// ranges of the refinement issue, typical of small and mid-size multirotors):
//   delay 5-40 ms, motor time constant 20-60 ms, acc bias 0.1-0.5 m/s^2 per axis (random sign),
//   gyro bias 0.005-0.03 rad/s per axis (random sign), misalignment 1-4 deg about a random axis.

#include <cstdint>
#include <vector>

#include "rotorid/model/effects.h"
#include "rotorid/sim/random.h"

namespace rotorid {

struct RealisticEffectRange {
  double delay_min_s = 0.005, delay_max_s = 0.040;
  double motor_tau_min_s = 0.020, motor_tau_max_s = 0.060;
  double acc_bias_min = 0.1, acc_bias_max = 0.5;
  double gyro_bias_min = 0.005, gyro_bias_max = 0.03;
  double misalignment_min_deg = 1.0, misalignment_max_deg = 4.0;
};

// Draws the listed effects (the others stay zero), uniformly within `range`.
Effects DrawRealisticEffects(const std::vector<EffectKind>& kinds, RandomStream* random,
                             const RealisticEffectRange& range = {});

// A random stream for drawing `kinds` from a flight's seed, apart from the simulator's own streams,
// so that a study's flights and effect sizes are independent.
RandomStream EffectDrawStream(std::uint64_t seed, const std::vector<EffectKind>& kinds);

}  // namespace rotorid

#pragma once

// Unmodelled effects at random realistic sizes, as the studies and benchmarks inject them: each
// effect's descriptor gives its range (EffectDescriptor::Info::draw), typical of small and
// mid-size multirotors (docs/simulator.md lists them).

#include <cstdint>
#include <vector>

#include "rotorid/model/effects.h"
#include "rotorid/sim/random.h"

namespace rotorid {

// Draws the listed effects (the others stay zero), each within its descriptor's range, for a
// vehicle with `num_rotors` rotors (the dimension of per-rotor effects).
Effects DrawRealisticEffects(const std::vector<EffectKind>& kinds, RandomStream* random, int num_rotors = 4);

// A random stream for drawing `kinds` from a flight's seed, apart from the simulator's own streams,
// so that a study's flights and effect sizes are independent.
RandomStream EffectDrawStream(std::uint64_t seed, const std::vector<EffectKind>& kinds);

}  // namespace rotorid

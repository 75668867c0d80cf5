#pragma once

// The v1 candidate effects by name, for the diagnosis tests on hand-made verdicts and records.

#include "rotorid/model/effects.h"

namespace rotorid::testing {

inline const EffectKind kDelay = ParseEffectKind("delay");
inline const EffectKind kMotorLag = ParseEffectKind("motor_lag");
inline const EffectKind kAccBias = ParseEffectKind("acc_bias");
inline const EffectKind kGyroBias = ParseEffectKind("gyro_bias");
inline const EffectKind kMisalignment = ParseEffectKind("misalignment");

}  // namespace rotorid::testing

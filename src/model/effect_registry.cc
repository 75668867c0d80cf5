// The registry of effects: one line per effect, in report order (which also fixes each effect's
// bit in masks and its simulator draw stream, so new effects go at the end).

#include "rotorid/model/effects.h"

#define ROTORID_EFFECTS(X) \
  X(DelayEffect)           \
  X(MotorLagEffect)        \
  X(AccBiasEffect)         \
  X(GyroBiasEffect)        \
  X(MisalignmentEffect)    \
  X(ImuLeverArmEffect)     \
  X(RotorDragEffect)       \
  X(RotorInertiaEffect)    \
  X(RotorThrustScaleEffect) \
  X(AccDelayEffect)         \
  X(GroundEffectEffect)    \
  X(BatteryEffect)         \
  X(SlowActuationEffect)

namespace rotorid {
namespace internal {
#define ROTORID_DECLARE_EFFECT(function) const EffectDescriptor& function();
ROTORID_EFFECTS(ROTORID_DECLARE_EFFECT)
#undef ROTORID_DECLARE_EFFECT
}  // namespace internal

const std::vector<EffectKind>& AllEffects() {
  static const std::vector<EffectKind> effects = [] {
#define ROTORID_LIST_EFFECT(function) &internal::function(),
    std::vector<EffectKind> list = {ROTORID_EFFECTS(ROTORID_LIST_EFFECT)};
#undef ROTORID_LIST_EFFECT
    for (size_t i = 0; i < list.size(); ++i) list[i]->index_ = static_cast<int>(i);
    return list;
  }();
  return effects;
}

}  // namespace rotorid

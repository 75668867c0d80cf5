#include "rotorid/sim/realistic_effects.h"

#include "rotorid/core/units.h"

namespace rotorid {

Effects DrawRealisticEffects(const std::vector<EffectKind>& kinds, RandomStream* random,
                             const RealisticEffectRange& range) {
  auto signed_size = [&](double low, double high) {
    const double sign = random->Uniform() < 0.5 ? -1.0 : 1.0;
    return sign * random->Uniform(low, high);
  };
  Effects e;
  for (EffectKind kind : kinds) {
    switch (kind) {
      case EffectKind::kDelay:
        e.delay_s = random->Uniform(range.delay_min_s, range.delay_max_s);
        break;
      case EffectKind::kMotorLag:
        e.motor_tau_s = random->Uniform(range.motor_tau_min_s, range.motor_tau_max_s);
        break;
      case EffectKind::kAccBias:
        for (int a = 0; a < 3; ++a) e.acc_bias[a] = signed_size(range.acc_bias_min, range.acc_bias_max);
        break;
      case EffectKind::kGyroBias:
        for (int a = 0; a < 3; ++a) e.gyro_bias[a] = signed_size(range.gyro_bias_min, range.gyro_bias_max);
        break;
      case EffectKind::kMisalignment: {
        // A direction uniform on the sphere (normalised Gaussian vector).
        Eigen::Vector3d axis;
        do {
          axis = Eigen::Vector3d(random->Normal(), random->Normal(), random->Normal());
        } while (axis.norm() < 1e-6);
        const double angle_rad = random->Uniform(range.misalignment_min_deg, range.misalignment_max_deg) * kDegToRad;
        e.misalignment_rad = axis.normalized() * angle_rad;
        break;
      }
    }
  }
  return e;
}

RandomStream EffectDrawStream(std::uint64_t seed, const std::vector<EffectKind>& kinds) {
  constexpr std::uint64_t kFirstEffectStream = 1000;  // the simulator's streams are below it
  std::uint64_t stream = kFirstEffectStream;
  for (EffectKind kind : kinds) stream += std::uint64_t{1} << static_cast<int>(kind);
  return RandomStream(seed, stream);
}

}  // namespace rotorid

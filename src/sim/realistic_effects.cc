#include "rotorid/sim/realistic_effects.h"

#include "rotorid/core/vehicle.h"

namespace rotorid {

Effects DrawRealisticEffects(const std::vector<EffectKind>& kinds, RandomStream* random, int num_rotors) {
  Vehicle vehicle;
  vehicle.rotors.resize(static_cast<size_t>(num_rotors));
  Effects e;
  for (EffectKind kind : kinds) {
    const DrawRange& range = kind->info().draw;
    Eigen::VectorXd value(kind->Dimension(vehicle));
    switch (range.shape) {
      case DrawShape::kUniform:
        for (Eigen::Index a = 0; a < value.size(); ++a) value[a] = random->Uniform(range.low, range.high) * range.to_si;
        break;
      case DrawShape::kSignedPerAxis:
        for (Eigen::Index a = 0; a < value.size(); ++a) {
          const double sign = random->Uniform() < 0.5 ? -1.0 : 1.0;
          value[a] = sign * random->Uniform(range.low, range.high) * range.to_si;
        }
        break;
      case DrawShape::kRandomDirection: {
        // A direction uniform on the sphere (normalised Gaussian vector).
        // (The 3-d draw keeps its original expression: the evaluation order of the constructor's
        // arguments is the compiler's, and studies are reproduced from their seeds.)
        Eigen::VectorXd axis(value.size());
        do {
          if (axis.size() == 3) {
            axis = Eigen::Vector3d(random->Normal(), random->Normal(), random->Normal());
          } else {
            for (Eigen::Index a = 0; a < axis.size(); ++a) axis[a] = random->Normal();
          }
        } while (axis.norm() < 1e-6);
        value = axis.normalized() * (random->Uniform(range.low, range.high) * range.to_si);
        break;
      }
    }
    // A zero-sum effect's mean is a linear parameter's (kt's): draw the spread around it.
    if (kind->info().zero_sum && value.size() > 0) value.array() -= value.mean();
    e.Set(kind, value);
  }
  return e;
}

RandomStream EffectDrawStream(std::uint64_t seed, const std::vector<EffectKind>& kinds) {
  constexpr std::uint64_t kFirstEffectStream = 1000;  // the simulator's streams are below it
  std::uint64_t stream = kFirstEffectStream;
  for (EffectKind kind : kinds) stream += std::uint64_t{1} << kind->index();
  return RandomStream(seed, stream);
}

}  // namespace rotorid

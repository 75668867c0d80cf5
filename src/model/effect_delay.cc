// `delay` (INTERFACE.md section 1): the rotor speeds act delay_s after the log says,
//   Omega_true(t) = Omega_log(t - delay_s),
// the log interpolated linearly between its samples and held beyond its ends. Positive: the log
// leads the physics (command-to-motor latency); negative: the IMU lags the rotor signal.

#include <algorithm>
#include <cmath>

#include "model/effect_adapter.h"
#include "rotorid/core/units.h"

namespace rotorid::internal {
namespace {

struct DelayModel {
  template <typename T>
  static void Transform(const T* p, double dt, const Eigen::Matrix<T, -1, 1>& x, Eigen::Matrix<T, -1, 1>* out) {
    const Eigen::Index n = x.size();
    const T shift = p[0] / dt;
    const double whole = std::floor(ScalarPart(shift));
    const T frac = shift - T(whole);  // in [0, 1): u[k] = x(k - whole - frac)
    const Eigen::Index offset = static_cast<Eigen::Index>(whole);
    auto sample = [&](Eigen::Index k) { return x[std::clamp<Eigen::Index>(k, 0, n - 1)]; };
    out->resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      // Between samples k - offset - 1 and k - offset.
      const T upper = sample(k - offset), lower = sample(k - offset - 1);
      (*out)[k] = upper + frac * (lower - upper);
    }
  }
  static double CommandDelay(const Eigen::VectorXd& v) { return v[0]; }
  static double MotorTimeConstant(const Eigen::VectorXd&) { return 0.0; }
  static double EquivalentValue(double delay_s) { return delay_s; }
};

}  // namespace

const EffectDescriptor& DelayEffect() {
  static const RotorSignalEffect<DelayModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "delay";
    i.parameter_name = "delay_s";
    i.unit = "s";
    i.meaning = "Omega_true(t) = Omega_log(t - delay_s), linear interpolation";
    i.stage = EffectStage::kRotorSignal;
    i.chain_position = 0;
    i.dimension = 1;
    i.lower_bound = -0.1;
    i.upper_bound = 0.2;
    i.grid_searched = true;
    i.draw = {DrawShape::kUniform, 0.005, 0.040};
    i.simulator_limit = {true, 0.0, 0.05};
    i.settle_tolerance = 1e-5;
    i.display_scale = 1e3;
    i.display_unit = "ms";
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal

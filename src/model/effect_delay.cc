// `delay` (INTERFACE.md section 1): the rotor speeds act delay_s after the log says,
//   Omega_true(t) = Omega_log(t - delay_s),
// the log interpolated between its samples by a cubic (Catmull-Rom) spline and held beyond its
// ends. Positive: the log leads the physics (command-to-motor latency); negative: the IMU lags the
// rotor signal. The spline's first derivative is continuous, so the rows and the criterion are
// smooth in the delay across sample multiples; with linear interpolation their slope jumps there
// and the refinement stuck at whole samples (a 26.4 ms delay ended at 25.000 ms at 200 Hz).

#include <algorithm>
#include <cmath>

#include "model/effect_adapter.h"
#include "rotorid/core/units.h"

namespace rotorid::internal {
namespace {

struct DelayModel {
  template <typename T>
  static void Transform(const T* p, const RotorSignalInput& input, const Eigen::Matrix<T, -1, 1>& x,
                        Eigen::Matrix<T, -1, 1>* out) {
    const Eigen::Index n = x.size();
    const T shift = p[0] / input.dt;
    const double whole = std::floor(ScalarPart(shift));
    const T frac = shift - T(whole);  // in [0, 1): u[k] = x(k - whole - frac)
    const Eigen::Index offset = static_cast<Eigen::Index>(whole);
    auto sample = [&](Eigen::Index k) { return x[std::clamp<Eigen::Index>(k, 0, n - 1)]; };
    const T u = T(1.0) - frac;  // position between samples i (u = 0) and i + 1 (u = 1)
    out->resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::Index i = k - offset - 1;
      const T p0 = sample(i - 1), p1 = sample(i), p2 = sample(i + 1), p3 = sample(i + 2);
      (*out)[k] = p1 + T(0.5) * u *
                           ((p2 - p0) +
                            u * ((T(2.0) * p0 - T(5.0) * p1 + T(4.0) * p2 - p3) + u * (T(3.0) * (p1 - p2) + p3 - p0)));
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
    // Omega_true(t) = Omega_log(t - delay_s), cubic (Catmull-Rom) interpolation
    i.stage = EffectStage::kRotorSignal;
    i.chain_position = 0;
    i.dimension = 1;
    i.lower_bound = -0.1;
    i.upper_bound = 0.2;
    i.grid_searched = true;
    i.checked_at_half_cutoff = true;
    i.draw = {DrawShape::kUniform, 0.005, 0.040};
    i.simulator_limit = {true, 0.0, 0.05};
    // A rotor speed measured through a filter can be logged up to ~30 ms after it acts; ESC latency and a
    // few control periods stay under ~150 ms. Beyond, the logs' clocks disagree or a lag hides in it.
    i.plausible = {true, -0.03, 0.15, PlausibleScale::kNone, "ESC latency and a few control periods"};
    i.negligible = SubMillisecondTimeShift();
    i.settle_tolerance = 1e-5;
    i.display_scale = 1e3;
    i.display_unit = "ms";
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal

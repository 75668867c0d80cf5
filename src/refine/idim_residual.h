#pragma once

// The residual block of the refinement (internal; tests check its Jacobians).

#include <memory>
#include <mutex>

#include <ceres/ceres.h>
#include <Eigen/Core>

#include "rotorid/ident/observation.h"
#include "rotorid/refine/effect_model.h"

namespace rotorid::internal {

constexpr int kNumEffectParameters = 12;  // delay, tau, acc bias (3), gyro bias (3), quaternion (4: x y z w)
using EffectJet = ceres::Jet<double, kNumEffectParameters>;

// The delayed and lagged rotor signal of one flight at its row samples, with derivatives with respect
// to delay and tau, recomputed (once, under a lock) whenever Ceres evaluates at a new (delay, tau).
class RotorSignalCache {
 public:
  explicit RotorSignalCache(const ProcessedFlight* flight) : flight_(flight) {}

  struct State {
    double delay = NAN, tau = NAN;
    EffectiveRotor rotor;
  };

  std::shared_ptr<const State> Get(double delay, double tau) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!state_ || state_->delay != delay || state_->tau != tau) {
      auto state = std::make_shared<State>();
      state->delay = delay;
      state->tau = tau;
      state->rotor = EffectiveRotorAtRows(*flight_, delay, tau);
      state_ = state;
    }
    return state_;
  }

 private:
  const ProcessedFlight* flight_;
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const State> state_;
};

// Shared by all residual blocks: the TLS weights and metric and the row offsets.
struct CriterionContext {
  Eigen::MatrixXd metric;  // N over all p + 1 columns
  // The chi block holds chi ./ chi_scale, so that its Jacobian columns are of comparable size (kt is
  // ~1e-6 N s^2, an inertia ~1e-2 kg m^2): the solver and ceres::Covariance see a well-conditioned problem.
  Eigen::VectorXd chi_scale;
  double total_rows = 0.0;
  int num_parameters = 0;
};

// Whitened TLS residuals of `count` row samples of one flight:
//   r = sqrt(lambda) * (w(effects) . chi_t) / d,   d^2 = chi_t^T N chi_t / rows.
// Parameter blocks: chi ./ chi_scale (p), delay (1), tau (1), acc bias (3), gyro bias (3), misalignment
// quaternion (4, Eigen layout x y z w; v_imu = q v_body). The rows come from the templated model
// with Jets over the effect parameters; chi enters linearly and is differentiated by hand.
class IdimResidualBlock : public ceres::CostFunction {
 public:
  IdimResidualBlock(const ProcessedFlight* flight, const RotorSignalCache* rotor, const CriterionContext* context,
                    int config, int first, int count, Eigen::VectorXd sqrt_weight)
      : flight_(flight), rotor_(rotor), context_(context), config_(config), first_(first), count_(count),
        sqrt_weight_(std::move(sqrt_weight)) {
    set_num_residuals(6 * count);
    *mutable_parameter_block_sizes() = {context->num_parameters, 1, 1, 3, 3, 4};
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const ProcessedFlight* flight_;
  const RotorSignalCache* rotor_;
  const CriterionContext* context_;
  int config_, first_, count_;
  Eigen::VectorXd sqrt_weight_;
};

}  // namespace rotorid::internal

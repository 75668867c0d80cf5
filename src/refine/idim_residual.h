#pragma once

// The residual block of the refinement (internal; tests check its Jacobians).

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <array>
#include <memory>
#include <mutex>
#include <vector>

#include "rotorid/ident/observation.h"
#include "rotorid/ident/tls.h"
#include "rotorid/refine/effect_model.h"

namespace rotorid::internal {

// The effects of a refinement: one Ceres parameter block per free effect (its own size, in this
// order after chi), the others held at their values in `fixed`.
struct EffectBlocks {
  std::vector<EffectKind> free;
  Effects fixed;
  // Per free effect, the unit its block is in (value = block * scale; empty: 1).
  std::vector<double> scale;

  double Scale(size_t j) const { return j < scale.size() ? scale[j] : 1.0; }

  // The effects at a point: the free ones from the parameter blocks (parameters[1 + j]).
  Effects At(double const* const* parameters, const Vehicle& vehicle) const;
};

// The anchor of the anchored criterion (MODEL.md 9) for one flight. Each moment row is divided by
// h_c = sqrt(1 - s_c + s_c g_c^2), with g_c the gain of the rotor-signal effects on that row's
// rotor moment: the RMS about its mean of M_c = sum_i u_ci Omega_i^2 with the effects, over the
// same without them (u_ci: rotor i's unit moment with the start's kt and kd). An effect that only
// attenuates the rotor moment by a factor a (a lag where the data have none) lets the inertia
// shrink by a and, with it, every part of the equation error that passes through the rotor moment
// or the inertia: the model error and the rotor signal's noise. s_c is that part's share of the
// row's residual variance at the start (what the noise model does not explain, plus the rotor
// noise), so h_c shrinks with it and the criterion does not move; the remaining share (noise of
// the measured angular acceleration and specific force) does not scale, and h_c does not charge
// it. A delay keeps g_c at 1. The force rows need no anchor: the known mass fixes their scale.
struct RotorMomentAnchor {
  std::array<double, 6> power{};  // per wrench component: sum (M_c - mean)^2 without effects (0: none)
  std::array<double, 6> share{};  // s_c
  Eigen::Matrix<double, 6, Eigen::Dynamic> unit;  // u_ci
};
// `flight` is flight `index` of `system`, whose rows are the flight's with `effects` (evaluated here
// one row sample at a time: no W needed); chi the start.
RotorMomentAnchor AnchorRotorMoments(const ProcessedFlight& flight, const Effects& effects, const IdimLayout& system,
                                     int index, const Eigen::VectorXd& chi);

// The rotor signal of one flight at its row samples after the rotor-signal effects, with
// derivatives with respect to the free ones, recomputed (once, under a lock) whenever Ceres
// evaluates at new rotor-signal values; with an anchor, also the gains g_c and their derivatives.
class RotorSignalCache {
 public:
  RotorSignalCache(const ProcessedFlight* flight, const EffectBlocks* blocks, const RotorMomentAnchor* anchor = nullptr)
      : flight_(flight), blocks_(blocks), anchor_(anchor) {}

  struct State {
    Eigen::VectorXd key;  // the rotor-signal effects' values, concatenated
    EffectiveRotor rotor;
    std::array<double, 6> gain{1, 1, 1, 1, 1, 1};  // h_c
    // d h_c / d (free rotor-signal coordinate d), as rotor.derivative[d]: 6 x coordinates.
    Eigen::Matrix<double, 6, Eigen::Dynamic> gain_derivative;
  };
  std::shared_ptr<const State> Get(const Effects& effects) const;

 private:
  void SetGains(State* state) const;

  const ProcessedFlight* flight_;
  const EffectBlocks* blocks_;
  const RotorMomentAnchor* anchor_;
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const State> state_;
};

// The criterion's piece that turns the rows of a row sample into whitened residuals and their
// derivatives: the TLS one, r = sqrt(lambda) (w . chi_t) / (d g_c), d^2 = chi_t^T N chi_t / rows,
// with the TLS weights and metric and (anchored criterion) the rotor-moment gain g_c of the
// flight's RotorSignalCache (1 for the TLS criterion). Shared by all residual blocks.
struct CriterionContext {
  Eigen::MatrixXd metric;  // N over all p + 1 columns
  // The chi block holds chi ./ chi_scale, so that its Jacobian columns are of comparable size (kt is
  // ~1e-6 N s^2, an inertia ~1e-2 kg m^2): the solver and ceres::Covariance see a well-conditioned problem.
  Eigen::VectorXd chi_scale;
  double total_rows = 0.0;
  int num_parameters = 0;
};

// Whitened residuals of `count` row samples of one flight. Parameter blocks: chi ./ chi_scale (p),
// then one per free effect of `blocks`. The rows come from the templated model with Jets over the
// effect parameters (in passes of up to kWideImuJetSize coordinates); chi enters linearly and is
// differentiated by hand.
class IdimResidualBlock : public ceres::CostFunction {
 public:
  IdimResidualBlock(const ProcessedFlight* flight, const RotorSignalCache* rotor, const CriterionContext* context,
                    const EffectBlocks* blocks, const std::array<int, kNumBodyParameters>& body_columns, int first,
                    int count, Eigen::VectorXd sqrt_weight);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  struct Point;
  template <typename T>
  void EvaluatePass(const Point& point, size_t first_coordinate, double* residuals, double** jacobians) const;

  const ProcessedFlight* flight_;
  const RotorSignalCache* rotor_;
  const CriterionContext* context_;
  const EffectBlocks* blocks_;
  std::array<int, kNumBodyParameters> body_columns_;  // the flight's body parameters' chi coordinates
  int first_, count_;
  Eigen::VectorXd sqrt_weight_;
};

}  // namespace rotorid::internal

#pragma once

// The residual block of the refinement (internal; tests check its Jacobians).

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <mutex>
#include <vector>

#include "rotorid/ident/observation.h"
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

// The rotor signal of one flight at its row samples after the rotor-signal effects, with
// derivatives with respect to the free ones, recomputed (once, under a lock) whenever Ceres
// evaluates at new rotor-signal values.
class RotorSignalCache {
 public:
  RotorSignalCache(const ProcessedFlight* flight, const EffectBlocks* blocks) : flight_(flight), blocks_(blocks) {}

  struct State {
    Eigen::VectorXd key;  // the rotor-signal effects' values, concatenated
    EffectiveRotor rotor;
  };
  std::shared_ptr<const State> Get(const Effects& effects) const;

 private:
  const ProcessedFlight* flight_;
  const EffectBlocks* blocks_;
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const State> state_;
};

// The criterion's piece that turns the rows of a row sample into whitened residuals and their
// derivatives: the TLS one, r = sqrt(lambda) (w . chi_t) / d, d^2 = chi_t^T N chi_t / rows, with
// the TLS weights and metric. Shared by all residual blocks. (Another criterion replaces this
// class and nothing else.)
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
                    const EffectBlocks* blocks, int config, int first, int count, Eigen::VectorXd sqrt_weight);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  struct Point;
  template <typename T>
  void EvaluatePass(const Point& point, size_t first_coordinate, double* residuals, double** jacobians) const;

  const ProcessedFlight* flight_;
  const RotorSignalCache* rotor_;
  const CriterionContext* context_;
  const EffectBlocks* blocks_;
  int config_, first_, count_;
  Eigen::VectorXd sqrt_weight_;
};

}  // namespace rotorid::internal

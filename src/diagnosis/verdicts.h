#pragma once

// The diagnosis' verdict per candidate effect (internal): its test, magnitude and std, the
// smallest size this data would reveal, its status, and the ranking.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "diagnosis/linearization.h"
#include "diagnosis/selection.h"
#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {

// Smallest size per parameter at which the F-test and the shrink floor would flag the effect,
// from the linearised information: a parameter of size a removes (a / std)^2 / n_eff of the
// residual.
Eigen::VectorXd DetectableSizes(const Eigen::VectorXd& std_dev, int parameters, double effective_samples,
                                const DiagnosisOptions& options);

// Above this share of its signature in components without weight, no held-out test of the scored
// components can see an effect.
inline constexpr double kMostlyUnscored = 0.5;

// The largest share of one of the effect's coordinates' signature that falls in components without
// weight (EffectLinearization::effect_unscored_share), and that coordinate's label; 0 and empty when
// every component is weighed.
struct UnscoredShare {
  double share = 0.0;
  std::string label;
};
UnscoredShare MostlyUnscoredShare(const EffectLinearization& linearization, EffectKind kind);

// The selection as it ended, and the final model on all identification data.
struct SelectionOutcome {
  const ForwardSelection& forward;
  const BackwardElimination& backward;
  const std::vector<SelectionStep>& steps;   // GapAfterEachEffect of the kept effects
  const Effects& final_effects;              // kept effects refined on all data
  const EffectLinearization& linearization;  // criterion linearised at the final model
  const EffectSubsetFit& kept_fit;           // the kept effects' fit in that linearisation
};

// One candidate's verdict (status "selected" or "not significant"; confounding and notes come
// later): kept effects carry their test on top of the kept effects added before them, dropped ones
// their test on top of the others at the moment they were dropped, the rest their last forward
// test. Magnitudes: kept effects from the final fit, the others the mean of their fold fits, or
// the linearised step of a candidate that was only screened.
EffectVerdict VerdictOf(EffectKind kind, const SelectionContext& context, const SelectionOutcome& outcome);

// The rivals' verdicts say with what they are confounded, the kept effects' with which rivals; an
// indistinguishable rival's status becomes "confounded".
void MarkConfounded(const std::vector<ConfoundedEffects>& confounded, std::vector<EffectVerdict>* verdicts);

// The kept effects in the order they were added, then the others by the held-out residual they
// removed, then the unavailable ones.
std::vector<EffectVerdict> Rank(std::vector<EffectVerdict> verdicts, const std::vector<EffectKind>& kept,
                                const std::vector<EffectVerdict>& unavailable);

// A misalignment's coordinate beyond 3 std about axis k where the linear identification discarded
// the product of inertia of the other two axes (I_xy for z): a rotation of the gyro about k mixes
// those two rows as that product does, and takes the coupling the discarded product leaves (the
// independent simulator's A flights: I_xy = 1e-4 dropped at 11 % std, misalignment about z -0.24
// to -0.27 deg; with I_xy estimated, 0.04 +- 0.10 deg). The sentence that says so, else empty.
std::string DiscardedProductStatement(const EffectVerdict& v, const std::vector<DiscardedParameter>& discarded);

// The component with the largest model error (gap beyond the noise floor) among those whose gap is
// at least sqrt(2) times the floor (as much model error as noise); when none is, the one whose gap
// exceeds its floor the most.
int WhereComponent(const HeldOutGap& baseline);

}  // namespace rotorid::internal

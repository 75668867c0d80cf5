#pragma once

// Confounding of the diagnosis (internal): a candidate that removed about as much held-out
// residual as a kept effect, at the step that effect was selected, is compared with it directly on
// the held-out rows. If the kept effect does not fit significantly and practically better, the
// data cannot tell them apart.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "diagnosis/linearization.h"
#include "diagnosis/selection.h"
#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {

// A rival of a kept effect: refined at the forward step that selected it (on top of `base`),
// significant, and with at least half its held-out shrink.
struct Rival {
  EffectKind selected = nullptr;
  EffectKind other = nullptr;
  EffectMask base = 0;
  EffectTest selected_test;
  EffectTest other_test;
  std::optional<TimingSeparation> separation;  // a timing twin's joint fit at half the cut-off
};

// The rivals of the effects in `kept`, step by step in candidate order. Rivals that are kept
// themselves are none.
std::vector<Rival> FindRivals(const std::vector<ForwardStep>& steps, EffectMask kept);

// Paired comparison of the two models' held-out residuals (CompareHeldOut with these scales):
// distinguishable when significant at `alpha` and the shrinks are not practically equal; the note
// says which, and for two scalar effects what each fits alone. A timing twin that the joint fit at
// half the cut-off separated from the selected one is distinguishable, whatever the held-out rows say.
ConfoundedEffects CompareRival(const Rival& rival, const ModelRecord& with_selected, const ModelRecord& with_other,
                               const HeldOutScales& scales, double alpha);

// The largest |correlation| between a parameter of c->selected and one of c->other in `joint_fit`
// (a fit with both in the model), and its labels.
void SetLargestCorrelation(const EffectSubsetFit& joint_fit, ConfoundedEffects* c);

// Each rival with its comparison and its correlation from the criterion linearised at the final
// model with the kept effects (`kept_kinds`) and the rival in it (the refinement's Ceres covariance
// drops weak directions, see linearization.h).
std::vector<ConfoundedEffects> AnalyzeConfounding(const std::vector<Rival>& rivals, const SelectionContext& context,
                                                  const HeldOutScales& scales,
                                                  const EffectLinearization& final_linearization,
                                                  const std::vector<EffectKind>& kept_kinds);

}  // namespace rotorid::internal

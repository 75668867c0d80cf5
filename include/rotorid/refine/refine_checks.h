#pragma once

// The plausibility checks (rotorid/ident/checks.h) of refinement and delay results: the refined
// parameters, effects that are not finite or end on the bound of their range, Table III.

#include <string>
#include <vector>

#include "rotorid/ident/checks.h"
#include "rotorid/refine/delay.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

// `label` names the model in the messages ("refined", "delay,motor_lag", ...). Effects on their
// bounds are the ones Refine reported (RefineResult::on_bound): an error by default, since a value
// the bound clipped is not an estimate; ablation, which compares subsets, passes kWarning.
std::vector<Check> CheckRefinement(const IdentificationResult& linear, const RefineResult& refined,
                                   const std::string& label = "refined",
                                   CheckStatus on_bound_status = CheckStatus::kError);
// The linear step's Table III error above 100 % is what an effect the linear model lacks gives (an
// IMU lever arm's centripetal acceleration on a yaw spin: 763-988 % in roll and pitch). When every
// error of the refined model is within 100 %, the refinement explains it: that check of `checks`
// becomes a warning that says so, and the refined model's own checks decide the exit.
void ExcuseLinearErrorTheRefinementExplains(const IdentificationResult& linear, const RefineResult& refined,
                                            std::vector<Check>* checks);

std::vector<Check> CheckDelay(const IdentificationResult& linear, const DelayEstimate& estimate,
                              const DelayOptions& options);

}  // namespace rotorid

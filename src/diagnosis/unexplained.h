#pragma once

// What the selected effects leave unexplained (internal): the held-out components whose gap after
// the selection lies far above the noise floor, where that residual lies, and what it can be.

#include <string>
#include <vector>

#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {

// The components of `final_gap` (held out, with the selected effects) at least
// options.unexplained_floor_ratio times their noise floor with a model error of at least
// options.unexplained_min_pct, largest model error first; `where` (LocateGap with the final
// effects) gives each its band and stretch. Components the baseline does not score (no rotor term
// in the linear model: Mz with kd discarded) are not judged: their noise floor is no floor.
std::vector<UnexplainedResidual> FindUnexplained(const HeldOutGap& baseline, const HeldOutGap& final_gap,
                                                 const GapLocation& where, const DiagnosisOptions& options);

// "a force off the thrust axis that no sensor effect reproduces: ..." for Fx, Fy; the same for Fz
// and the moments with what can cause them.
std::string UnexplainedNote(int component);

// One entry for people: "Fx 5.10 % held out against a noise floor of 0.45 % (99 % of its residual
// beyond it), mostly at 0-1 Hz (93 %), worst in flight.csv 12.5-17.5 s: a force off the thrust axis ...".
std::string UnexplainedSentence(const UnexplainedResidual& u);

// Each entry as a line "unexplained: <sentence>"; "unexplained: nothing far above the noise floor" when empty.
std::string UnexplainedText(const std::vector<UnexplainedResidual>& unexplained);

}  // namespace rotorid::internal

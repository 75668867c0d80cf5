#pragma once

// The scale-free test of a component the held-out score leaves out (internal). With kd discarded,
// the linear model has no rotor term in Mz, the held-out score does not weigh Mz, and an effect
// acting there (a rotor inertia) is invisible to every other test. Keeping kd does not help: the
// yaw row I_zz w_z' + J sum(+-Omega') = kd sum(+-Omega^2) fixes only the ratios of I_zz, J and kd,
// and the TLS shrinks them together (docs/diagnosis.md, tenth session). This test fits that row
// alone with the rotor coefficient's column fixed at 1, so that every coefficient is a ratio to it,
// and judges a candidate by the held-out relative error of the row, which the common scale drops
// out of. Nothing here names an effect: the candidate's columns are the derivatives of the row by
// the refinement's own Jets (EffectRows), and whether its value comes out as a ratio to the rotor
// coefficient follows from where its term enters the row.

#include <map>
#include <string>
#include <vector>

#include "diagnosis/held_out.h"
#include "diagnosis/linearization.h"
#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/ident/observation.h"
#include "rotorid/model/effects.h"

namespace rotorid::internal {

// What the test is run on: the held-out folds (or flights) with the effects the selection kept,
// fitted in each fold; all identification data with the final model, and its fit's rotor
// coefficients (an SI value needs them).
struct ScaleFreeData {
  const std::vector<Fold>& folds;
  const std::vector<Effects>& fold_effects;
  const std::vector<ProcessedFlight>& flights;
  const Effects& final_effects;
  const std::map<std::string, double>& final_parameters;
  const std::map<std::string, double>& final_parameter_std;
};

// Whether the test applies to `kind`: every coordinate of it acts mostly in components nothing
// scores (EffectLinearization::effect_unscored_share above kMostlyUnscored). The row test judges the
// candidate as a whole, and a coordinate that acts elsewhere (rotor drag's flapping moment, in roll
// and pitch) has no column in that row to be judged by. Effects whose coordinates the refinement
// ties (a zero-sum or held coordinate) would need those ties in the row fit too, which it lacks.
bool ScaleFreeTestable(EffectKind kind, const EffectLinearization& linearization);

// The scale-free test of `kind` in `component` (one the linear model leaves without rotor term), on
// top of the kept effects: the row fitted on each fold's training rows without and with the
// candidate, scored on its held-out rows (F-test as TestAddedEffects), and the candidate's value in
// the row's units from all identification data.
ScaleFreeTest TestScaleFree(EffectKind kind, int component, const ScaleFreeData& data, const DiagnosisOptions& options);

// Runs the scale-free test for every verdict that is not selected and ScaleFreeTestable, in each
// component nothing scores, keeping the one with the
// largest held-out shrink. A candidate that passes it (significant, its sign and, with an SI value,
// its physical range plausible) is marked selected. Returns those, in the verdicts' order.
std::vector<EffectKind> SelectInUnscoredComponents(const EffectLinearization& linearization, const ScaleFreeData& data,
                                                   const DiagnosisOptions& options, const Vehicle& vehicle,
                                                   std::vector<EffectVerdict>* verdicts);

}  // namespace rotorid::internal

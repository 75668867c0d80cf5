#pragma once

// The check `physical_consistency` (INTERFACE.md 6, MODEL.md 10) of a model's parameters: each body
// the model predicts with -- a configuration's inertia with each of its first moments (one, or one per
// flight) and the configuration's mass -- must be one some mass distribution has. When it is not, the
// check names the likely cause and how far the estimate lies from the nearest consistent body, in its
// own std (ProjectOntoConsistentBodies): a large distance is itself a finding.

#include <string>
#include <vector>

#include "rotorid/ident/checks.h"
#include "rotorid/model/physical_consistency.h"

namespace rotorid {

struct BodyAssessment {
  std::string name;    // "A", or "A.flight2" for a configuration with per-flight first moments
  std::string config;  // "A"
  double mass_kg = 0.0;
  BodyParameters predicted;  // the values the model predicts with
  PhysicalConsistency consistency;
  // The estimate: the essential values and the discarded parameters' estimates beside them (profiled),
  // whatever the model predicts with; a discarded parameter without one is free.
  BodyParameters estimate;
  // The physical body nearest to the estimate in its metric (its std, and covariance where known),
  // and the distance (std): 0 when the estimate is a body. Not computed without a std.
  bool has_projection = false;
  ConsistentProjection projection;
  std::string cause;  // why it is not a body, in words; empty when it is
};

// Step 3 of issue 37: for each discarded diagonal inertia entry (I_xx, I_yy, I_zz in turn, each with
// the others at what the model predicts with) of each configuration in `mass_kg`, the range with which
// every body of the configuration is physical (solution->allowed_low/high), and, where the value
// PredictionChi would take lies outside it (1 % of its width kept clear of the ends) or the entry has
// no estimate, the value to predict with instead (within_range_chi): the estimate clamped into the
// range, or its middle. Called by identify and refine on every solution they return.
void SetAllowedRanges(const IdimLayout& layout, const std::map<std::string, double>& mass_kg, TlsSolution* solution);

// One assessment per body of each configuration in p.mass_kg, in the configurations' order of
// p.mass_kg and the first moments' order of their names.
std::vector<BodyAssessment> AssessBodies(const CheckedParameters& p);

// `physical_consistency`, one per body: ok with the centre of mass and the inertia about it, or an
// error naming the cause (a discarded inertia, a first moment the flights do not fix, a wrong mass or
// geometry) and the distance to the nearest consistent body. A body the model predicts with but the
// estimate is not (its discarded inertias moved into the range a body allows) is a warning when the
// estimate lies more than kFarFromABodyStd from every body. `label` names the model ("linear").
inline constexpr double kFarFromABodyStd = 3.0;
std::vector<Check> PhysicalConsistencyChecks(const CheckedParameters& p, const std::string& label);

}  // namespace rotorid

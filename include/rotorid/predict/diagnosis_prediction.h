#pragma once

// The diagnosis's "how far does the gap shrink" as a simulator sees it (INTERFACE.md 6,
// steps[].prediction): the held-out flights predicted (rotorid predict's protocol) with the linear
// model and after each step of the forward selection, each step's model refined on the
// identification flights with the effects kept so far.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/ident/identify.h"
#include "rotorid/predict/predict.h"

namespace rotorid {

struct StepPrediction {
  std::vector<EffectKind> effects;  // the model's effects (none: the linear model)
  PredictionCurves curves;          // held-out, pooled
  std::string unavailable;          // why it could not be flown (an impossible body), else empty
};

// The linear model, then one entry per diagnosis step; empty without held-out flights. `settings`:
// horizon, scope and grid (its paths are not read).
std::vector<StepPrediction> PredictDiagnosisSteps(const Diagnosis& diagnosis, const std::vector<FlightData>& training,
                                                  const std::vector<FlightData>& held_out,
                                                  const IdentifyOptions& identify, const PredictOptions& settings = {});

// Adds `baseline.prediction` and `steps[k].prediction` to a diagnosis report (DiagnosisJson):
// {windows, mae: {group: {"10": x, "50": y}}, naive_mae: {...}} at h = 10 and N, or {unavailable}.
void AddStepPredictions(const std::vector<StepPrediction>& predictions, nlohmann::json* report);

}  // namespace rotorid

#include "rotorid/predict/diagnosis_prediction.h"

#include <algorithm>

#include "predict/predict_json.h"
#include "predict/rollout.h"
#include "rotorid/core/error.h"
#include "rotorid/ident/tls.h"
#include "rotorid/refine/refine.h"
#include "rotorid/report/json.h"

namespace rotorid {
namespace {

// The held-out flights flown with these parameters and effects, pooled; `label` names the model in
// the reason it cannot be flown.
StepPrediction PredictHeldOut(const std::string& label, const std::map<std::string, double>& values,
                              const Effects& effects, const std::vector<FlightData>& held_out,
                              const ObservationOptions& observation, const PredictOptions& settings) {
  StepPrediction prediction;
  internal::ErrorSums sums(settings.horizon_steps, false);
  try {
    for (const FlightData& flight : held_out) {
      internal::FlownModel model = internal::FlownModelFromValues(values, effects, flight.vehicle);
      model.source = label;
      sums.Add(internal::ScoreSegments({flight.log}, flight.vehicle, model, observation, settings, nullptr));
    }
  } catch (const Error& e) {
    prediction.unavailable = e.what();
  }
  prediction.curves = sums.Mean();
  if (prediction.unavailable.empty() && prediction.curves.windows == 0)
    prediction.unavailable = "no window of " + std::to_string(settings.horizon_steps) +
                             " steps lies in the held-out flights' " + PredictionScopeName(settings.scope) + " scope";
  return prediction;
}

}  // namespace

std::vector<StepPrediction> PredictDiagnosisSteps(const Diagnosis& diagnosis, const std::vector<FlightData>& training,
                                                  const std::vector<FlightData>& held_out,
                                                  const IdentifyOptions& identify, const PredictOptions& settings) {
  if (held_out.empty() || training.empty()) return {};
  const IdentificationResult linear = Identify(training, identify);
  std::vector<StepPrediction> out;
  out.push_back(PredictHeldOut("the linear model", NamedParameters(linear.system, PredictionChi(linear.solution)),
                               Effects(), held_out, identify.observation, settings));
  RefineOptions refine;
  refine.effects.clear();
  for (const SelectionStep& step : diagnosis.steps) {
    refine.effects.push_back(step.added);
    // A step whose refinement fails costs its prediction, not the diagnosis.
    StepPrediction prediction;
    try {
      const RefineResult refined = Refine(linear, refine);
      std::string label = "the model with";
      for (EffectKind kind : refine.effects) label += std::string(" ") + EffectName(kind);
      prediction = PredictHeldOut(label, NamedParameters(linear.system, PredictionChi(refined.refined)),
                                  refined.effects, held_out, identify.observation, settings);
    } catch (const Error& e) {
      prediction.unavailable = e.what();
    }
    prediction.effects = refine.effects;
    out.push_back(std::move(prediction));
  }
  return out;
}

void AddStepPredictions(const std::vector<StepPrediction>& predictions, nlohmann::json* report) {
  for (size_t k = 0; k < predictions.size(); ++k) {
    const StepPrediction& p = predictions[k];
    nlohmann::json j = {{"windows", p.curves.windows}};
    if (!p.unavailable.empty()) j["unavailable"] = p.unavailable;
    // h = 10 and N, the steps the diagnosis compares (every window scores the rotation).
    const int horizon = static_cast<int>(p.curves.mae[static_cast<int>(PredictionGroup::kRotation)].size());
    std::vector<int> steps = PredictionSummarySteps(horizon);
    steps.erase(std::remove(steps.begin(), steps.end(), 1), steps.end());
    j["mae"] = internal::GroupsAtSteps(p.curves.mae, steps);
    j["naive_mae"] = internal::GroupsAtSteps(p.curves.naive_mae, steps);
    if (k == 0)
      (*report)["baseline"]["prediction"] = j;
    else if (report->contains("steps") && k - 1 < (*report)["steps"].size())
      (*report)["steps"][k - 1]["prediction"] = j;
  }
}

}  // namespace rotorid

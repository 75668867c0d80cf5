#pragma once

// The values a model predicts with, decided in one place for every consumer (the report's tables
// and figures, validate, export, predict): the essential estimates, a discarded inertia at its
// profiled estimate or at the value within the range a physical body allows (PredictionChi,
// INTERFACE.md 5's `predicts_with`), every other discarded parameter at 0; and of a saved report,
// its refined block with the refined effects when it has one, else its linear block.

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "rotorid/ident/tls.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

// By name ("kt", "kd", "<config>.<name>") from a solution over `system`'s parameters.
std::map<std::string, double> PredictedParameters(const IdimLayout& system, const TlsSolution& solution);

// Whether the model predicts with another value than the reported chi[k] (PredictionChi): a
// discarded inertia at its profiled estimate (PredictsWithProfiled) or at a value a body allows
// (PredictsWithinRange). The JSON's `predicts_with`, the console table and the HTML answer mark it.
bool PredictsWithOtherValue(const TlsSolution& solution, int k);

// Named values with what the model predicts with in their place (a diagnosis's `*_predicts_with`).
std::map<std::string, double> PredictedParameters(std::map<std::string, double> values,
                                                  const std::map<std::string, double>& predicts_with);

// The block of a saved identify/refine report a model is taken from: `block` when given, else
// "refined" when the report has refined parameters, else "linear".
std::string PredictedBlock(const nlohmann::json& report, const std::string& block = "");

// A saved report's model: the block (PredictedBlock), the values it predicts with, and the effects
// that go with them (the refined block's; none for the linear one). Throws rotorid::Error naming
// `source` on a malformed report.
struct PredictedModel {
  std::string block;
  std::map<std::string, double> values;
  Effects effects;
};
PredictedModel PredictedParameters(const nlohmann::json& report, const std::string& source,
                                   const std::string& block = "");

}  // namespace rotorid

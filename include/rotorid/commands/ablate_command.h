#pragma once

// `rotorid ablate` (INTERFACE.md 4): the refinement with every subset of the chosen effects, with
// relative errors (identification and held-out flights), parameter counts and information criteria.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
#include "rotorid/refine/ablate.h"

namespace rotorid {

struct AblateCommandOptions {
  CommandInputOptions input;
  IdentifyOptions identify;
  std::string effects = "all";  // an --effects list (EffectsForFlights)
  RefineOptions refine;
  int threads = 2;  // subsets refined in parallel
};

struct AblateCommandResult {
  AblateCommandOptions options;
  LoadedFlights training, validation;
  IdentificationResult linear;
  std::vector<ProcessedFlight> held_out;
  AblationResult ablation;
  std::vector<Check> checks;
};

AblateCommandResult RunAblate(const AblateCommandOptions& options);
nlohmann::json AblateJson(const AblateCommandResult& result);
ReportInput AblateReportInput(const AblateCommandResult& result);
std::string WriteAblateReport(const AblateCommandResult& result);
// The subsets' table: effects, parameter count, BIC, relative errors.
std::string AblateBrief(const AblateCommandResult& result);

}  // namespace rotorid

#pragma once

// `rotorid refine` (INTERFACE.md 4, 5): the TLS, then a Ceres refinement of the same parameters
// jointly with unmodelled effects; both applied to the held-out flights.

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

struct RefineCommandOptions {
  CommandInputOptions input;
  IdentifyOptions identify;
  std::string effects = "all";  // an --effects list (EffectsForFlights); sets refine.effects
  RefineOptions refine;

  // Empty when valid, else what is wrong (a usage error).
  std::string Validate() const;
};

// One parameter set applied to the held-out flights: Table III, and with per-flight first moments
// each held-out flight's own, fitted (empty otherwise).
struct HeldOutFit {
  std::map<std::string, double> values;  // what the model predicts with, first moments included
  std::map<std::string, double> first_moments;
  std::vector<std::optional<double>> relative_error_pct;
};

struct RefineCommandResult {
  RefineCommandOptions options;  // options.refine.effects: those refined
  LoadedFlights training, validation;
  IdentificationResult linear;
  RefineResult refined;
  std::vector<ProcessedFlight> held_out;
  HeldOutFit held_out_linear, held_out_refined;  // values only, without held-out flights
  std::vector<Check> checks;
  std::vector<std::string> warnings;  // the linear step's, then the refinement's
};

RefineCommandResult RunRefine(const RefineCommandOptions& options);
nlohmann::json RefineJson(const RefineCommandResult& result);
ReportInput RefineReportInput(const RefineCommandResult& result);
std::string WriteRefineReport(const RefineCommandResult& result);
// Linear and refined side by side, the effects, Table III (identification and held-out flights).
std::string RefineBrief(const RefineCommandResult& result);

}  // namespace rotorid

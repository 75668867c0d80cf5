#pragma once

// `rotorid validate` (INTERFACE.md 4, 5): a saved identify/refine report's model applied to other
// flights, the paper's Table III; with per-flight first moments, each flight's own is fitted.

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
#include "rotorid/report/predicted_parameters.h"

namespace rotorid {

struct ValidateCommandOptions {
  CommandInputOptions input;
  std::string params_path;  // the identify or refine report
  std::string block;        // "linear", "refined" or "" (PredictedBlock)
};

struct ValidateCommandResult {
  ValidateCommandOptions options;
  LoadedFlights loaded;
  nlohmann::json params;                        // the saved report
  ObservationOptions observation;               // the report's: rows built exactly as in its run
  PredictedModel model;                         // what it predicts with, the flights' fitted first moments included
  std::map<std::string, double> first_moments;  // fitted on these flights (per-flight reports)
  std::vector<ProcessedFlight> flights;
  std::vector<FlightFit> fits;                            // per flight, Table III with the model's effects
  std::vector<std::optional<double>> relative_error_pct;  // over all flights
  std::vector<Check> checks;
};

ValidateCommandResult RunValidate(const ValidateCommandOptions& options);
nlohmann::json ValidateJson(const ValidateCommandResult& result);
ReportInput ValidateReportInput(const ValidateCommandResult& result);
std::string WriteValidateReport(const ValidateCommandResult& result);
std::string ValidateBrief(const ValidateCommandResult& result);

}  // namespace rotorid

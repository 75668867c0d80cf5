#pragma once

// `rotorid diagnose` (INTERFACE.md 4, 5): where the model's residual lies, which unmodelled effect
// causes it (judged on held-out data), how far the held-out gap shrinks once it is added, and how
// each step's model predicts the held-out flights.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/predict/diagnosis_prediction.h"

namespace rotorid {

struct DiagnoseCommandOptions {
  CommandInputOptions input;
  DiagnosisOptions diagnosis;   // its candidates are set from `effects`
  std::string effects = "all";  // "all" (DiagnosisCandidates), or an effect list

  // The diagnosis options with the candidates `effects` names; throws rotorid::Error on an unknown
  // effect.
  DiagnosisOptions Resolved() const;
  // Empty when valid, else what is wrong (a usage error).
  std::string Validate() const;
};

struct DiagnoseCommandResult {
  DiagnoseCommandOptions options;  // options.diagnosis resolved
  LoadedFlights training, validation;
  std::vector<ProcessedFlight> flights, held_out;
  Diagnosis diagnosis;
  std::vector<StepPrediction> step_predictions;  // empty without held-out flights
  std::vector<Check> checks;
};

DiagnoseCommandResult RunDiagnose(const DiagnoseCommandOptions& options);
nlohmann::json DiagnoseJson(const DiagnoseCommandResult& result);
ReportInput DiagnoseReportInput(const DiagnoseCommandResult& result);
std::string WriteDiagnoseReport(const DiagnoseCommandResult& result);
// The candidates and time, then the verdict (DiagnosisVerdict).
std::string DiagnoseBrief(const DiagnoseCommandResult& result);

}  // namespace rotorid

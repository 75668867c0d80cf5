#include "rotorid/commands/diagnose_command.h"

#include <memory>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/diagnosis/diagnosis_checks.h"
#include "rotorid/diagnosis/diagnosis_json.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"
#include "rotorid/report/progress.h"

namespace rotorid {

namespace {

nlohmann::json DiagnoseSettingsJson(const DiagnosisOptions& diagnosis) {
  return {{"observation", ObservationOptionsJson(diagnosis.identify.observation)},
          {"tls", TlsOptionsJson(diagnosis.identify.tls)},
          {"diagnosis", DiagnosisOptionsJson(diagnosis)}};
}

}  // namespace

DiagnosisOptions DiagnoseCommandOptions::Resolved() const {
  DiagnosisOptions resolved = diagnosis;
  resolved.candidates = effects == "all" ? DiagnosisCandidates() : ParseEffectList(effects);
  return resolved;
}

std::string DiagnoseCommandOptions::Validate() const {
  try {
    if (std::string problem = Resolved().Validate(); !problem.empty()) return problem;
  } catch (const Error& e) {
    return e.what();
  }
  return input.Validate();
}

DiagnoseCommandResult RunDiagnose(const DiagnoseCommandOptions& options) {
  DiagnoseCommandResult result;
  result.options = options;
  const DiagnosisOptions diagnosis = result.options.diagnosis = options.Resolved();
  const ObservationOptions& observation = diagnosis.identify.observation;
  result.training = LoadFlights(options.input.training, options.input);
  result.validation = LoadFlights(options.input.held_out, options.input);
  result.flights = ProcessFlights(result.training.flights, observation);
  result.checks = CheckFlights(result.training.flights, result.flights);
  if (!result.validation.flights.empty()) result.held_out = ProcessFlights(result.validation.flights, observation);

  // One progress line per batch of fold refinements, each with its total and an ETA.
  std::unique_ptr<Progress> progress;
  std::string batch;
  auto on_progress = [&](const std::string& label, int done, int total) {
    if (!progress || label != batch || done == 0) {
      batch = label;
      progress = std::make_unique<Progress>("diagnose: " + label, total, options.input.quiet);
      progress->StartTicking();
    }
    progress->Update(done);
  };
  try {
    result.diagnosis = Diagnose(result.flights, result.held_out, diagnosis, on_progress);
  } catch (const Error& e) {
    if (!AnyCheckFailed(result.checks)) throw;
    throw Error(std::string(e.what()) + "; likely cause: " + FailedCheckMessages(result.checks));
  }
  progress.reset();
  for (Check& c :
       CheckDiagnosis(result.diagnosis, ConfigurationNames(result.flights), ConfigurationMasses(result.flights)))
    result.checks.push_back(std::move(c));
  result.step_predictions =
      PredictDiagnosisSteps(result.diagnosis, result.training.flights, result.validation.flights, diagnosis.identify);
  return result;
}

nlohmann::json DiagnoseJson(const DiagnoseCommandResult& result) {
  nlohmann::json report = DiagnosisJson(result.diagnosis);
  AddStepPredictions(result.step_predictions, &report);
  report.update(CommandJsonHead("diagnose", DiagnoseSettingsJson(result.options.diagnosis)));
  report["checks"] = ChecksJson(result.checks);
  AddCommonReportSections(result.options.input, result.training, &result.validation, &report);
  return report;
}

ReportInput DiagnoseReportInput(const DiagnoseCommandResult& result) {
  const Diagnosis& d = result.diagnosis;
  const DiagnosisOptions& diagnosis = result.options.diagnosis;
  ReportInput input = CommandReportInput("diagnose", diagnosis.identify.observation, result.training,
                                         &result.validation, DiagnoseSettingsJson(diagnosis));
  input.diagnosis = &d;
  input.checks = result.checks;
  input.flights = ReportFlights(result.flights, result.held_out);
  input.parameter_sets = {{"linear", PredictedParameters(d.linear_parameters, d.linear_predicts_with), Effects()}};
  if (!d.final_model.empty())
    input.parameter_sets.push_back(
        {"with selected effects", PredictedParameters(d.final_parameters, d.final_predicts_with), d.final_effects});
  return input;
}

std::string WriteDiagnoseReport(const DiagnoseCommandResult& result) {
  return WriteCommandReport(result.options.input, DiagnoseReportInput(result));
}

std::string DiagnoseBrief(const DiagnoseCommandResult& result) {
  const Diagnosis& d = result.diagnosis;
  std::ostringstream out;
  out << "rotorid diagnose: " << TlsMethodName(result.options.diagnosis.identify.tls.method) << " TLS, candidates "
      << result.options.effects << "; " << d.refinements << " refinements in " << d.seconds << " s\n";
  out << DiagnosisVerdict(d);
  return out.str();
}

}  // namespace rotorid

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/diagnosis/diagnosis_checks.h"
#include "rotorid/diagnosis/diagnosis_json.h"
#include "rotorid/predict/diagnosis_prediction.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"
#include "rotorid/report/progress.h"

namespace rotorid::cli {

Command AddDiagnoseCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
    std::string effects = "all";
    DiagnosisOptions diagnosis;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "diagnose",
      "the sim-to-real gap: where the model's residual lies (component, frequency band, stretch of the "
      "flight), which unmodelled effect causes it (judged on held-out data) and how far the held-out gap "
      "shrinks once it is added");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/true);
  AddIdentifyOptions(command.app, &options->identify);
  DiagnosisOptions& d = options->diagnosis;
  std::string names;
  for (EffectKind kind : AllEffects()) names += (names.empty() ? "" : ",") + kind->name();
  std::string in_all;
  for (EffectKind kind : DiagnosisCandidates()) in_all += (in_all.empty() ? "" : ",") + kind->name();
  command.app
      ->add_option("--effects", options->effects,
                   "candidate effects: all (" + in_all + "), every (all " + std::to_string(AllEffects().size()) +
                       " registered effects) or a list of " + names)
      ->capture_default_str();
  command.app->add_option("--folds", d.folds, "time-blocked held-out folds per flight (without --validate-log)")
      ->capture_default_str();
  command.app->add_option("--guard-s", d.guard_s, "seconds left out of the training data around a held-out block")
      ->capture_default_str();
  command.app->add_option("--alpha", d.alpha, "level of the F-test of each added effect")->capture_default_str();
  command.app
      ->add_option("--min-shrink", d.min_shrink_pct, "held-out gap reduction (%) an effect must exceed to be kept")
      ->capture_default_str();
  command.app->add_option("--max-effects", d.max_effects, "most effects the forward selection keeps")
      ->capture_default_str();
  command.app->add_option("--window-s", d.location.window_s, "length of the stretches of the flight (s)")
      ->capture_default_str();
  command.app->add_option("--threads", d.num_threads, "refinements run in parallel")->capture_default_str();
  command.run = [options, app = command.app]() {
    DiagnosisOptions diagnosis = options->diagnosis;
    diagnosis.identify = ResolveIdentifyOptions(&options->identify);
    diagnosis.candidates = options->effects == "all" ? DiagnosisCandidates() : ParseEffectList(options->effects);
    if (const std::string problem = diagnosis.Validate(); !problem.empty()) throw Error(problem);
    const FlightSourceOptions source = SourceOptions(options->identify);
    const LoadedFlights training = LoadTrainingFlights(options->flights, source);
    const LoadedFlights validation = LoadValidationFlights(options->flights, source);
    const std::vector<ProcessedFlight> flights = ProcessFlights(training.flights, diagnosis.identify.observation);
    std::vector<Check> checks = CheckFlights(training.flights, flights);
    std::vector<ProcessedFlight> held_out;
    if (!validation.flights.empty()) held_out = ProcessFlights(validation.flights, diagnosis.identify.observation);

    // One progress line per batch of fold refinements, each with its total and an ETA.
    std::unique_ptr<Progress> progress;
    std::string batch;
    auto on_progress = [&](const std::string& label, int done, int total) {
      if (!progress || label != batch || done == 0) {
        batch = label;
        progress = std::make_unique<Progress>("diagnose: " + label, total, options->flights.quiet);
        progress->StartTicking();
      }
      progress->Update(done);
    };
    Diagnosis result;
    try {
      result = Diagnose(flights, held_out, diagnosis, on_progress);
    } catch (const Error& e) {
      if (!AnyCheckFailed(checks)) throw;
      throw Error(std::string(e.what()) + "; likely cause: " + FailedCheckMessages(checks));
    }
    progress.reset();
    for (Check& c : CheckDiagnosis(result, ConfigurationNames(flights), ConfigurationMasses(flights)))
      checks.push_back(std::move(c));

    const nlohmann::json settings = {{"observation", ObservationOptionsJson(diagnosis.identify.observation)},
                                     {"tls", TlsOptionsJson(diagnosis.identify.tls)},
                                     {"diagnosis", DiagnosisOptionsJson(diagnosis)}};
    nlohmann::json report = DiagnosisJson(result);
    AddStepPredictions(PredictDiagnosisSteps(result, training.flights, validation.flights, diagnosis.identify),
                       &report);
    report["rotorid_version"] = kRotoridVersion;
    report["command"] = "diagnose";
    report["settings"] = settings;
    report["checks"] = ChecksJson(checks);
    AddCommonReportSections(*app, training, &validation, &report);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, report);
    ReportInput input = CommandReportInput("diagnose", diagnosis.identify.observation, training, &validation, settings);
    input.diagnosis = &result;
    input.checks = checks;
    input.flights = ReportFlights(flights, /*held_out=*/false);
    for (const ReportFlight& f : ReportFlights(held_out, /*held_out=*/true)) input.flights.push_back(f);
    input.parameter_sets = {{"linear", result.linear_parameters, Effects()}};
    if (!result.final_model.empty())
      input.parameter_sets.push_back({"with selected effects", result.final_parameters, result.final_effects});
    const std::string report_path = WriteCommandReport(options->flights, input);
    if (!options->flights.quiet) {
      std::cout << "rotorid diagnose: " << TlsMethodName(diagnosis.identify.tls.method) << " TLS, candidates "
                << options->effects << "; " << result.refinements << " refinements in " << result.seconds << " s\n";
      std::cout << DiagnosisVerdict(result);
      PrintWarnings(result.warnings);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/diagnose_command.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddDiagnoseCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
    DiagnoseCommandOptions diagnose;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "diagnose",
      "the sim-to-real gap: where the model's residual lies (component, frequency band, stretch of the "
      "flight), which unmodelled effect causes it (judged on held-out data) and how far the held-out gap "
      "shrinks once it is added");
  CLI::App* app = command.app;
  AddFlightOptions(app, &options->flights, /*held_out=*/true);
  AddIdentifyOptions(app, &options->identify);
  DiagnosisOptions& d = options->diagnose.diagnosis;
  app->add_option("--effects", options->diagnose.effects,
                  "candidate effects: all (" + EffectListText(DiagnosisCandidates()) + "), every (all " +
                      std::to_string(AllEffects().size()) + " registered effects) or a list of " +
                      EffectListText(AllEffects()))
      ->capture_default_str();
  app->add_option("--folds", d.folds, "time-blocked held-out folds per flight (without --validate-log)")
      ->capture_default_str();
  app->add_option("--guard-s", d.guard_s, "seconds left out of the training data around a held-out block")
      ->capture_default_str();
  app->add_option("--alpha", d.alpha, "level of the F-test of each added effect")->capture_default_str();
  app->add_option("--min-shrink", d.min_shrink_pct, "held-out gap reduction (%) an effect must exceed to be kept")
      ->capture_default_str();
  app->add_option("--max-effects", d.max_effects, "most effects the forward selection keeps")->capture_default_str();
  app->add_option("--window-s", d.location.window_s, "length of the stretches of the flight (s)")
      ->capture_default_str();
  app->add_option("--threads", d.num_threads, "refinements run in parallel")->capture_default_str();
  command.run = [options, app]() {
    DiagnoseCommandOptions diagnose = options->diagnose;
    diagnose.diagnosis.identify = ResolveIdentifyOptions(&options->identify);
    diagnose.input = ResolveCommandInput(*app, options->flights, SourceOptions(options->identify));
    if (const std::string problem = diagnose.Validate(); !problem.empty()) throw UsageError(problem);
    MarkOptionsValidated();
    const DiagnoseCommandResult result = RunDiagnose(diagnose);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, DiagnoseJson(result));
    const std::string report_path = WriteDiagnoseReport(result);
    if (!options->flights.quiet) {
      std::cout << DiagnoseBrief(result);
      PrintWarnings(result.diagnosis.warnings);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(result.checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

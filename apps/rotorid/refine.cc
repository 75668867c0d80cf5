#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/refine_command.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddRefineCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
    std::vector<std::string> initial;
    RefineCommandOptions refine;
  };
  auto options = std::make_shared<Options>();
  RefineOptions& r = options->refine.refine;
  r.num_threads = 2;  // as delay and diagnose: the Ceres evaluations and the delay grid on 2 cores
  Command command;
  command.app = root.add_subcommand(
      "refine",
      "TLS, then a Ceres refinement of the same parameters jointly with unmodelled effects; linear and "
      "refined results side by side");
  CLI::App* app = command.app;
  AddFlightOptions(app, &options->flights, /*held_out=*/true);
  AddIdentifyOptions(app, &options->identify);
  AddFirstMomentOption(app, &options->identify);
  app->add_option("--effects", options->refine.effects,
                  "effects to estimate: all (the default candidates), every (all registered effects), none, or a list "
                  "of effect names (rotorid diagnose --help lists them)")
      ->capture_default_str();
  app->add_option("--init", options->initial, "initial value of an effect parameter, e.g. delay_s=0.01");
  app->add_option("--robust-loss", r.robust_loss, "none, huber or cauchy")->capture_default_str();
  app->add_option("--criterion", r.criterion,
                  "anchored: moment rows divided by the rotor-signal effects' gain on the rotor moment, so that a lag "
                  "cannot win by attenuating it (MODEL.md 9); tls: the TLS criterion itself")
      ->check(CLI::IsMember({"anchored", "tls"}))
      ->capture_default_str();
  app->add_option("--robust-scale", r.robust_scale, "scale of the robust loss (whitened units)")->capture_default_str();
  app->add_flag("!--no-delay-search", r.coarse_delay_search, "start the delay at --init instead of a global search");
  app->add_flag("!--keep-discarded", r.reselect_essential,
                "keep the linear step's discarded parameters at zero (no re-selection on corrected rows)");
  app->add_option("--max-iterations", r.max_iterations)->capture_default_str();
  app->add_option("--threads", r.num_threads)->capture_default_str();
  command.run = [options, app]() {
    RefineCommandOptions refine = options->refine;
    refine.identify = ResolveIdentifyOptions(&options->identify);
    for (const std::string& assignment : options->initial) refine.refine.initial.Assign(assignment);
    refine.input = ResolveCommandInput(*app, options->flights, SourceOptions(options->identify));
    if (const std::string problem = refine.Validate(); !problem.empty()) throw UsageError(problem);
    MarkOptionsValidated();
    const RefineCommandResult result = RunRefine(refine);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, RefineJson(result));
    WriteRefineReport(result);
    if (!options->flights.quiet) {
      std::cout << RefineBrief(result);
      if (options->flights.verbose) std::cout << result.refined.solver.full_report << "\n";
      PrintWarnings(result.warnings);
    }
    return PrintChecks(result.checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

#include "rotorid/refine/refine.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/refine/refine.h"
#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"
#include "rotorid/report/progress.h"
#include "rotorid/report/refine_json.h"

namespace rotorid::cli {

namespace {

void PrintSideBySide(const IdentificationResult& linear, const RefineResult& refined) {
  const TlsSolution& a = linear.solution;
  const TlsSolution& b = refined.refined;
  size_t width = 10;
  for (const std::string& n : linear.system.parameter_names) width = std::max(width, n.size() + 2);
  std::cout << std::left << std::setw(static_cast<int>(width)) << "parameter" << std::right << std::setw(13) << "linear"
            << std::setw(10) << "std" << std::setw(13) << "refined" << std::setw(10) << "std" << std::setw(10)
            << "change/std"
            << "\n";
  // Each block's own essential flag, as in the JSON: a parameter one block discarded shows "discarded"
  // in that block's std column, and the change is shown where both estimated it.
  const auto value_and_std = [](const TlsSolution& s, int k) {
    std::cout << std::scientific << std::setprecision(4) << std::setw(13) << s.chi[k] << std::setprecision(1)
              << std::setw(10);
    if (s.essential[k])
      std::cout << s.std[k];
    else
      std::cout << "discarded";
  };
  for (int k = 0; k < linear.system.num_parameters(); ++k) {
    std::cout << std::left << std::setw(static_cast<int>(width)) << linear.system.parameter_names[k] << std::right;
    value_and_std(a, k);
    value_and_std(b, k);
    if (a.essential[k] && b.essential[k] && a.std[k] > 0)
      std::cout << std::fixed << std::setprecision(2) << std::setw(10) << (b.chi[k] - a.chi[k]) / a.std[k];
    else
      std::cout << std::setw(10) << "-";
    std::cout << "\n";
  }
  std::cout.unsetf(std::ios::floatfield);
}

void PrintEffects(const RefineResult& refined) {
  std::cout << "effects (value +- std):\n";
  for (EffectKind kind : AllEffects()) {
    const bool on = std::find(refined.enabled.begin(), refined.enabled.end(), kind) != refined.enabled.end();
    std::cout << "  " << std::left << std::setw(27) << EffectParameterName(kind) << std::right << " "
              << (on ? kind->Format(refined.effects.Get(kind), refined.effects_std.Get(kind)) : "off") << "\n";
  }
}

}  // namespace

Command AddRefineCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
    std::string effects = "all";
    std::vector<std::string> initial;
    RefineOptions refine;
  };
  auto options = std::make_shared<Options>();
  options->refine.num_threads = 2;  // as delay and diagnose: the Ceres evaluations and the delay grid on 2 cores
  Command command;
  command.app = root.add_subcommand(
      "refine",
      "TLS, then a Ceres refinement of the same parameters jointly with unmodelled effects; linear and "
      "refined results side by side");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/true);
  AddIdentifyOptions(command.app, &options->identify);
  AddFirstMomentOption(command.app, &options->identify);
  command.app
      ->add_option("--effects", options->effects,
                   "effects to estimate: all (the default candidates), every (all registered effects), none, or a list "
                   "of effect names (rotorid diagnose --help lists them)")
      ->capture_default_str();
  command.app->add_option("--init", options->initial, "initial value of an effect parameter, e.g. delay_s=0.01");
  command.app->add_option("--robust-loss", options->refine.robust_loss, "none, huber or cauchy")->capture_default_str();
  command.app
      ->add_option("--criterion", options->refine.criterion,
                   "anchored: moment rows divided by the rotor-signal effects' gain on the rotor moment, so that a lag "
                   "cannot win by attenuating it (MODEL.md 9); tls: the TLS criterion itself")
      ->check(CLI::IsMember({"anchored", "tls"}))
      ->capture_default_str();
  command.app->add_option("--robust-scale", options->refine.robust_scale, "scale of the robust loss (whitened units)")
      ->capture_default_str();
  command.app->add_flag("!--no-delay-search", options->refine.coarse_delay_search,
                        "start the delay at --init instead of a global search");
  command.app->add_flag("!--keep-discarded", options->refine.reselect_essential,
                        "keep the linear step's discarded parameters at zero (no re-selection on corrected rows)");
  command.app->add_option("--max-iterations", options->refine.max_iterations)->capture_default_str();
  command.app->add_option("--threads", options->refine.num_threads)->capture_default_str();
  command.run = [options, app = command.app]() {
    const IdentifyOptions identify = ResolveIdentifyOptions(&options->identify);
    RefineOptions refine = options->refine;
    refine.effects = ParseEffectList(options->effects);
    for (const std::string& assignment : options->initial) refine.initial.Assign(assignment);
    if (const std::string problem = refine.Validate(); !problem.empty()) throw Error(problem);
    const FlightSourceOptions source = SourceOptions(options->identify);
    LoadedFlights training = LoadTrainingFlights(options->flights, source);
    const LoadedFlights validation = LoadValidationFlights(options->flights, source);
    std::vector<Check> checks;
    IdentificationResult linear = IdentifyWithChecks(std::move(training.flights), identify, &checks);
    linear.system.w = Eigen::MatrixXd();  // the refinements rebuild rows with effects: 100 MB less on a 1 h log
    refine.effects = EffectsForFlights(options->effects, linear, options->flights.quiet);
    Progress progress("refine: delay search and Ceres passes", RefineSteps(refine), options->flights.quiet);
    progress.StartTicking();
    const RefineResult refined = Refine(linear, refine, [&progress](int done, int) { progress.Update(done); });
    progress.Finish();
    for (Check& c : CheckRefinement(linear, refined)) checks.push_back(std::move(c));
    ExcuseLinearErrorsTheRefinementExplains(linear, refined, &checks);
    for (Check& c : CheckTimingAtHalfCutoff(linear, identify, refined, refine)) checks.push_back(std::move(c));

    const nlohmann::json settings = {{"observation", ObservationOptionsJson(identify.observation)},
                                     {"tls", TlsOptionsJson(identify.tls)},
                                     {"first_moment", FirstMomentName(identify.first_moment)},
                                     {"refine", RefineOptionsJson(refine)}};
    nlohmann::json report = {{"rotorid_version", kRotoridVersion},
                             {"command", "refine"},
                             {"settings", settings},
                             {"linear", LinearJson(linear)},
                             {"refined", RefinedJson(linear, refined)}};
    std::vector<std::optional<double>> held_out_linear, held_out_refined;
    std::vector<ProcessedFlight> held_out;
    std::map<std::string, double> linear_values = NamedParameters(linear.system, PredictionChi(linear.solution));
    std::map<std::string, double> refined_values = NamedParameters(linear.system, PredictionChi(refined.refined));
    if (!options->flights.validate_log_paths.empty()) {
      held_out = ProcessFlights(validation.flights, identify.observation);
      // Per-flight first moments: each held-out flight's is fitted, for either parameter set.
      const nlohmann::json linear_moments = FitHeldOutFirstMomentsJson(&held_out, &linear_values, Effects{});
      held_out_linear = CombinedRelativeErrorPct(held_out, linear_values);
      const nlohmann::json refined_moments = FitHeldOutFirstMomentsJson(&held_out, &refined_values, refined.effects);
      held_out_refined = RelativeErrorWithEffects(held_out, refined_values, refined.effects);
      for (Check& c : CheckRelativeError(held_out_refined, "held-out refined", /*held_out=*/true))
        checks.push_back(std::move(c));
      report["held_out"] = {{"linear", {{"relative_error_pct", ComponentsJson(held_out_linear)}}},
                            {"refined", {{"relative_error_pct", ComponentsJson(held_out_refined)}}}};
      if (!linear_moments.empty()) {
        report["held_out"]["linear"]["first_moments"] = linear_moments;
        report["held_out"]["refined"]["first_moments"] = refined_moments;
      }
    }
    report["checks"] = ChecksJson(checks);
    AddCommonReportSections(*app, training, &validation, &report);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, report);
    ReportInput input = CommandReportInput("refine", identify.observation, training, &validation, settings);
    input.linear = &linear;
    input.refined = &refined;
    if (!options->flights.validate_log_paths.empty())
      input.relative_errors = {{"held-out flights", "linear", held_out_linear},
                               {"held-out flights", "refined", held_out_refined}};
    input.checks = checks;
    input.flights = ReportFlights(linear.flights, /*held_out=*/false);
    for (const ReportFlight& f : ReportFlights(held_out, /*held_out=*/true)) input.flights.push_back(f);
    input.parameter_sets = {{"linear", linear_values, Effects()}, {"refined", refined_values, refined.effects}};
    WriteCommandReport(options->flights, input);
    if (!options->flights.quiet) {
      std::cout << "rotorid refine: " << TlsMethodName(identify.tls.method) << " TLS, then Ceres with effects "
                << (options->effects.empty() ? "none" : options->effects) << " (" << refined.solver.iterations
                << " iterations, " << refined.solver.termination << ")\n";
      PrintSideBySide(linear, refined);
      PrintEffects(refined);
      std::cout << "relative error, identification flights: linear " << FormatComponents(linear.relative_error_pct)
                << "\n                                      refined " << FormatComponents(refined.relative_error_pct)
                << "\n";
      if (!held_out_linear.empty())
        std::cout << "relative error, held-out flights:       linear " << FormatComponents(held_out_linear)
                  << "\n                                      refined " << FormatComponents(held_out_refined) << "\n";
      if (options->flights.verbose) std::cout << refined.solver.full_report << "\n";
      PrintWarnings(linear.warnings);
      PrintWarnings(refined.warnings);
    }
    return PrintChecks(checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

#include "rotorid/refine/ablate.h"

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/refine/ablate.h"
#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"
#include "rotorid/report/progress.h"
#include "rotorid/report/refine_json.h"

namespace rotorid::cli {

namespace {

std::string SubsetName(const std::vector<EffectKind>& effects) {
  if (effects.empty()) return "(none)";
  std::string name;
  for (EffectKind k : effects) name += (name.empty() ? "" : "+") + std::string(EffectName(k));
  return name;
}

// The report's parameter table: the linear result and the subset with the lowest BIC.
std::vector<ParameterSet> AblationParameterSets(const IdentificationResult& linear, const AblationResult& ablation) {
  std::vector<ParameterSet> sets = {{"linear", NamedParameters(linear.system, linear.solution.chi), Effects()}};
  const auto best = std::min_element(ablation.entries.begin(), ablation.entries.end(),
                                     [](const AblationEntry& a, const AblationEntry& b) { return a.bic < b.bic; });
  if (best != ablation.entries.end())
    sets.push_back({"lowest BIC: " + SubsetName(best->effects),
                    NamedParameters(linear.system, best->result.refined.chi), best->result.effects});
  return sets;
}

}  // namespace

Command AddAblateCommand(CLI::App& root) {
  struct Options {
    FlightOptions flights;
    IdentifyCliOptions identify;
    std::string effects = "all";
    RefineOptions refine;
    int threads = 2;
  };
  auto options = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand(
      "ablate", "refines with every subset of the chosen effects and tabulates relative errors (identification and "
                "held-out flights), parameter counts, information criteria and key parameters");
  AddFlightOptions(command.app, &options->flights, /*held_out=*/true);
  AddIdentifyOptions(command.app, &options->identify);
  command.app->add_option("--effects", options->effects, "effects to combine (default all: 2^n subsets of the default effects the flights can carry)")
      ->capture_default_str();
  command.app->add_option("--threads", options->threads, "subsets refined in parallel")->capture_default_str();
  command.run = [options, app = command.app]() {
    const IdentifyOptions identify = ResolveIdentifyOptions(&options->identify);
    const FlightSourceOptions source = SourceOptions(options->identify);
    LoadedFlights training = LoadTrainingFlights(options->flights, source);
    const LoadedFlights validation = LoadValidationFlights(options->flights, source);
    std::vector<Check> checks;
    IdentificationResult linear = IdentifyWithChecks(std::move(training.flights), identify, &checks);
    linear.system.w = Eigen::MatrixXd();  // the refinements rebuild rows with effects: 100 MB less on a 1 h log
    const std::vector<EffectKind> effects = EffectsForFlights(options->effects, linear, options->flights.quiet);
    std::vector<ProcessedFlight> held_out;
    if (!validation.flights.empty()) held_out = ProcessFlights(validation.flights, identify.observation);
    Progress progress("ablate", int64_t{1} << effects.size(), options->flights.quiet);
    const AblationResult ablation = Ablate(linear, held_out, effects, options->refine, options->threads,
                                           [&progress](int done, int) { progress.Update(done); });
    progress.Finish();

    // Each subset's failed checks (the passing ones would repeat for every subset).
    for (const AblationEntry& e : ablation.entries)
      for (Check& c : CheckRefinement(linear, e.result, SubsetName(e.effects), CheckStatus::kWarning))
        if (c.status != CheckStatus::kOk) checks.push_back(std::move(c));
    const nlohmann::json settings = {{"observation", ObservationOptionsJson(identify.observation)},
                                     {"tls", TlsOptionsJson(identify.tls)}};
    nlohmann::json report = {{"rotorid_version", kRotoridVersion},
                             {"command", "ablate"},
                             {"settings", settings},
                             {"effective_samples", ablation.effective_samples},
                             {"linear", LinearJson(linear)},
                             {"ablation", AblationJson(ablation)},
                             {"checks", ChecksJson(checks)}};
    AddCommonReportSections(*app, training, &validation, &report);
    if (!options->flights.json_path.empty()) WriteJsonFile(options->flights.json_path, report);
    ReportInput input = CommandReportInput("ablate", identify.observation, training, &validation, settings);
    input.linear = &linear;
    input.ablation = &ablation;
    input.checks = checks;
    input.flights = ReportFlights(linear.flights, false);
    input.parameter_sets = AblationParameterSets(linear, ablation);
    const std::string report_path = WriteCommandReport(options->flights, input);
    if (!options->flights.quiet) {
      std::cout << "rotorid ablate: " << ablation.entries.size() << " subsets of " << options->effects << "\n";
      std::cout << std::left << std::setw(46) << "effects" << std::right << std::setw(4) << "k" << std::setw(11)
                << "BIC" << "  relative error (identification" << (held_out.empty() ? "" : " | held-out") << ")\n";
      for (const AblationEntry& e : ablation.entries) {
        std::cout << std::left << std::setw(46) << SubsetName(e.effects) << std::right << std::setw(4)
                  << e.num_parameters << std::fixed << std::setprecision(1) << std::setw(11) << e.bic << "  "
                  << FormatComponents(e.relative_error_pct);
        if (!held_out.empty()) std::cout << " | " << FormatComponents(e.held_out_relative_error_pct);
        std::cout << "\n";
      }
      std::cout.unsetf(std::ios::floatfield);
      if (!report_path.empty()) std::cout << "report: " << report_path << "\n";
    }
    return PrintChecks(checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/refine/ablate.h"
#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/refine_json.h"

namespace rotorid::cli {

namespace {

std::string SubsetName(const std::vector<EffectKind>& effects) {
  if (effects.empty()) return "(none)";
  std::string name;
  for (EffectKind k : effects) name += (name.empty() ? "" : "+") + std::string(EffectName(k));
  return name;
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
  command.app->add_option("--effects", options->effects, "effects to combine (default all five: 32 subsets)")
      ->capture_default_str();
  command.app->add_option("--threads", options->threads, "subsets refined in parallel")->capture_default_str();
  command.run = [options]() {
    const IdentifyOptions identify = ResolveIdentifyOptions(&options->identify);
    const std::vector<EffectKind> effects = ParseEffectList(options->effects);
    const FlightSourceOptions source = SourceOptions(options->identify);
    std::vector<Check> checks;
    const IdentificationResult linear =
        IdentifyWithChecks(LoadTrainingFlights(options->flights, source), identify, &checks);
    std::vector<ProcessedFlight> held_out;
    if (!options->flights.validate_log_paths.empty())
      held_out = ProcessFlights(LoadValidationFlights(options->flights, source), identify.observation);
    const AblationResult ablation = Ablate(linear, held_out, effects, options->refine, options->threads);

    nlohmann::json rows = nlohmann::json::array();
    for (const AblationEntry& e : ablation.entries) {
      nlohmann::json names = nlohmann::json::array();
      for (EffectKind k : e.effects) names.push_back(EffectName(k));
      nlohmann::json row = {{"effects", names},
                            {"num_parameters", e.num_parameters},
                            {"aic", e.aic},
                            {"bic", e.bic},
                            {"criterion", e.result.refined_criterion},
                            {"relative_error_pct", ComponentsJson(e.relative_error_pct)},
                            {"kt", e.result.refined.chi[0]},
                            {"kd", e.result.refined.chi[1]},
                            {"effects_values", EffectsJson(e.result.effects, e.result.effects_std, e.effects)}};
      if (!held_out.empty()) row["held_out_relative_error_pct"] = ComponentsJson(e.held_out_relative_error_pct);
      rows.push_back(row);
      // Each subset's failed checks (the passing ones would repeat for every subset).
      for (Check& c : CheckRefinement(linear, e.result, options->refine, SubsetName(e.effects)))
        if (c.status != CheckStatus::kOk) checks.push_back(std::move(c));
    }
    if (!options->flights.json_path.empty()) {
      WriteJsonFile(options->flights.json_path, {{"rotorid_version", kRotoridVersion},
                                                 {"command", "ablate"},
                                                 {"settings", {{"observation", ObservationOptionsJson(identify.observation)},
                                                               {"tls", TlsOptionsJson(identify.tls)}}},
                                                 {"effective_samples", ablation.effective_samples},
                                                 {"linear", LinearJson(linear)},
                                                 {"ablation", rows},
                                                 {"checks", ChecksJson(checks)}});
    }
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
    }
    return PrintChecks(checks, options->flights.quiet);
  };
  return command;
}

}  // namespace rotorid::cli

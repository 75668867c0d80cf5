#include "rotorid/commands/ablate_command.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"
#include "rotorid/report/progress.h"
#include "rotorid/report/refine_json.h"

namespace rotorid {

namespace {

std::string SubsetName(const std::vector<EffectKind>& effects) {
  if (effects.empty()) return "(none)";
  std::string name;
  for (EffectKind k : effects) name += (name.empty() ? "" : "+") + std::string(EffectName(k));
  return name;
}

nlohmann::json AblateSettingsJson(const AblateCommandOptions& options) {
  return {{"observation", ObservationOptionsJson(options.identify.observation)},
          {"tls", TlsOptionsJson(options.identify.tls)}};
}

}  // namespace

AblateCommandResult RunAblate(const AblateCommandOptions& options) {
  AblateCommandResult result;
  result.options = options;
  result.training = LoadFlights(options.input.training, options.input);
  result.validation = LoadFlights(options.input.held_out, options.input);
  result.linear = IdentifyWithChecks(std::move(result.training.flights), options.identify, &result.checks);
  result.linear.system.w = Eigen::MatrixXd();  // the refinements rebuild rows with effects: 100 MB less on a 1 h log
  const std::vector<EffectKind> effects = EffectsForFlights(options.effects, result.linear, options.input);
  if (!result.validation.flights.empty())
    result.held_out = ProcessFlights(result.validation.flights, options.identify.observation);
  Progress progress("ablate", int64_t{1} << effects.size(), options.input.quiet);
  result.ablation = Ablate(result.linear, result.held_out, effects, options.refine, options.threads,
                           [&progress](int done, int) { progress.Update(done); });
  progress.Finish();
  // Each subset's failed checks (the passing ones would repeat for every subset).
  for (const AblationEntry& e : result.ablation.entries)
    for (Check& c : CheckRefinement(result.linear, e.result, SubsetName(e.effects), CheckStatus::kWarning))
      if (c.status != CheckStatus::kOk) result.checks.push_back(std::move(c));
  return result;
}

nlohmann::json AblateJson(const AblateCommandResult& result) {
  nlohmann::json report = CommandJsonHead("ablate", AblateSettingsJson(result.options));
  report["effective_samples"] = result.ablation.effective_samples;
  report["linear"] = LinearJson(result.linear);
  report["ablation"] = AblationJson(result.ablation);
  report["checks"] = ChecksJson(result.checks);
  AddCommonReportSections(result.options.input, result.training, &result.validation, &report);
  return report;
}

ReportInput AblateReportInput(const AblateCommandResult& result) {
  const IdentificationResult& linear = result.linear;
  ReportInput input = CommandReportInput("ablate", result.options.identify.observation, result.training,
                                         &result.validation, AblateSettingsJson(result.options));
  input.linear = &linear;
  input.ablation = &result.ablation;
  input.checks = result.checks;
  input.flights = ReportFlights(linear.flights, false);
  // The parameter table: the linear result and the subset with the lowest BIC.
  input.parameter_sets = {{"linear", PredictedParameters(linear.system, linear.solution), Effects()}};
  const std::vector<AblationEntry>& entries = result.ablation.entries;
  const auto best = std::min_element(entries.begin(), entries.end(),
                                     [](const AblationEntry& a, const AblationEntry& b) { return a.bic < b.bic; });
  if (best != entries.end())
    input.parameter_sets.push_back({"lowest BIC: " + SubsetName(best->effects),
                                    PredictedParameters(linear.system, best->result.refined), best->result.effects});
  return input;
}

std::string WriteAblateReport(const AblateCommandResult& result) {
  return WriteCommandReport(result.options.input, AblateReportInput(result));
}

std::string AblateBrief(const AblateCommandResult& result) {
  const bool held_out = !result.held_out.empty();
  std::ostringstream out;
  out << "rotorid ablate: " << result.ablation.entries.size() << " subsets of " << result.options.effects << "\n";
  out << std::left << std::setw(46) << "effects" << std::right << std::setw(4) << "k" << std::setw(11) << "BIC"
      << "  relative error (identification" << (held_out ? " | held-out" : "") << ")\n";
  for (const AblationEntry& e : result.ablation.entries) {
    out << std::left << std::setw(46) << SubsetName(e.effects) << std::right << std::setw(4) << e.num_parameters
        << std::fixed << std::setprecision(1) << std::setw(11) << e.bic << "  " << ComponentsText(e.relative_error_pct);
    if (held_out) out << " | " << ComponentsText(e.held_out_relative_error_pct);
    out << "\n";
  }
  return out.str();
}

}  // namespace rotorid

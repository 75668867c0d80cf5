#include "rotorid/commands/refine_command.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/refine/refine_checks.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"
#include "rotorid/report/progress.h"
#include "rotorid/report/refine_json.h"

namespace rotorid {

namespace {

nlohmann::json RefineSettingsJson(const RefineCommandOptions& options) {
  return {{"observation", ObservationOptionsJson(options.identify.observation)},
          {"tls", TlsOptionsJson(options.identify.tls)},
          {"first_moment", FirstMomentName(options.identify.first_moment)},
          {"refine", RefineOptionsJson(options.refine)}};
}

// A parameter set on the held-out flights: each flight's first moment fitted when the set has
// per-flight ones, then Table III with the set's effects.
HeldOutFit FitHeldOut(std::vector<ProcessedFlight>* held_out, std::map<std::string, double> values,
                      const Effects& effects) {
  HeldOutFit fit;
  fit.values = std::move(values);
  if (held_out->empty()) return fit;
  fit.first_moments = FitHeldOutFirstMomentsWithEffects(held_out, &fit.values, effects);
  fit.relative_error_pct = effects.AllZero() ? CombinedRelativeErrorPct(*held_out, fit.values)
                                             : RelativeErrorWithEffects(*held_out, fit.values, effects);
  return fit;
}

nlohmann::json HeldOutFitJson(const HeldOutFit& fit, bool with_first_moments) {
  nlohmann::json out = {{"relative_error_pct", ComponentsJson(fit.relative_error_pct)}};
  if (with_first_moments) out["first_moments"] = FirstMomentsJson(fit.first_moments);
  return out;
}

// Each block's own essential flag, as in the JSON: a parameter one block discarded shows "discarded"
// in that block's std column, and the change is shown where both estimated it.
std::string SideBySideText(const IdentificationResult& linear, const RefineResult& refined) {
  const TlsSolution& a = linear.solution;
  const TlsSolution& b = refined.refined;
  std::ostringstream out;
  size_t width = 10;
  for (const std::string& n : linear.system.parameter_names) width = std::max(width, n.size() + 2);
  out << std::left << std::setw(static_cast<int>(width)) << "parameter" << std::right << std::setw(13) << "linear"
      << std::setw(10) << "std" << std::setw(13) << "refined" << std::setw(10) << "std" << std::setw(10)
      << "change/std\n";
  const auto value_and_std = [&out](const TlsSolution& s, int k) {
    out << std::scientific << std::setprecision(4) << std::setw(13) << s.chi[k] << std::setprecision(1)
        << std::setw(10);
    if (s.essential[k])
      out << s.std[k];
    else
      out << "discarded";
  };
  for (int k = 0; k < linear.system.num_parameters(); ++k) {
    out << std::left << std::setw(static_cast<int>(width)) << linear.system.parameter_names[k] << std::right;
    value_and_std(a, k);
    value_and_std(b, k);
    if (a.essential[k] && b.essential[k] && a.std[k] > 0)
      out << std::fixed << std::setprecision(2) << std::setw(10) << (b.chi[k] - a.chi[k]) / a.std[k];
    else
      out << std::setw(10) << "-";
    out << "\n";
  }
  return out.str();
}

std::string EffectsText(const RefineResult& refined) {
  std::ostringstream out;
  out << "effects (value +- std):\n";
  for (EffectKind kind : AllEffects()) {
    const bool on = std::find(refined.enabled.begin(), refined.enabled.end(), kind) != refined.enabled.end();
    out << "  " << std::left << std::setw(27) << EffectParameterName(kind) << std::right << " "
        << (on ? kind->Format(refined.effects.Get(kind), refined.effects_std.Get(kind)) : "off") << "\n";
  }
  return out.str();
}

}  // namespace

std::string RefineCommandOptions::Validate() const {
  try {
    RefineOptions resolved = refine;
    resolved.effects = ParseEffectList(effects);
    if (std::string problem = resolved.Validate(); !problem.empty()) return problem;
  } catch (const Error& e) {
    return e.what();
  }
  return input.Validate();
}

RefineCommandResult RunRefine(const RefineCommandOptions& options) {
  RefineCommandResult result;
  result.options = options;
  RefineOptions& refine = result.options.refine;
  const IdentifyOptions& identify = options.identify;
  result.training = LoadFlights(options.input.training, options.input);
  result.validation = LoadFlights(options.input.held_out, options.input);
  IdentificationResult& linear = result.linear;
  linear = IdentifyWithChecks(std::move(result.training.flights), identify, &result.checks);
  linear.system.w = Eigen::MatrixXd();  // the refinements rebuild rows with effects: 100 MB less on a 1 h log
  refine.effects = EffectsForFlights(options.effects, linear, options.input);
  Progress progress("refine: delay search and Ceres passes", RefineSteps(refine), options.input.quiet);
  progress.StartTicking();
  result.refined = Refine(linear, refine, [&progress](int done, int) { progress.Update(done); });
  progress.Finish();
  for (Check& c : CheckRefinement(linear, result.refined)) result.checks.push_back(std::move(c));
  ExcuseLinearErrorsTheRefinementExplains(linear, result.refined, &result.checks);
  for (Check& c : CheckTimingAtHalfCutoff(linear, identify, result.refined, refine))
    result.checks.push_back(std::move(c));

  if (!result.validation.flights.empty())
    result.held_out = ProcessFlights(result.validation.flights, identify.observation);
  result.held_out_linear = FitHeldOut(&result.held_out, PredictedParameters(linear.system, linear.solution), Effects{});
  result.held_out_refined =
      FitHeldOut(&result.held_out, PredictedParameters(linear.system, result.refined.refined), result.refined.effects);
  if (!result.held_out.empty())
    for (Check& c : CheckRelativeError(result.held_out_refined.relative_error_pct, "held-out refined", true))
      result.checks.push_back(std::move(c));
  result.warnings = linear.warnings;
  result.warnings.insert(result.warnings.end(), result.refined.warnings.begin(), result.refined.warnings.end());
  return result;
}

nlohmann::json RefineJson(const RefineCommandResult& result) {
  nlohmann::json report = CommandJsonHead("refine", RefineSettingsJson(result.options));
  report["linear"] = LinearJson(result.linear);
  report["refined"] = RefinedJson(result.linear, result.refined);
  if (!result.held_out.empty()) {
    const bool per_flight = !result.held_out_linear.first_moments.empty();
    report["held_out"] = {{"linear", HeldOutFitJson(result.held_out_linear, per_flight)},
                          {"refined", HeldOutFitJson(result.held_out_refined, per_flight)}};
  }
  report["checks"] = ChecksJson(result.checks);
  AddCommonReportSections(result.options.input, result.training, &result.validation, &report);
  return report;
}

ReportInput RefineReportInput(const RefineCommandResult& result) {
  ReportInput input = CommandReportInput("refine", result.options.identify.observation, result.training,
                                         &result.validation, RefineSettingsJson(result.options));
  input.linear = &result.linear;
  input.refined = &result.refined;
  if (!result.held_out.empty())
    input.relative_errors = {{"held-out flights", "linear", result.held_out_linear.relative_error_pct},
                             {"held-out flights", "refined", result.held_out_refined.relative_error_pct}};
  input.checks = result.checks;
  input.flights = ReportFlights(result.linear.flights, result.held_out);
  input.parameter_sets = {{"linear", result.held_out_linear.values, Effects()},
                          {"refined", result.held_out_refined.values, result.refined.effects}};
  return input;
}

std::string WriteRefineReport(const RefineCommandResult& result) {
  return WriteCommandReport(result.options.input, RefineReportInput(result));
}

std::string RefineBrief(const RefineCommandResult& result) {
  const RefineResult& refined = result.refined;
  std::ostringstream out;
  out << "rotorid refine: " << TlsMethodName(result.options.identify.tls.method) << " TLS, then Ceres with effects "
      << (result.options.effects.empty() ? "none" : result.options.effects) << " (" << refined.solver.iterations
      << " iterations, " << refined.solver.termination << ")\n";
  out << SideBySideText(result.linear, refined) << EffectsText(refined);
  out << "relative error, identification flights: linear " << ComponentsText(result.linear.relative_error_pct)
      << "\n                                      refined " << ComponentsText(refined.relative_error_pct) << "\n";
  if (!result.held_out.empty())
    out << "relative error, held-out flights:       linear "
        << ComponentsText(result.held_out_linear.relative_error_pct)
        << "\n                                      refined "
        << ComponentsText(result.held_out_refined.relative_error_pct) << "\n";
  return out.str();
}

}  // namespace rotorid

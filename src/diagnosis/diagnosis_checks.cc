#include "rotorid/diagnosis/diagnosis_checks.h"

#include <algorithm>

#include "diagnosis/held_out.h"
#include "diagnosis/linearization.h"
#include "rotorid/core/text.h"
#include "rotorid/refine/refine.h"

namespace rotorid {
namespace {

// A parameter the diagnosis discarded is 0 in its map: not estimated. Without a std (empty map) a
// check counts any violation.
CheckedParameters Checked(const std::map<std::string, double>& values, const std::map<std::string, double>& std,
                          const std::map<std::string, double>& predicts_with,
                          const std::map<std::string, double>& mass_kg) {
  CheckedParameters p;
  p.value = values;
  p.std = std;
  p.mass_kg = mass_kg;
  for (const auto& [name, value] : predicts_with)
    if (const auto it = values.find(name); it != values.end() && it->second != value) p.predicts_with[name] = value;
  for (const auto& [name, value] : values) p.essential[name] = value != 0.0;
  return p;
}

// The check's linearisation keeps at most this many row samples (an even stride): a first-order
// screen needs the signatures' shapes, not every row, and the Jets of every row were most of
// identify's time and, on long logs, its memory. On 19 simulated and 7 real logs the verdicts
// stayed the same down to 1000 row samples, the shrinks within 1 percentage point
// (docs/benchmarks.md); 2000 -> 1000 took 4 % off identify of a 90 s log.
constexpr int kSignatureRowSamples = 1000;

}  // namespace

std::vector<Check> CheckDiagnosis(const Diagnosis& diagnosis, const std::vector<std::string>& configs,
                                  const std::map<std::string, double>& mass_kg) {
  std::vector<Check> checks = CheckParameters(
      Checked(diagnosis.linear_parameters, diagnosis.linear_parameter_std, diagnosis.linear_predicts_with, mass_kg),
      configs, "linear");
  auto append = [&](std::vector<Check> more) {
    for (Check& c : more) checks.push_back(std::move(c));
  };
  if (!diagnosis.final_model.empty()) {
    std::vector<Check> final_checks = CheckParameters(
        Checked(diagnosis.final_parameters, diagnosis.final_parameter_std, diagnosis.final_predicts_with, mass_kg),
        configs, "final");
    ExcuseLinearParameterErrors(std::vector<Check>(checks), final_checks, &checks);
    append(std::move(final_checks));
    bool finite = true;
    for (EffectKind kind : diagnosis.final_model)
      finite =
          finite && diagnosis.final_effects.Get(kind).allFinite() && diagnosis.final_effects_std.Get(kind).allFinite();
    if (!finite) checks.push_back({"effects_finite", CheckStatus::kError, "final: NaN or inf in a selected effect"});
  }
  append(CheckRelativeError(diagnosis.baseline.relative_error_pct, "held-out linear", /*held_out=*/true));
  append(CheckRelativeError(diagnosis.final_gap.relative_error_pct, "held-out final", /*held_out=*/true));
  return checks;
}

Check CheckResidualSignature(const IdentificationResult& linear, const DiagnosisOptions& options,
                             double min_shrink_pct) {
  std::vector<EffectKind> candidates;
  for (EffectKind kind : options.candidates) {
    bool available = kind->FixedDimension() > 0;
    for (const ProcessedFlight& flight : linear.flights)
      available = available && kind->Unavailable(flight.inputs()).empty();
    if (available) candidates.push_back(kind);
  }
  const internal::EffectLinearization linearization = internal::LinearizeEffects(
      linear.flights, NamedParameters(linear.system, PredictionChi(linear.solution)),
      internal::EstimatedParameterNames(linear), Effects{}, candidates, kSignatureRowSamples, options.num_threads);
  // In-sample forward selection to first order: the effect that removes the most, then what each
  // further one adds on top, while that is at least min_shrink_pct and significant. An effect that
  // stands in for part of another (an acc delay for part of a lag) adds little once that one is in.
  std::vector<EffectKind> shown;
  std::vector<std::string> parts;
  double shown_shrink = 0.0;
  for (;;) {
    EffectKind best = nullptr;
    EffectTest best_test;
    std::vector<EffectKind> rivals;  // fit as well as the best, within a tenth of its shrink
    std::vector<std::pair<EffectKind, double>> added;
    for (EffectKind kind : candidates) {
      if (std::find(shown.begin(), shown.end(), kind) != shown.end()) continue;
      std::vector<EffectKind> subset = shown;
      subset.push_back(kind);
      const internal::EffectSubsetFit fit = internal::FitEffectSubset(linearization, subset);
      const EffectTest test = internal::ScreeningTest(fit.predicted_shrink - shown_shrink, EffectDimension(kind),
                                                      fit.effective_samples, linearization.scored_rows);
      added.emplace_back(kind, test.shrink_pct);
      if (!best || test.shrink_pct > best_test.shrink_pct) {
        best = kind;
        best_test = test;
      }
    }
    if (!best || best_test.shrink_pct < min_shrink_pct || !(best_test.p_value < options.alpha)) break;
    for (const auto& [kind, shrink] : added)
      if (kind != best && shrink >= 0.9 * best_test.shrink_pct) rivals.push_back(kind);
    std::string part = best->name() + " (" + FormatValue("%.0f", best_test.shrink_pct) + " %";
    for (EffectKind rival : rivals) part += "; " + rival->name() + " fits as well";
    parts.push_back(part + ")");
    shown.push_back(best);
    shown_shrink += best_test.shrink_pct / 100.0;
  }
  if (shown.empty())
    return {"residual_signature", CheckStatus::kOk,
            "the residual shows no candidate effect's signature (none removes " + ShortNumber(min_shrink_pct) +
                " % of it to first order)"};
  std::string effects, names;
  for (size_t k = 0; k < shown.size(); ++k) {
    effects += (k == 0 ? "" : ", then ") + parts[k];
    names += (k == 0 ? "" : ",") + shown[k]->name();
  }
  return {"residual_signature", CheckStatus::kWarning,
          "the residual shows the signature of " + effects +
              ": the share of the in-sample residual a first-order fit removes, each on top of the ones before; "
              "`rotorid refine --effects " +
              names + "` estimates " + (shown.size() == 1 ? "it" : "them") +
              " with the parameters, `rotorid diagnose` tests " + (shown.size() == 1 ? "it" : "them") +
              " on held-out data"};
}

}  // namespace rotorid

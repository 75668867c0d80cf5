#include "rotorid/diagnosis/diagnosis_checks.h"

namespace rotorid {
namespace {

// A parameter the diagnosis discarded is 0 in its map: not estimated.
CheckedParameters ValuesOnly(const std::map<std::string, double>& values) {
  CheckedParameters p;
  p.value = values;
  for (const auto& [name, value] : values) p.essential[name] = value != 0.0;
  return p;
}

}  // namespace

std::vector<Check> CheckDiagnosis(const Diagnosis& diagnosis, const std::vector<std::string>& configs) {
  std::vector<Check> checks = CheckParameters(ValuesOnly(diagnosis.linear_parameters), configs, "linear");
  auto append = [&](std::vector<Check> more) {
    for (Check& c : more) checks.push_back(std::move(c));
  };
  if (!diagnosis.selected.empty()) {
    append(CheckParameters(ValuesOnly(diagnosis.final_parameters), configs, "final"));
    bool finite = true;
    for (EffectKind kind : diagnosis.selected)
      finite =
          finite && diagnosis.final_effects.Get(kind).allFinite() && diagnosis.final_effects_std.Get(kind).allFinite();
    if (!finite) checks.push_back({"effects_finite", CheckStatus::kError, "final: NaN or inf in a selected effect"});
  }
  append(CheckRelativeError(diagnosis.baseline.relative_error_pct, "held-out linear", /*held_out=*/true));
  append(CheckRelativeError(diagnosis.final_gap.relative_error_pct, "held-out final", /*held_out=*/true));
  return checks;
}

}  // namespace rotorid

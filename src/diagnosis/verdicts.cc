#include "diagnosis/verdicts.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "diagnosis/statistics.h"
#include "rotorid/core/units.h"
#include "rotorid/model/parameters.h"

namespace rotorid::internal {

Eigen::VectorXd DetectableSizes(const Eigen::VectorXd& std_dev, int parameters, double effective_samples,
                                const DiagnosisOptions& options) {
  const double q = parameters;
  const double n_eff = std::max(effective_samples, q + 2.0);
  const double f_critical = FCritical(options.alpha, q, n_eff - q);
  const double required_shrink = std::max(options.min_shrink_pct / 100.0, q * f_critical / n_eff);
  return std_dev * std::sqrt(required_shrink * n_eff);
}

namespace {

// A kept effect: its test on top of the kept effects added before it.
void ApplyKeptStep(const std::vector<SelectionStep>& steps, EffectVerdict* v) {
  EffectMask prefix = 0;
  for (size_t i = 0; i < steps.size(); ++i) {
    if (steps[i].added == v->kind) {
      v->step = static_cast<int>(i) + 1;
      v->tested_on_top_of = KindsOf(prefix);
      v->test = steps[i].test;
      v->significant = v->test.significant;
      v->relative_error_pct = steps[i].after.relative_error_pct;
    }
    prefix |= Bit(steps[i].added);
  }
}

// A dropped effect: its test on top of all the others at the moment it was dropped.
void ApplyDropped(const SelectionContext& context, const std::vector<DroppedEffect>& dropped, EffectVerdict* v) {
  for (const DroppedEffect& d : dropped) {
    if (d.kind != v->kind) continue;
    const ModelRecord& with = context.records.at(d.others | Bit(v->kind));
    v->dropped_as_redundant = true;
    v->tested_on_top_of = KindsOf(d.others);
    v->test = d.test;
    v->significant = false;
    v->relative_error_pct = with.gap.relative_error_pct;
    v->value = MeanFoldEffect(with, v->kind);
  }
}

}  // namespace

UnscoredShare MostlyUnscoredShare(const EffectLinearization& linearization, EffectKind kind) {
  UnscoredShare out;
  const auto k = std::find(linearization.kinds.begin(), linearization.kinds.end(), kind);
  if (k == linearization.kinds.end() || linearization.unscored_components.empty()) return out;
  for (size_t c = 0; c < linearization.column_kind.size(); ++c) {
    const double column_share = linearization.effect_unscored_share[static_cast<Eigen::Index>(c)];
    if (linearization.column_kind[c] == k - linearization.kinds.begin() && column_share > out.share) {
      out.share = column_share;
      out.label = linearization.labels[c];
    }
  }
  return out;
}

namespace {

// Why a candidate acting mostly where nothing is scored is not ruled out; empty otherwise.
std::string UnscoredStatement(const EffectLinearization& linearization, EffectKind kind) {
  const UnscoredShare unscored = MostlyUnscoredShare(linearization, kind);
  const double share = unscored.share;
  if (!(share > kMostlyUnscored)) return "";
  std::string components, coefficients;
  for (int j : linearization.unscored_components) {
    components += (components.empty() ? "" : ", ") + std::string(kWrenchComponentNames[static_cast<size_t>(j)]);
    const std::string coefficient = j == 5 ? "kd" : "kt";
    if (coefficients.find(coefficient) == std::string::npos)
      coefficients += (coefficients.empty() ? "" : ", ") + coefficient;
  }
  std::ostringstream out;
  out << "but " << std::lround(100.0 * share) << " % of " << unscored.label << "'s signature lies in " << components
      << ", which no test here scores (the linear identification discarded " << coefficients
      << ", so that component has no rotor term): this data cannot rule it out, and an unmodelled effect there "
         "can be what made "
      << coefficients << " unidentifiable";
  return out.str();
}

EffectVerdict& VerdictIn(std::vector<EffectVerdict>& verdicts, EffectKind kind) {
  return *std::find_if(verdicts.begin(), verdicts.end(), [&](const EffectVerdict& v) { return v.kind == kind; });
}

}  // namespace

EffectVerdict VerdictOf(EffectKind kind, const SelectionContext& context, const SelectionOutcome& outcome) {
  const EffectMask kept = MaskOf(outcome.backward.kept);
  EffectVerdict v;
  v.kind = kind;
  v.selected = Has(kept, kind);
  const auto t = outcome.forward.tested.find(kind);
  const bool tested = t != outcome.forward.tested.end();
  const auto record = tested ? context.records.find(t->second.base | Bit(kind)) : context.records.end();
  const bool refined = record != context.records.end();
  if (tested) {
    v.step = t->second.step;
    v.tested_on_top_of = KindsOf(t->second.base);
    v.test = t->second.test;
    v.alone_test = t->second.alone;
    v.screening = t->second.screening;
    if (refined) v.relative_error_pct = record->second.gap.relative_error_pct;
  }
  v.significant = v.test.significant;
  std::vector<EffectKind> subset = KindsOf(kept);
  if (!v.selected) subset.push_back(kind);
  const EffectSubsetFit fit = v.selected ? outcome.kept_fit : FitEffectSubset(outcome.linearization, subset);
  v.std = EffectColumns(fit, kind, fit.std);
  v.detectable_above =
      DetectableSizes(v.std, kind->FreeDimension(context.vehicle), fit.effective_samples, context.options);
  // A free coordinate with no std has no column in the scored rows: no size reveals it (not 0).
  for (Eigen::Index k = 0; k < v.detectable_above.size(); ++k)
    if (!(v.std[k] > 0.0) && !kind->Held(static_cast<int>(k)))
      v.detectable_above[k] = std::numeric_limits<double>::infinity();
  if (v.selected) {
    v.value = outcome.final_effects.Get(kind);
    v.status = "selected";
  } else {
    if (refined && !v.test.screened)
      v.value = MeanFoldEffect(record->second, kind);
    else if (tested)
      v.value = t->second.linearized_value;
    else
      v.value = Eigen::VectorXd::Zero(kind->Dimension(context.vehicle));
    v.status = "not significant";
  }
  if (tested && t->second.Rejected() && !v.selected) {
    v.status = t->second.implausible.empty() ? "negligible" : "implausible";
    v.implausible = t->second.implausible;
    v.negligible = t->second.negligible;
  }
  if (tested && !t->second.worsens.empty() && !v.selected && !t->second.Rejected()) {
    v.status = "worsens a component";
    v.worsens = t->second.worsens;
  }
  if (tested && v.selected) v.held_at_half_cutoff = t->second.held_at_half_cutoff;
  if (v.selected) v.unstated_reference = kind->UnstatedReference(v.value, context.vehicle);
  ApplyKeptStep(outcome.steps, &v);
  ApplyDropped(context, outcome.backward.dropped, &v);
  if (!v.selected) v.unscored = UnscoredStatement(outcome.linearization, kind);
  return v;
}

void MarkConfounded(const std::vector<ConfoundedEffects>& confounded, std::vector<EffectVerdict>* verdicts) {
  for (const ConfoundedEffects& c : confounded) {
    EffectVerdict& other = VerdictIn(*verdicts, c.other);
    other.confounded_with.push_back(c.selected);
    if (!c.distinguishable) other.status = "confounded";
    VerdictIn(*verdicts, c.selected).confounded_with.push_back(c.other);
  }
}

std::vector<EffectVerdict> Rank(std::vector<EffectVerdict> verdicts, const std::vector<EffectKind>& kept,
                                const std::vector<EffectVerdict>& unavailable) {
  std::vector<EffectVerdict> ranking;
  for (EffectKind kind : kept) ranking.push_back(VerdictIn(verdicts, kind));
  std::vector<EffectVerdict> rest;
  for (const EffectVerdict& v : verdicts)
    if (!v.selected) rest.push_back(v);
  std::stable_sort(rest.begin(), rest.end(), [](const EffectVerdict& a, const EffectVerdict& b) {
    return a.test.shrink_pct > b.test.shrink_pct;
  });
  ranking.insert(ranking.end(), rest.begin(), rest.end());
  ranking.insert(ranking.end(), unavailable.begin(), unavailable.end());
  return ranking;
}

std::string DiscardedProductStatement(const EffectVerdict& v, const std::vector<DiscardedParameter>& discarded) {
  if (v.kind != ParseEffectKind("misalignment") || v.value.size() != 3 || v.std.size() != 3) return {};
  static const char* const kAxes = "xyz";
  static const char* const kProducts[3] = {"I_yz", "I_xz", "I_xy"};  // of the two axes a rotation about k mixes
  std::ostringstream out;
  for (int k = 0; k < 3; ++k) {
    if (!(v.std[k] > 0.0) || std::abs(v.value[k]) < 3.0 * v.std[k]) continue;
    for (const DiscardedParameter& p : discarded) {
      const size_t dot = p.name.rfind('.');
      if (p.name.substr(dot == std::string::npos ? 0 : dot + 1) != kProducts[k]) continue;
      out << (out.tellp() > 0 ? "; " : "") << "its " << kAxes[k] << " coordinate (" << std::setprecision(3)
          << v.value[k] * kRadToDeg << " +- " << std::setprecision(2) << v.std[k] * kRadToDeg
          << " deg) mixes the rows the discarded " << p.name << " couples (" << std::setprecision(3) << p.value
          << " +- " << std::setprecision(2) << p.std << " kg m^2 when dropped at " << std::fixed << std::setprecision(1)
          << p.rel_std_pct << std::defaultfloat
          << " % std, held at 0): it may be that product of inertia rather than an IMU rotation";
      break;
    }
  }
  return out.str();
}

int WhereComponent(const HeldOutGap& baseline) {
  const HeldOutGap& b = baseline;
  double largest_error = -1.0, largest_ratio = -1.0;
  int by_error = -1, by_ratio = 0;
  for (int j = 0; j < kNumWrenchComponents; ++j) {
    if (!b.gap_pct[j] || !b.noise_floor_pct[j] || !b.model_error_pct[j]) continue;
    const double ratio = *b.noise_floor_pct[j] > 0.0 ? *b.gap_pct[j] / *b.noise_floor_pct[j] : INFINITY;
    if (ratio > largest_ratio) {
      largest_ratio = ratio;
      by_ratio = j;
    }
    if (ratio >= std::sqrt(2.0) && *b.model_error_pct[j] > largest_error) {
      largest_error = *b.model_error_pct[j];
      by_error = j;
    }
  }
  return by_error >= 0 ? by_error : by_ratio;
}

}  // namespace rotorid::internal

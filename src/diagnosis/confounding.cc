#include "diagnosis/confounding.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>

namespace rotorid::internal {

std::vector<Rival> FindRivals(const std::vector<ForwardStep>& steps, EffectMask kept) {
  std::vector<Rival> rivals;
  EffectMask before = 0;
  for (const ForwardStep& step : steps) {
    const SelectionStep& selection = step.selection;
    if (Has(kept, selection.added)) {
      for (const auto& [other, other_test] : step.refined) {
        if (other == selection.added || Has(kept, other)) continue;
        if (!other_test.significant || other_test.shrink_pct < 0.5 * selection.test.shrink_pct) continue;
        rivals.push_back({selection.added, other, before, selection.test, other_test,
                          other == step.timing_twin ? step.timing_separation : std::nullopt});
      }
    }
    before |= Bit(selection.added);
  }
  return rivals;
}

namespace {

// "; alone, motor_lag = 25.1 ms and delay = 24.6 ms fit as well" for two scalar effects (a delay
// and a lag, say): what the data do fix is what the two values share. Empty otherwise.
std::string AloneValues(EffectKind a, const ModelRecord& with_a, EffectKind b, const ModelRecord& with_b) {
  if (a->FixedDimension() != 1 || b->FixedDimension() != 1) return "";
  return "; alone, " + std::string(EffectName(a)) + " = " + a->Format(MeanFoldEffect(with_a, a), {}) + " and " +
         EffectName(b) + " = " + b->Format(MeanFoldEffect(with_b, b), {}) +
         " fit as well: the data fix what the two share, not which of them it is";
}

}  // namespace

ConfoundedEffects CompareRival(const Rival& rival, const ModelRecord& with_selected, const ModelRecord& with_other,
                               const HeldOutScales& scales, double alpha) {
  ConfoundedEffects c;
  c.selected = rival.selected;
  c.other = rival.other;
  c.selected_shrink_pct = rival.selected_test.shrink_pct;
  c.other_shrink_pct = rival.other_test.shrink_pct;
  const PairedComparison comparison = CompareHeldOut(with_selected.held_out, with_other.held_out, scales);
  c.t_statistic = comparison.t_statistic;
  c.p_value = comparison.p_value;
  // Practical equivalence (issue 11): a significant t on two held-out shrinks that are almost
  // equal says the better one is better by a hair, not that the data tell them apart.
  const bool practically_equal = std::abs(c.selected_shrink_pct - c.other_shrink_pct) <
                                 kPracticalEquivalence * std::max(c.selected_shrink_pct, c.other_shrink_pct);
  c.distinguishable = comparison.p_value < alpha && !practically_equal;
  const char* selected = EffectName(c.selected);
  const char* other = EffectName(c.other);
  std::ostringstream note;
  note << std::fixed << std::setprecision(1) << other << " alone removes " << c.other_shrink_pct
       << " % of the held-out residual, " << selected << " " << c.selected_shrink_pct << " %";
  const std::optional<TimingSeparation>& separation = rival.separation;
  if (separation && separation->decided == c.selected) {
    c.distinguishable = true;
    note << "; the held-out rows cannot tell them apart (t = " << std::setprecision(1) << c.t_statistic
         << "), but refined together at half the low-pass cut-off (" << separation->cutoff_hz
         << " Hz), below the controller's reply to sensor noise, " << separation->values << ": " << selected
         << " carries the timing, the data tell them apart";
    c.note = note.str();
    return c;
  }
  if (c.distinguishable)
    note << "; " << selected << " fits the held-out rows significantly better (t = " << std::setprecision(1)
         << c.t_statistic << "): the data tell them apart";
  else if (practically_equal)
    note << "; they differ by less than " << std::setprecision(0) << 100 * kPracticalEquivalence
         << " % of that (t = " << std::setprecision(1) << c.t_statistic
         << " measures a hair, not a difference): these flights cannot tell " << selected << " and " << other
         << " apart" << AloneValues(c.selected, with_selected, c.other, with_other);
  else
    note << "; the difference is not significant (t = " << std::setprecision(1) << c.t_statistic
         << "): these flights cannot tell " << selected << " and " << other << " apart"
         << AloneValues(c.selected, with_selected, c.other, with_other);
  if (separation)
    note << "; refined together at half the low-pass cut-off (" << std::setprecision(1) << separation->cutoff_hz
         << " Hz), " << separation->values << ": both carry a share (a mix of the two, or neither pure)";
  c.note = note.str();
  return c;
}

void SetLargestCorrelation(const EffectSubsetFit& joint_fit, ConfoundedEffects* c) {
  for (size_t a = 0; a < joint_fit.labels.size(); ++a)
    for (size_t b = 0; b < joint_fit.labels.size(); ++b) {
      if (joint_fit.column_kind[a] != c->selected || joint_fit.column_kind[b] != c->other) continue;
      const double r = joint_fit.correlation(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
      if (!c->correlation || std::abs(r) > std::abs(*c->correlation)) {
        c->correlation = r;
        c->correlated_labels = joint_fit.labels[a] + " / " + joint_fit.labels[b];
      }
    }
}

std::vector<ConfoundedEffects> AnalyzeConfounding(const std::vector<Rival>& rivals, const SelectionContext& context,
                                                  const HeldOutScales& scales,
                                                  const EffectLinearization& final_linearization,
                                                  const std::vector<EffectKind>& kept_kinds) {
  std::vector<ConfoundedEffects> confounded;
  for (const Rival& rival : rivals) {
    ConfoundedEffects c =
        CompareRival(rival, context.records.at(rival.base | Bit(rival.selected)),
                     context.records.at(rival.base | Bit(rival.other)), scales, context.options.alpha);
    std::vector<EffectKind> pair = kept_kinds;
    pair.push_back(rival.other);
    SetLargestCorrelation(FitEffectSubset(final_linearization, pair), &c);
    confounded.push_back(std::move(c));
  }
  return confounded;
}

}  // namespace rotorid::internal

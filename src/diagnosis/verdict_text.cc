#include "diagnosis/verdict_text.h"

#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>

#include "diagnosis/selection.h"
#include "diagnosis/unexplained.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

std::string FormatEffectMagnitude(EffectKind kind, const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) {
  return kind->Format(value, std_dev);
}

std::string DiagnosisVerdict(const Diagnosis& d) {
  return "held out: " + d.validation + " (" + std::to_string(d.held_out_row_samples) + " row samples)\n" +
         internal::WhereText(d) + internal::WhichText(d) + internal::HowFarText(d) +
         internal::UnexplainedText(d.unexplained);
}

namespace internal {

namespace {

// Whether every estimated coordinate (std > 0; held ones have none) lies within 2 std of zero: the
// effect removes held-out residual, but the flights do not fix its size (thrust scales of 1-8 % with
// a std of 8 % on a 30 s ARPL window, where the first moment takes the same rows).
bool SizeUndetermined(const EffectVerdict& v) {
  if (v.std.size() != v.value.size()) return false;
  int estimated = 0;
  for (Eigen::Index k = 0; k < v.std.size(); ++k) {
    if (!(v.std[k] > 0.0)) continue;
    ++estimated;
    if (std::abs(v.value[k]) >= 2.0 * v.std[k]) return false;
  }
  return estimated > 0;
}

}  // namespace

std::string ScaleFreeValueText(const ScaleFreeTest& t) {
  std::ostringstream out;
  for (Eigen::Index k = 0; k < t.ratio.size(); ++k)
    out << (k ? ", " : "") << t.labels[static_cast<size_t>(k)] << " = " << std::setprecision(4) << t.ratio[k] << " +- "
        << std::setprecision(2) << t.ratio_std[k];
  return out.str();
}

std::string ScaleFreeStatement(const EffectVerdict& v) {
  const ScaleFreeTest& t = *v.scale_free;
  const char* component = kWrenchComponentNames[static_cast<size_t>(t.component)];
  std::ostringstream out;
  out << "the scale-free test of " << component << " (its row alone, every coefficient a ratio to "
      << t.rotor_coefficient << ", which the linear identification discarded) "
      << (v.selected                             ? "selects it"
          : !t.implausible.empty()               ? "finds it implausible"
          : t.relative_error_before_pct >= 100.0 ? "cannot judge it (the row without it predicts its held-out rows no "
                                                   "better than zero)"
                                                 : "finds it not significant")
      << ": " << ScaleFreeValueText(t) << std::fixed << std::setprecision(1) << "; held-out " << component
      << " relative error " << t.relative_error_before_pct << " -> " << t.relative_error_after_pct << " % (shrink "
      << t.test.shrink_pct << " %, F = " << t.test.f_statistic << ", p = " << std::scientific << std::setprecision(1)
      << t.test.p_value << ")";
  if (!t.implausible.empty()) out << "; " << t.implausible;
  if (v.selected)
    out << (t.value.size() > 0 ? "; in SI with the final fit's " + t.rotor_coefficient + ": " +
                                     FormatEffectMagnitude(v.kind, t.value, t.std)
                               : "; " + t.rotor_coefficient + " is not fixed by these flights, so " +
                                     v.kind->parameter_name() + " itself is not");
  return out.str();
}

std::string VerdictNote(const EffectVerdict& v, const DiagnosisOptions& options,
                        const std::vector<EffectKind>& selected) {
  const std::string given = selected.empty() ? "" : " (with " + Join(selected) + " in the model)";
  std::ostringstream note;
  if (v.scale_free && v.selected) return ScaleFreeStatement(v);
  if (v.status == "selected") {
    note << "held-out gap shrinks " << std::fixed << std::setprecision(1) << v.test.shrink_pct << " %";
    if (SizeUndetermined(v))
      note << "; its size is not determined (every coordinate within 2 std of zero): the flights fix what it "
              "removes, not its value";
    if (!v.held_at_half_cutoff.empty()) note << "; " << v.held_at_half_cutoff;
    if (!v.unstated_reference.empty()) note << "; " << v.unstated_reference;
  } else if (v.status == "implausible") {
    note << "implausible: absorbs something else; " << v.implausible << " (its held-out shrink of " << std::fixed
         << std::setprecision(1) << v.test.shrink_pct << " % on top of " << Join(v.tested_on_top_of)
         << " is bought with that value: not selected)";
  } else if (v.status == "negligible") {
    note << "negligible: too small to matter; " << v.negligible << " (its held-out shrink of " << std::fixed
         << std::setprecision(1) << v.test.shrink_pct << " % on top of " << Join(v.tested_on_top_of)
         << " is significant, but not an effect worth modelling: not selected)";
  } else if (v.status == "worsens a component") {
    note << "worsens a component held out: " << v.worsens << " (its held-out shrink of " << std::fixed
         << std::setprecision(1) << v.test.shrink_pct << " % on top of " << Join(v.tested_on_top_of)
         << " trades that component for others rather than explaining the gap: not selected)";
  } else if (v.dropped_as_redundant) {
    note << "selected early, but not significant once " << Join(v.tested_on_top_of) << " were in (held-out shrink "
         << std::setprecision(2) << std::fixed << v.test.shrink_pct << " %): dropped as redundant";
  } else if (v.test.screened && v.test.shrink_pct >= options.screen_fraction * options.min_shrink_pct) {
    note << "not refined: its predicted in-sample shrink (" << std::setprecision(2) << std::fixed << v.test.shrink_pct
         << " %) was well below the leading candidate's at step " << v.step << ", where the selection stopped";
  } else if (v.test.screened) {
    note << "not refined: its first-order in-sample shrink is only " << std::setprecision(2) << std::fixed
         << v.test.shrink_pct << " %; this data would reveal it above "
         << FormatEffectMagnitude(v.kind, v.detectable_above, Eigen::VectorXd()) << given;
  } else if (v.status == "confounded") {
    note << "removes as much held-out residual as " << EffectName(v.confounded_with.front())
         << "; the data cannot tell them apart";
  } else {
    const Eigen::VectorXd ratio = v.value.cwiseAbs().cwiseQuotient(v.detectable_above.cwiseMax(1e-300));
    note << (ratio.maxCoeff() < 1.0 ? "not detected" : "not significant") << "; this data would reveal it above "
         << FormatEffectMagnitude(v.kind, v.detectable_above, Eigen::VectorXd()) << given;
  }
  if (v.scale_free)
    note << "; " << ScaleFreeStatement(v);
  else if (!v.unscored.empty())
    note << "; " << v.unscored;
  return note.str();
}

// Distance from a bound, relative to the range, within which a value is on it (the refinement's own
// test is stricter, 1e-9: this one only has to find the coordinate that test saw).
constexpr double kOnBoundMargin = 1e-6;

std::string OnBoundStatement(EffectKind kind, const Eigen::VectorXd& value) {
  const double lower = kind->info().lower_bound, upper = kind->info().upper_bound;
  const double margin = kOnBoundMargin * (upper - lower);
  auto on = [&](double v, double bound) { return bound != 0.0 && std::abs(v - bound) <= margin; };
  const std::vector<std::string> labels = kind->Labels(static_cast<int>(value.size()));
  std::string out;
  int named = 0;
  for (Eigen::Index k = 0; k < value.size(); ++k) {
    const bool at_upper = on(value[k], upper);
    if (!at_upper && !on(value[k], lower)) continue;
    out += std::string(named++ ? ", " : "") + (value.size() == 1 ? kind->name() : labels[k]) + " = " +
           kind->Format(value.segment(k, 1), {}) + " is on its " + (at_upper ? "upper" : "lower") + " bound (" +
           kind->Format(Eigen::VectorXd::Constant(1, at_upper ? upper : lower), {}) + ")";
  }
  // A bound the descriptor does not know (a grid-searched effect's search range): not named.
  if (named == 0) return kind->name() + " ended on a bound of its search range: the data push it further";
  return out + (named == 1 ? ": the data push it further" : ": the data push them further");
}

namespace {

std::string Percent(const std::optional<double>& v) {
  std::ostringstream s;
  if (v)
    s << std::fixed << std::setprecision(2) << *v << " %";
  else
    s << "n/a";
  return s.str();
}

// The band where the selected effects remove the most residual energy of component j, else the band
// that holds the most of it.
std::string BandText(const Diagnosis& d, int j) {
  auto removed = [&](const BandGap& b) {
    return b.residual_rms[j] * b.residual_rms[j] - b.final_residual_rms[j] * b.final_residual_rms[j];
  };
  size_t band = 0;
  for (size_t b = 1; b < d.where.bands.size(); ++b) {
    const bool better = d.final_model.empty() ? d.where.bands[b].share_pct[j] > d.where.bands[band].share_pct[j]
                                              : removed(d.where.bands[b]) > removed(d.where.bands[band]);
    if (better) band = b;
  }
  const BandGap& bg = d.where.bands[band];
  std::ostringstream out;
  out << std::fixed << ";\n       mostly at " << std::setprecision(0) << bg.low_hz << "-" << bg.high_hz << " Hz ("
      << bg.share_pct[j] << " % of its residual energy";
  if (!d.final_model.empty() && bg.residual_rms[j] > 0.0)
    out << ", of which the selected effects remove " << 100.0 * removed(bg) / (bg.residual_rms[j] * bg.residual_rms[j])
        << " %";
  out << ")";
  return out.str();
}

std::string StretchText(const FlightStretch& w) {
  std::ostringstream out;
  out << std::fixed << ";\n       worst stretch " << std::setprecision(1) << w.start_s << "-" << w.end_s << " s (";
  for (size_t a = 0; a < w.activities.size(); ++a) out << (a ? ", " : "") << w.activities[a];
  out << "; rates " << std::setprecision(2) << w.angular_velocity_rms[0] << "/" << w.angular_velocity_rms[1] << "/"
      << w.angular_velocity_rms[2] << " rad/s RMS; " << std::setprecision(1) << w.mean_square_ratio
      << "x the flight's mean square, mostly " << kWrenchComponentNames[w.dominant_component] << ")";
  return out.str();
}

}  // namespace

std::string WhereText(const Diagnosis& d) {
  const int j = d.where_component;
  const HeldOutGap& b = d.baseline;
  std::string out;
  const bool beyond_noise =
      b.gap_pct[j] && b.noise_floor_pct[j] && *b.gap_pct[j] >= std::sqrt(2.0) * *b.noise_floor_pct[j];
  if (beyond_noise)
    out = "where: the largest held-out gap beyond the noise floor is in " + std::string(kWrenchComponentNames[j]) +
          ": " + Percent(b.model_error_pct[j]) + (j < 2 ? " of the thrust" : "") + " (gap " + Percent(b.gap_pct[j]) +
          ", noise floor " + Percent(b.noise_floor_pct[j]) + ")";
  else
    out = "where: no component's held-out gap is well above its noise floor (closest: " +
          std::string(kWrenchComponentNames[j]) + ", gap " + Percent(b.gap_pct[j]) + " against " +
          Percent(b.noise_floor_pct[j]) + ")";
  if (!d.where.bands.empty()) out += BandText(d, j);
  if (!d.where.worst_stretches.empty()) out += StretchText(d.where.worst_stretches.front());
  return out + "\n";
}

std::string WhichText(const Diagnosis& d) {
  std::ostringstream out;
  out << std::fixed;
  if (d.selected.empty()) {
    std::string unscored;
    for (const EffectVerdict& v : d.ranking)
      if (!v.unscored.empty() || v.scale_free)
        unscored += (unscored.empty() ? "" : ", ") + std::string(EffectName(v.kind));
    out << "which: no candidate effect removes significant held-out residual; the model explains these flights "
           "as well as the candidates can"
        << (unscored.empty()
                ? std::string()
                : " in the components it scores (" + unscored + ": mostly in one it does not score, below)")
        << "\n";
  }
  for (const EffectVerdict& v : d.ranking) {
    if (v.selected && v.scale_free) {
      out << (v.kind == d.selected.front() ? "which: " : "     + ") << EffectName(v.kind) << ": " << v.note << "\n";
    } else if (v.selected) {
      out << (v.kind == d.selected.front() ? "which: " : "     + ") << EffectName(v.kind) << " = "
          << FormatEffectMagnitude(v.kind, v.value, v.std) << " (F = " << std::setprecision(1) << v.test.f_statistic
          << ", p = " << std::scientific << std::setprecision(1) << v.test.p_value << std::fixed
          << "; held-out gap shrinks " << std::setprecision(1) << v.test.shrink_pct << " %)\n";
      if (!v.unstated_reference.empty()) out << "       " << v.unstated_reference << "\n";
    }
  }
  for (const ConfoundedEffects& c : d.confounded) {
    out << "       " << c.note;
    if (c.correlation) out << " (correlation " << std::setprecision(2) << *c.correlation << ")";
    out << "\n";
  }
  for (const EffectVerdict& v : d.ranking)
    if (!v.selected) out << "       " << EffectName(v.kind) << ": " << v.note << "\n";
  return out.str();
}

std::string HowFarText(const Diagnosis& d) {
  std::ostringstream out;
  out << std::fixed << "how far (held-out gap, %; Fx, Fy against the thrust): baseline";
  for (EffectKind kind : d.final_model) out << " -> +" << EffectName(kind);
  out << "\n";
  auto value = [&](const std::optional<double>& v) {
    if (v)
      out << std::setprecision(2) << *v;
    else
      out << "n/a";
  };
  for (int c = 0; c < kNumWrenchComponents; ++c) {
    out << "       " << kWrenchComponentNames[c] << " ";
    value(d.baseline.gap_pct[c]);
    for (const SelectionStep& step : d.steps) {
      out << " -> ";
      value(step.after.gap_pct[c]);
    }
    out << "  (noise floor ";
    value(d.baseline.noise_floor_pct[c]);
    // The final model's own floor, where its parameters move it (unexplained[] judges against it).
    const std::optional<double>&before = d.baseline.noise_floor_pct[c], &after = d.final_gap.noise_floor_pct[c];
    if (!d.steps.empty() && after && (!before || std::abs(*after - *before) > 0.05 * *before)) {
      out << "; with the selected effects ";
      value(after);
    }
    out << ")\n";
    // Each gap divides by its own model's rotor wrench, which an effect can change (per-rotor thrust
    // scales cancel a static moment that the baseline's first moment balanced: jana01's My read 8.4 ->
    // 33.3 % while its residual fell by a third): the residual itself is the comparison that no
    // divisor moves, so each step's is printed too.
    out << "          residual " << std::scientific << std::setprecision(2) << d.baseline.residual_rms[c];
    for (const SelectionStep& step : d.steps) out << " -> " << step.after.residual_rms[c];
    out << (c < 3 ? " N" : " N m") << std::fixed;
    if (!d.steps.empty() && d.baseline.residual_rms[c] > 0.0)
      out << " (" << std::showpos << std::setprecision(0)
          << 100.0 * (d.steps.back().after.residual_rms[c] / d.baseline.residual_rms[c] - 1.0) << std::noshowpos
          << " %)";
    // Mz without kd: the held-out score leaves it out, and its residual lacks the rotor term.
    if (!d.baseline.gap_pct[c]) out << "; not scored (no rotor term in the linear model)";
    out << "\n";
  }
  return out.str();
}

}  // namespace internal
}  // namespace rotorid

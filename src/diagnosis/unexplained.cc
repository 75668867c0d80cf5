#include "diagnosis/unexplained.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "rotorid/model/parameters.h"

namespace rotorid::internal {

namespace {

// The band with the largest share of the final model's residual energy in `component`.
void PlaceInBand(const GapLocation& where, UnexplainedResidual* u) {
  const int j = u->component;
  double total = 0.0;
  for (const BandGap& band : where.bands) total += band.final_residual_rms[j] * band.final_residual_rms[j];
  if (!(total > 0.0)) return;
  const auto largest = std::max_element(
      where.bands.begin(), where.bands.end(),
      [j](const BandGap& a, const BandGap& b) { return a.final_residual_rms[j] < b.final_residual_rms[j]; });
  u->band_low_hz = largest->low_hz;
  u->band_high_hz = largest->high_hz;
  u->band_share_pct = 100.0 * largest->final_residual_rms[j] * largest->final_residual_rms[j] / total;
}

}  // namespace

std::string UnexplainedNote(int component) {
  constexpr const char* kOr = "an external force (tether, payload, contact, wind) or an effect rotorid does not model";
  if (component < 2) return std::string("a force off the thrust axis that no sensor effect reproduces: ") + kOr;
  if (component == 2)
    return std::string(
               "a force along the thrust axis that no candidate reproduces (a thrust that is not kt Omega^2): ") +
           kOr;
  return std::string("a moment that no candidate reproduces: ") + kOr +
         " (an external force off the centre of mass, aerodynamics, a flexible frame)";
}

std::vector<UnexplainedResidual> FindUnexplained(const HeldOutGap& baseline, const HeldOutGap& final_gap,
                                                 const GapLocation& where, const DiagnosisOptions& options) {
  std::vector<UnexplainedResidual> out;
  for (int j = 0; j < kNumWrenchComponents; ++j) {
    // Not scored (no rotor term in the linear model, Mz with kd discarded): the noise floor comes from
    // the baseline's parameters, without the rotor speeds' noise through kd, and is no floor for a
    // final model that brought kd back (independent A_imu_lever_arm: Mz 35 % "against" 1.9 %).
    if (!baseline.gap_pct[j]) continue;
    const std::optional<double>&gap = final_gap.gap_pct[j], &floor = final_gap.noise_floor_pct[j],
          &model_error = final_gap.model_error_pct[j];
    if (!gap || !floor || !model_error || !(*floor > 0.0)) continue;
    if (*gap < options.unexplained_floor_ratio * *floor || *model_error < options.unexplained_min_pct) continue;
    UnexplainedResidual u;
    u.component = j;
    u.gap_pct = *gap;
    u.noise_floor_pct = *floor;
    u.share_pct = 100.0 * (*model_error * *model_error) / (*gap * *gap);
    PlaceInBand(where, &u);
    for (const FlightStretch& stretch : where.worst_stretches)
      if (stretch.dominant_component == j) {
        u.stretch = stretch;
        break;
      }
    u.note = UnexplainedNote(j);
    out.push_back(std::move(u));
  }
  std::sort(out.begin(), out.end(), [](const UnexplainedResidual& a, const UnexplainedResidual& b) {
    return a.gap_pct * a.gap_pct - a.noise_floor_pct * a.noise_floor_pct >
           b.gap_pct * b.gap_pct - b.noise_floor_pct * b.noise_floor_pct;
  });
  return out;
}

std::string UnexplainedSentence(const UnexplainedResidual& u) {
  std::ostringstream out;
  out << std::fixed << kWrenchComponentNames[u.component] << " " << std::setprecision(2) << u.gap_pct
      << " % held out against a noise floor of " << u.noise_floor_pct << " % (" << std::setprecision(0) << u.share_pct
      << " % of its residual beyond it)";
  if (u.band_share_pct > 0.0)
    out << ", mostly at " << u.band_low_hz << "-" << u.band_high_hz << " Hz (" << u.band_share_pct << " %)";
  if (u.stretch)
    out << ", worst in " << u.stretch->flight << " " << std::setprecision(1) << u.stretch->start_s << "-"
        << u.stretch->end_s << " s";
  out << ": " << u.note;
  return out.str();
}

std::string UnexplainedText(const std::vector<UnexplainedResidual>& unexplained) {
  if (unexplained.empty()) return "unexplained: nothing far above the noise floor\n";
  std::string out;
  for (const UnexplainedResidual& u : unexplained) out += "unexplained: " + UnexplainedSentence(u) + "\n";
  return out;
}

}  // namespace rotorid::internal

#pragma once

// The plausibility checks (rotorid/ident/checks.h) of refinement and delay results: the refined
// parameters, effects that are not finite or end on the bound of their range, Table III.

#include <string>
#include <vector>

#include "rotorid/ident/checks.h"
#include "rotorid/refine/delay.h"
#include "rotorid/refine/refine.h"
#include "rotorid/signal/butterworth.h"

namespace rotorid {

// The refined parameters as the checks read them. Without a covariance (not asked for, as in ablation,
// or a rank-deficient joint Jacobian: a delay and a lag both near zero are the same to first order)
// every std is 0 meaning "not known", not "exactly determined".
CheckedParameters CheckedFromRefinement(const IdentificationResult& linear, const RefineResult& refined);

// `label` names the model in the messages ("refined", "delay,motor_lag", ...). Effects on their
// bounds are the ones Refine reported (RefineResult::on_bound): an error by default, since a value
// the bound clipped is not an estimate; ablation, which compares subsets, passes kWarning.
std::vector<Check> CheckRefinement(const IdentificationResult& linear, const RefineResult& refined,
                                   const std::string& label = "refined",
                                   CheckStatus on_bound_status = CheckStatus::kError);
// The linear step's errors that an effect the linear model lacks gives, where the refined model
// passes: Table III above 100 % (an IMU lever arm's centripetal acceleration on a yaw spin: 763-988 %
// in roll and pitch) when every refined error is within 100 %, and a parameter check the refined
// parameters pass (ExcuseLinearParameterErrors: a non-physical inertia). Each such check of `checks`
// becomes a warning that says so, and the refined model's own checks decide the exit.
void ExcuseLinearErrorsTheRefinementExplains(const IdentificationResult& linear, const RefineResult& refined,
                                             std::vector<Check>* checks);

// The low-pass filter at half `filter`'s cut-off, and the identification of `full`'s flights
// low-passed further through it (with the options `full` was made with; throws rotorid::Error).
ButterworthOptions HalfCutoff(const ButterworthOptions& filter);
IdentificationResult IdentifyAtHalfCutoff(const IdentificationResult& full, const IdentifyOptions& identify);

// A timing effect (EffectDescriptor::Info::checked_at_half_cutoff) refined at the low-pass cut-off
// and again at half of it: both values ("<at the cut-off> at the 10 Hz cut-off, <at half> at 5 Hz")
// and whether it holds. A true delay or lag acts at every frequency and stays (a simulated 10 ms delay
// reads 11.0 +- 0.1 ms at 10 Hz, 10.2 +- 0.1 at 5 Hz), one the controller's reply to sensor noise
// fakes lives between the two cut-offs (a clean take-off flight: 1.06 +- 0.13 ms at 10 Hz, 0.07 +-
// 0.06 at 4 Hz). It holds when every coordinate is significant at half the cut-off (3 std) and at
// least half its size at the cut-off; `kBetweenTheCutoffs` says why one that does not is no timing.
struct HalfCutoffComparison {
  bool holds = false;
  std::string values;
};
HalfCutoffComparison CompareAtHalfCutoff(EffectKind kind, const RefineResult& at_cutoff, const RefineResult& at_half,
                                         double cutoff_hz);
inline constexpr const char* kBetweenTheCutoffs =
    "what it fits lies between the two cut-offs, where the rotor signal of a closed-loop flight follows the "
    "controller's reply to sensor noise";

// The refinement's timing effects refined again, started at their values, on `linear`'s flights
// low-passed further to half the cut-off (`identify`: the options `linear` was made with): check
// "timing_at_half_cutoff", a warning naming those that do not hold (CompareAtHalfCutoff), ok with
// both values when all hold; nothing when no timing effect is refined significantly (3 std).
std::vector<Check> CheckTimingAtHalfCutoff(const IdentificationResult& linear, const IdentifyOptions& identify,
                                           const RefineResult& refined, const RefineOptions& options);

std::vector<Check> CheckDelay(const IdentificationResult& linear, const DelayEstimate& estimate,
                              const DelayOptions& options);

}  // namespace rotorid

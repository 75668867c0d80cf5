#pragma once

// The effect selection of the diagnosis (internal), in the order Diagnose runs it: screening of the
// candidates by the criterion linearised at the current model, forward selection on held-out data,
// backward elimination of effects made redundant by later ones, and the held-out gap after each
// kept effect. Models are refined in the folds through a ModelFitter, so that the selection logic
// can be tested on hand-made held-out gaps.

#include <Eigen/Core>
#include <chrono>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "diagnosis/held_out.h"
#include "diagnosis/linearization.h"
#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/ident/identify.h"
#include "rotorid/model/effects.h"

namespace rotorid::internal {

// Held-out shrinks closer than this fraction of the larger one are the same fit in practice.
inline constexpr double kPracticalEquivalence = 0.1;

// A set of effects, one bit per registry index (EffectDescriptor::index).
using EffectMask = unsigned;
EffectMask Bit(EffectKind kind);
bool Has(EffectMask mask, EffectKind kind);
std::vector<EffectKind> KindsOf(EffectMask mask);  // in registry order
EffectMask MaskOf(const std::vector<EffectKind>& kinds);
// "delay, motor_lag", or "none".
std::string Join(const std::vector<EffectKind>& kinds);

// One model (a set of effects) fitted in every fold, and its held-out residual.
struct ModelRecord {
  EffectMask mask = 0;
  bool ok = true;
  std::string error;
  std::vector<Effects> fold_effects;
  std::vector<std::map<std::string, double>> fold_parameters;
  HeldOutResidual held_out;
  HeldOutGap gap;
};

// The mean over the folds of one effect of a model, and of all of them.
Eigen::VectorXd MeanFoldEffect(const ModelRecord& record, EffectKind kind);
Effects MeanFoldEffects(const ModelRecord& record);

// Refines models in every fold, each from its own start per fold (initial[m][k]), and scores them
// on the held-out rows; a failed model comes back with ok = false.
class ModelFitter {
 public:
  virtual ~ModelFitter() = default;
  virtual std::vector<ModelRecord> Fit(const std::vector<EffectMask>& masks,
                                       const std::vector<std::vector<Effects>>& initial) = 0;
};

// Two timing effects (EffectDescriptor::Info::checked_at_half_cutoff: a delay and a motor lag) that
// removed practically the same held-out residual, refined together with the final model's other
// effects on the flights low-passed to half the cut-off. Between the two cut-offs the rotor signal
// of a closed-loop flight follows the controller's reply to sensor noise, which blurs a lag's shape
// into a delay's (a simulated 20 ms lag refined together with a delay: 16.8 + 3.1 ms at 10 Hz,
// 20.1 + -0.1 ms at 5 Hz); below it the two separate.
struct TimingSeparation {
  // The one the joint fit keeps: significant (3 std), while the other is neither significant nor
  // more than a tenth of the two's sum. Null: both carry a share (a mix of the two, or neither pure).
  EffectKind decided = nullptr;
  std::string values;  // "delay = 0.52 +- 0.19 ms, motor_lag = 19.5 +- 0.2 ms"
  double cutoff_hz = 0.0;
};

// What the selection steps share: the options (candidates: the available ones), the models refined
// so far by effect set (0: the linear model), the fitter that refines more, the warnings, and the
// vehicle (per-rotor effects' sizes, the physical ranges).
struct SelectionContext {
  const DiagnosisOptions& options;
  ModelFitter& fitter;
  std::vector<std::string>& warnings;
  std::map<EffectMask, ModelRecord> records;
  const Vehicle& vehicle;
};

// Refines the models of `masks` that are not refined yet, warm-started from the fold fits of
// `from` without the effects they lack. A failed refinement leaves a warning and no record.
void EnsureFitted(SelectionContext* context, const std::vector<EffectMask>& masks, EffectMask from);

// Wall time of the diagnosis' phases, appended in order.
class PhaseTimer {
 public:
  explicit PhaseTimer(std::vector<std::pair<std::string, double>>* phase_seconds);
  // Records the time since the previous mark (or the start) as `phase`.
  void Mark(const std::string& phase);
  double SecondsSinceStart() const;

 private:
  using Clock = std::chrono::steady_clock;
  std::vector<std::pair<std::string, double>>* phase_seconds_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point phase_start_ = start_;
};

// The linear model on all identification data, around which the screening linearises.
struct AllDataModel {
  const IdentificationResult& linear;
  std::map<std::string, double> parameters;  // NamedParameters of its solution (discarded: 0)
  std::map<std::string, double> predicted;   // and of what it predicts with (PredictionChi)
  std::vector<std::string> free_parameters;  // its estimated parameters (EstimatedParameterNames)
};

// A candidate as the forward selection last screened or tested it.
struct TestedCandidate {
  int step = 0;         // 1-based
  EffectMask base = 0;  // the effects selected before that step
  EffectTest test;      // refined in the folds on top of `base`; else the screening test
  EffectTest screening;
  std::optional<EffectTest> alone;   // the test at step 1, on top of the linear model
  Eigen::VectorXd linearized_value;  // one Gauss-Newton step on top of the base model
  Eigen::VectorXd linearized_std;    // its std there
  Effects linearized_step;           // that step for every effect of the model (base and candidate)
  // Significant when refined, but with a value outside its physical range
  // (EffectDescriptor::Implausible): which value and range; or one too small to matter
  // (EffectDescriptor::Negligible). Either way never selected, not tested again.
  std::string implausible;
  std::string negligible;
  // Significant when refined at `step`, but a scored held-out component got worse beyond its noise
  // (WorsenedComponents) over the base model or the linear one: which and by how much. Not selected
  // at that step; tested again on top of the next one.
  std::string worsens;
  // A kept timing effect refitted at half the low-pass cut-off, where it held: both values.
  std::string held_at_half_cutoff;
  bool Rejected() const { return !implausible.empty() || !negligible.empty(); }
  // Sets `implausible` (outside the physical range, or `on_bound`: a bound of its refinement clipped
  // it) or else `negligible` (below the size that matters) for this estimate; returns Rejected().
  bool Judge(EffectKind kind, const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev, const Vehicle& vehicle,
             bool on_bound);
};
using TestedCandidates = std::map<EffectKind, TestedCandidate, EffectOrder>;

// The values a strongly nonlinear scalar effect is screened over: its descriptor's grid, or for a
// grid-searched one the search range in steps of 10 ms; empty for the others.
std::vector<double> ScreeningGrid(EffectKind kind, const DiagnosisOptions& options);

// Screening at forward step `step` on top of the effects `selected` (fitted in the folds as
// `base`): every remaining candidate's first-order in-sample test, with the best shrink over its
// screening grid for nonlinear ones, goes into `tested`. Returns the candidates worth refining in
// the folds (CandidatesWorthRefining).
std::vector<EffectKind> ScreenCandidates(const AllDataModel& all_data, const DiagnosisOptions& options, int step,
                                         EffectMask selected, const ModelRecord& base,
                                         const std::vector<EffectKind>& remaining, TestedCandidates* tested);

// An effect removes less residual out of sample than in sample: a candidate whose screening shrink
// is below screen_fraction of the shrink floor, or below rival_fraction of the best candidate's,
// cannot pass and is not refined at this step.
std::vector<EffectKind> CandidatesWorthRefining(const std::vector<EffectKind>& remaining,
                                                const TestedCandidates& tested, const DiagnosisOptions& options);

// A forward step that added an effect: the step, and every candidate refined in the folds at that
// step (the added one included, in candidate order) with its test on top of the same base.
struct ForwardStep {
  EffectMask base = 0;  // the effects selected before it
  SelectionStep selection;
  std::vector<std::pair<EffectKind, EffectTest>> refined;
  // A timing effect tied with the added one on the held-out rows, and what the final model's joint
  // fit at half the cut-off made of the two (SwapTimingTwin: it may have put the twin in its place).
  EffectKind timing_twin = nullptr;
  EffectTest timing_twin_test;  // its test at this step, on top of `base`
  std::optional<TimingSeparation> timing_separation;
};

// Puts the step's timing twin in place of the added effect (refined on the same base at that step),
// with `separation`, which decided for it.
void SwapTimingTwin(const SelectionContext& context, const TimingSeparation& separation, ForwardStep* step);

struct ForwardSelection {
  std::vector<EffectKind> selected;  // in the order added
  std::vector<ForwardStep> steps;
  TestedCandidates tested;
  double initial_delay_s = 0.0;  // coarse delay search (0 when no rotor-signal candidate was refined)
};

// Forward selection: at each step the screened candidates are refined on top of the effects
// selected so far; the one with the smallest held-out residual among those whose fold-mean value is
// physically plausible is kept while its F-test is significant, up to options.max_effects. A timing
// effect that ties with the added one is noted as its twin (ForwardStep::timing_twin). A
// significant candidate with an implausible or negligible value is marked (TestedCandidate::implausible,
// ::negligible) and left out of the later steps.
ForwardSelection SelectForward(SelectionContext* context, const AllDataModel& all_data, PhaseTimer* timer);

// Selected by the forward selection, then not significant on top of `others`.
struct DroppedEffect {
  EffectKind kind = nullptr;
  EffectMask others = 0;
  EffectTest test;
};

struct BackwardElimination {
  std::vector<EffectKind> kept;  // in the order added
  std::vector<DroppedEffect> dropped;
};

// Backward elimination: an effect selected early can become redundant once later ones are in (an
// acc bias standing in for a misalignment while a large lag dominated the residual). Each kept
// effect, earliest first, is tested on top of all the others; the first that is not significant is
// dropped and the pass restarts. Models on top of which an effect is tested are refined as needed.
BackwardElimination EliminateBackward(SelectionContext* context, const std::vector<EffectKind>& selected);

// The held-out gap after each kept effect, on top of the kept effects added before it; stops at a
// model whose refinement failed.
std::vector<SelectionStep> GapAfterEachEffect(SelectionContext* context, const std::vector<EffectKind>& kept);

}  // namespace rotorid::internal

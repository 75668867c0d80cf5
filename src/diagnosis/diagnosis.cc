#include "rotorid/diagnosis/diagnosis.h"

#include <algorithm>
#include <array>
#include <mutex>
#include <optional>

#include "core/parallel_for.h"
#include "diagnosis/confounding.h"
#include "diagnosis/held_out.h"
#include "diagnosis/linearization.h"
#include "diagnosis/scale_free.h"
#include "diagnosis/selection.h"
#include "diagnosis/unexplained.h"
#include "diagnosis/verdict_text.h"
#include "diagnosis/verdicts.h"
#include "rotorid/core/error.h"
#include "rotorid/model/parameters.h"
#include "rotorid/refine/refine.h"
#include "rotorid/refine/refine_checks.h"

namespace rotorid {

std::vector<EffectKind> DiagnosisCandidates() {
  std::vector<EffectKind> kinds = DefaultCandidates();
  for (const char* name : {"rotor_thrust_scale", "imu_lever_arm"}) {
    const EffectKind kind = ParseEffectKind(name);
    if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end()) kinds.push_back(kind);
  }
  return kinds;
}

std::string DiagnosisOptions::Validate() const {
  if (const std::string problem = identify.Validate(); !problem.empty()) return problem;
  // Its folds and held-out flights would each need a first moment of their own.
  if (identify.first_moment == FirstMoment::kPerFlight) return "the diagnosis takes shared first moments only";
  if (const std::string problem = location.Validate(); !problem.empty()) return problem;
  for (size_t a = 0; a < candidates.size(); ++a)
    for (size_t b = a + 1; b < candidates.size(); ++b)
      if (candidates[a] == candidates[b])
        return std::string("candidate effect '") + EffectName(candidates[a]) + "' is listed twice";
  if (folds < 2) return "folds must be at least 2, got " + std::to_string(folds);
  if (!(guard_s >= 0.0)) return "guard_s must not be negative";
  if (!(alpha > 0.0 && alpha < 1.0)) return "alpha must lie in (0, 1)";
  if (!(min_shrink_pct >= 0.0 && min_shrink_pct < 100.0)) return "min_shrink_pct must lie in [0, 100)";
  if (max_effects < 0) return "max_effects must not be negative";
  if (!(screen_fraction >= 0.0 && screen_fraction <= 1.0)) return "screen_fraction must lie in [0, 1]";
  if (!(rival_fraction >= 0.0 && rival_fraction <= 1.0)) return "rival_fraction must lie in [0, 1]";
  if (!(max_component_growth_pct >= 0.0)) return "max_component_growth_pct must not be negative";
  if (!(component_growth_alpha > 0.0 && component_growth_alpha < 1.0))
    return "component_growth_alpha must lie in (0, 1)";
  if (!(unexplained_floor_ratio >= 1.0)) return "unexplained_floor_ratio must be at least 1";
  if (!(unexplained_min_pct >= 0.0)) return "unexplained_min_pct must not be negative";
  if (const std::string problem = delay_search.Validate(); !problem.empty()) return problem;
  if (refine_max_iterations < 1) return "refine_max_iterations must be at least 1";
  if (num_threads < 1) return "num_threads must be at least 1";
  return {};
}

namespace {

using internal::EffectMask;
using internal::FlightResidual;
using internal::HeldOutResidual;
using internal::KindsOf;
using internal::ModelRecord;
using internal::ParallelFor;

// The work shared by all steps: folds, their linear fits, and the refinement settings.
class HeldOutEvaluator : public internal::ModelFitter {
 public:
  HeldOutEvaluator(const DiagnosisOptions& options, std::vector<internal::Fold> folds,
                   std::vector<IdentificationResult> fold_linear, int num_evaluation_flights,
                   const DiagnosisProgress& progress)
      : options_(options),
        folds_(std::move(folds)),
        fold_linear_(std::move(fold_linear)),
        num_evaluation_flights_(num_evaluation_flights),
        progress_(progress) {}

  int num_folds() const { return static_cast<int>(folds_.size()); }
  const std::vector<internal::Fold>& folds() const { return folds_; }
  int refinements() const { return refinements_; }
  const internal::HeldOutScales& scales() const { return scales_; }

  ModelRecord Baseline() {
    ModelRecord record;
    for (int k = 0; k < num_folds(); ++k) {
      record.fold_effects.push_back(Effects{});
      record.fold_parameters.push_back(
          NamedParameters(fold_linear_[k].system, PredictionChi(fold_linear_[k].solution)));
    }
    EvaluateHeldOut(&record);
    scored_.clear();
    for (const FlightResidual& segment : record.held_out.segments) {
      std::array<bool, kNumWrenchComponents> scored;
      for (int j = 0; j < kNumWrenchComponents; ++j)
        scored[j] = j < 2 || segment.rotor_wrench.col(j).squaredNorm() > 0.0;
      scored_.push_back(scored);
    }
    record.held_out.scored = scored_;
    scales_ = internal::BaselineScales(record.held_out, num_evaluation_flights_);
    // The noise floor barely depends on the fitted parameters: the baseline's serves every model.
    noise_sq_.setZero();
    for (int k = 0; k < num_folds(); ++k)
      for (const ProcessedFlight& flight : folds_[k].evaluate)
        noise_sq_ += internal::NoiseResidualSquares(flight, record.fold_parameters[k]);
    record.gap = internal::ScoreHeldOut(record.held_out, scales_, noise_sq_);
    return record;
  }

  // A model's held-out gap with the noise floor of its own fitted parameters. The baseline's floor
  // serves the selection, but where the linear model's coefficients are far off it is no floor for
  // the final model: A on a circle with rotor drag and a lever arm, Mz's floor 26 % of the baseline's
  // rotor moment against 4 % of the final model's, whose gap of 25 % is then at its floor.
  HeldOutGap ScoreWithOwnNoiseFloor(const ModelRecord& record) const {
    ComponentVector noise_sq = ComponentVector::Zero();
    for (int k = 0; k < num_folds(); ++k)
      for (const ProcessedFlight& flight : folds_[k].evaluate)
        noise_sq += internal::NoiseResidualSquares(flight, record.fold_parameters[k]);
    return internal::ScoreHeldOut(record.held_out, scales_, noise_sq);
  }

  // Fits each model in every fold (in parallel), starting from `initial[m][k]`.
  std::vector<ModelRecord> Fit(const std::vector<EffectMask>& masks,
                               const std::vector<std::vector<Effects>>& initial) override {
    const int folds = num_folds();
    std::vector<ModelRecord> records(masks.size());
    for (size_t m = 0; m < masks.size(); ++m) {
      records[m].mask = masks[m];
      records[m].fold_effects.resize(folds);
      records[m].fold_parameters.resize(folds);
    }
    std::vector<std::string> errors(masks.size() * folds);
    StartBatch(static_cast<int>(masks.size()));
    ParallelFor(static_cast<int>(masks.size()) * folds, options_.num_threads, [&](int task) {
      const int m = task / folds, k = task % folds;
      try {
        RefineOptions refine;
        refine.effects = KindsOf(masks[m]);
        refine.initial = initial[m][k];
        refine.coarse_delay_search = false;           // started from the diagnosis' own search
        refine.delay_search = options_.delay_search;  // which also bounds the delay
        refine.compute_covariance = false;            // std come from the linearisation
        refine.max_iterations = options_.refine_max_iterations;
        refine.num_threads = 1;  // parallel over models and folds instead
        refine.reselect_essential = options_.reselect_essential;
        const RefineResult result = Refine(fold_linear_[k], refine);
        records[m].fold_effects[k] = result.effects;
        records[m].fold_parameters[k] = NamedParameters(fold_linear_[k].system, PredictionChi(result.refined));
      } catch (const std::exception& e) {
        errors[task] = e.what();
      }
      Report();
    });
    for (size_t m = 0; m < masks.size(); ++m) {
      for (int k = 0; k < folds; ++k)
        if (!errors[m * folds + k].empty()) {
          records[m].ok = false;
          records[m].error = "fold " + std::to_string(k + 1) + ": " + errors[m * folds + k];
        }
      if (!records[m].ok) continue;
      EvaluateHeldOut(&records[m]);
      records[m].held_out.scored = scored_;
      records[m].gap = internal::ScoreHeldOut(records[m].held_out, scales_, noise_sq_);
    }
    return records;
  }

 private:
  void EvaluateHeldOut(ModelRecord* record) const {
    record->held_out = HeldOutResidual{};
    for (int k = 0; k < num_folds(); ++k) {
      const internal::Fold& fold = folds_[k];
      for (size_t e = 0; e < fold.evaluate.size(); ++e) {
        record->held_out.flight.push_back(fold.evaluate_flight[e]);
        record->held_out.segments.push_back(
            internal::ResidualOf(fold.evaluate[e], record->fold_parameters[k], record->fold_effects[k]));
      }
    }
  }

  void StartBatch(int models) {
    batch_label_ = "fitting " + std::to_string(models) + (models == 1 ? " model in " : " models in ") +
                   std::to_string(num_folds()) + (num_folds() == 1 ? " fold" : " folds");
    batch_total_ = models * num_folds();
    batch_done_ = 0;
    if (progress_) progress_(batch_label_, 0, batch_total_);
  }

  void Report() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++refinements_;
    if (progress_) progress_(batch_label_, ++batch_done_, batch_total_);
  }

  const DiagnosisOptions& options_;
  std::vector<internal::Fold> folds_;
  std::vector<IdentificationResult> fold_linear_;
  int num_evaluation_flights_ = 0;
  const DiagnosisProgress& progress_;
  internal::HeldOutScales scales_;
  ComponentVector noise_sq_ = ComponentVector::Zero();
  std::vector<std::array<bool, kNumWrenchComponents>> scored_;
  std::mutex mutex_;
  int refinements_ = 0;
  std::string batch_label_;
  int batch_done_ = 0, batch_total_ = 0;
};

// The verdict of a candidate whose inputs a log lacks (velocity, voltage, ...): unavailable for
// these logs, with the reason. None when every flight can carry it.
std::optional<EffectVerdict> UnavailableVerdict(EffectKind kind, const std::vector<ProcessedFlight>& flights) {
  std::string reason;
  for (size_t f = 0; f < flights.size() && reason.empty(); ++f)
    if (const std::string why = kind->Unavailable(flights[f].inputs()); !why.empty())
      reason = flights[f].source + ": " + why + "; not a candidate";
  // One value per rotor: the folds and the linearisation give every flight the same parameters.
  const Vehicle& vehicle = flights.front().vehicle;
  for (size_t f = 1; f < flights.size() && reason.empty(); ++f)
    if (kind->Dimension(flights[f].vehicle) != kind->Dimension(vehicle))
      reason = flights[f].source + ": " + kind->name() + " has one value per rotor, and this flight's vehicle has " +
               std::to_string(flights[f].vehicle.num_rotors()) + " rotors, " + flights.front().source + "'s " +
               std::to_string(vehicle.num_rotors()) + "; not a candidate";
  if (reason.empty()) return std::nullopt;
  EffectVerdict v;
  v.kind = kind;
  v.status = "unavailable";
  v.value = Eigen::VectorXd::Zero(kind->Dimension(vehicle));
  v.note = reason;
  return v;
}

// Whether the held-out score leaves a component out: one without rotor term in the linear model
// (Mz when kd is discarded), whose Table III error is then undefined.
bool HasUnscoredComponent(const HeldOutGap& baseline) {
  for (int j = 2; j < kNumWrenchComponents; ++j)
    if (!baseline.relative_error_pct[j]) return true;
  return false;
}

// Where the models are judged: the held-out folds or flights, the linear model fitted on the
// training data of each, and how the validation is described.
struct HeldOutData {
  std::vector<internal::Fold> folds;
  std::vector<IdentificationResult> fold_linear;
  int num_evaluation_flights = 0;
  std::string validation;
};

// Time-blocked folds of the identification flights, each with its linear fit.
HeldOutData TimeBlockedHeldOut(const std::vector<ProcessedFlight>& flights, const DiagnosisOptions& options) {
  HeldOutData data;
  data.folds = internal::TimeBlockedFolds(flights, options.folds, options.guard_s);
  data.fold_linear.resize(data.folds.size());
  std::vector<std::string> errors(data.folds.size());
  ParallelFor(static_cast<int>(data.folds.size()), options.num_threads, [&](int k) {
    try {
      data.fold_linear[k] = IdentifyProcessed(data.folds[k].train, options.identify);
    } catch (const std::exception& e) {
      errors[k] = e.what();
    }
  });
  for (size_t k = 0; k < errors.size(); ++k)
    if (!errors[k].empty())
      throw Error("held-out fold " + std::to_string(k + 1) + " of " + std::to_string(data.folds.size()) +
                  ": the linear model cannot be identified without that block (" + errors[k] +
                  "); use fewer folds or held-out flights");
  data.num_evaluation_flights = static_cast<int>(flights.size());
  data.validation = std::to_string(options.folds) + " time-blocked folds of " + std::to_string(flights.size()) +
                    (flights.size() == 1 ? " flight" : " flights");
  return data;
}

// The given held-out flights, with the linear model fitted on all identification data.
HeldOutData GivenHeldOut(const IdentificationResult& full, const std::vector<ProcessedFlight>& flights,
                         const std::vector<ProcessedFlight>& held_out) {
  for (const ProcessedFlight& f : held_out)
    if (std::find(full.system.config_names.begin(), full.system.config_names.end(), f.vehicle.name) ==
        full.system.config_names.end())
      throw Error(f.source + ": held-out flight of configuration '" + f.vehicle.name +
                  "', which none of the identification flights has");
  HeldOutData data;
  internal::Fold fold;
  fold.train = flights;
  fold.evaluate = held_out;
  for (size_t e = 0; e < held_out.size(); ++e) fold.evaluate_flight.push_back(static_cast<int>(e));
  data.folds.push_back(std::move(fold));
  data.fold_linear.push_back(full);
  data.num_evaluation_flights = static_cast<int>(held_out.size());
  data.validation = std::to_string(held_out.size()) + (held_out.size() == 1 ? " held-out flight" : " held-out flights");
  return data;
}

// The effects refined on all identification data from `initial` (the mean of their fold fits).
RefineResult RefineOnAllData(const IdentificationResult& full, const std::vector<EffectKind>& effects,
                             const Effects& initial, const DiagnosisOptions& options) {
  RefineOptions refine;
  refine.effects = effects;
  refine.initial = initial;
  refine.coarse_delay_search = false;
  refine.delay_search = options.delay_search;
  refine.num_threads = options.num_threads;  // with the covariance: the physical checks need the std
  return Refine(full, refine);
}

// The identification flights low-passed further, to half the cut-off, and identified there; made on
// first use and shared by the final model's timing checks (Get throws rotorid::Error when it fails).
class HalfCutoffIdentification {
 public:
  HalfCutoffIdentification(const IdentificationResult& full, const DiagnosisOptions& options)
      : full_(full), options_(options) {}
  const IdentificationResult& Get() {
    if (!identified_) identified_ = IdentifyAtHalfCutoff(full_, options_.identify);
    return *identified_;
  }

 private:
  const IdentificationResult& full_;
  const DiagnosisOptions& options_;
  std::optional<IdentificationResult> identified_;
};

// A kept timing effect and its twin (ForwardStep::timing_twin) refined together with the other kept
// effects at half the cut-off (internal::TimingSeparation), each started at half the kept one's value:
// the fit then slides along the line of their sum to where their shapes fit. Nullopt, with a
// warning, when it fails.
std::optional<internal::TimingSeparation> SeparateTimingAtHalfCutoff(HalfCutoffIdentification* at_half,
                                                                     internal::SelectionContext* context,
                                                                     const std::vector<EffectKind>& kept,
                                                                     const Effects& final_effects, EffectKind selected,
                                                                     EffectKind other) {
  Effects initial = final_effects;
  const Eigen::VectorXd half_value = 0.5 * final_effects.Get(selected);
  initial.Set(selected, half_value);
  initial.Set(other, half_value);
  std::vector<EffectKind> model = kept;
  model.push_back(other);
  RefineResult joint;
  try {
    joint = RefineOnAllData(at_half->Get(), model, initial, context->options);
  } catch (const Error& e) {
    context->warnings.push_back(std::string(EffectName(selected)) + " and " + EffectName(other) +
                                " were not refined together at half the cut-off (" + e.what() + ")");
    return std::nullopt;
  }
  internal::TimingSeparation separation;
  separation.cutoff_hz = HalfCutoff(context->options.identify.observation.filter).cutoff_hz;
  separation.values = std::string(EffectName(selected)) + " = " +
                      selected->Format(joint.effects.Get(selected), joint.effects_std.Get(selected)) + ", " +
                      EffectName(other) + " = " + other->Format(joint.effects.Get(other), joint.effects_std.Get(other));
  if (joint.effects_std.Get(selected).size() != 1 || joint.effects_std.Get(other).size() != 1) return separation;
  // Timing effects are scalars in seconds: their values add up to the delay the two share.
  const double a = joint.effects.Scalar(selected), b = joint.effects.Scalar(other);
  const double sa = joint.effects_std.Scalar(selected), sb = joint.effects_std.Scalar(other);
  // Near tau = 0 a lag is a delay to first order: a pure delay's joint fit has a std of 1-3 ms and can
  // lean a quarter of it into the lag (a 5 ms delay: 1.2 +- 1.1 + 3.8 +- 1.1 ms), so the other one
  // must be both insignificant and small.
  auto carries = [](double value, double std_dev, double rival, double rival_std) {
    return std::abs(value) >= 3.0 * std_dev && std::abs(rival) < 3.0 * rival_std &&
           std::abs(rival) < 0.1 * (std::abs(value) + std::abs(rival));
  };
  if (carries(a, sa, b, sb)) separation.decided = selected;
  if (carries(b, sb, a, sa)) separation.decided = other;
  return separation;
}

// The first kept timing effect (EffectDescriptor::Info::checked_at_half_cutoff) that does not hold
// at half the low-pass cut-off (CompareAtHalfCutoff), marked implausible in `tested`; nullopt when all
// hold (each then carries both values in `held_at_half_cutoff`, for its verdict). The kept model is
// refined again on the flights low-passed further to half the cut-off.
std::optional<EffectKind> TimingEffectNotHoldingAtHalfCutoff(HalfCutoffIdentification* half_cutoff,
                                                             const std::vector<EffectKind>& kept,
                                                             const RefineResult& at_cutoff,
                                                             internal::SelectionContext* context,
                                                             internal::TestedCandidates* tested) {
  std::vector<EffectKind> checked;
  for (EffectKind kind : kept)
    if (kind->info().checked_at_half_cutoff) checked.push_back(kind);
  if (checked.empty()) return std::nullopt;
  RefineResult at_half;
  try {
    at_half = RefineOnAllData(half_cutoff->Get(), kept, at_cutoff.effects, context->options);
  } catch (const Error& e) {
    context->warnings.push_back("the timing effects were not checked at half the cut-off (" + std::string(e.what()) +
                                ")");
    return std::nullopt;
  }
  for (EffectKind kind : checked) {
    const HalfCutoffComparison comparison =
        CompareAtHalfCutoff(kind, at_cutoff, at_half, context->options.identify.observation.filter.cutoff_hz);
    if (comparison.holds) {
      (*tested)[kind].held_at_half_cutoff = "holds at half the low-pass cut-off (" + comparison.values + ")";
      continue;
    }
    (*tested)[kind].implausible = comparison.values + ": " + kBetweenTheCutoffs;
    return kind;
  }
  return std::nullopt;
}

// Separates each kept timing effect from its twin not separated yet (SeparateTimingAtHalfCutoff) and,
// where the data at half the cut-off decide for the twin, puts it in the kept one's place, in `kept`
// and in the forward step that added it; true when it did (the final model is then refined again).
bool SeparatedTimingTwin(HalfCutoffIdentification* at_half, const Effects& final_effects,
                         internal::SelectionContext* context, std::vector<EffectKind>* kept,
                         internal::ForwardSelection* forward) {
  for (internal::ForwardStep& step : forward->steps) {
    const EffectKind added = step.selection.added;
    const auto in_kept = std::find(kept->begin(), kept->end(), added);
    if (!step.timing_twin || step.timing_separation || in_kept == kept->end()) continue;
    if (std::find(kept->begin(), kept->end(), step.timing_twin) != kept->end()) continue;
    step.timing_separation =
        SeparateTimingAtHalfCutoff(at_half, context, *kept, final_effects, added, step.timing_twin);
    if (!step.timing_separation || step.timing_separation->decided != step.timing_twin) continue;
    *in_kept = step.timing_twin;
    std::replace(forward->selected.begin(), forward->selected.end(), added, step.timing_twin);
    internal::SwapTimingTwin(*context, *step.timing_separation, &step);
    return true;
  }
  return false;
}

// The final model on all identification data and the criterion linearised there (std, detectable
// sizes). A kept effect whose final value lies outside its physical range or on a bound of its
// refinement (or below the size that matters) is marked implausible (negligible) in `tested` and
// dropped from `kept`, and the rest refined again: the fold fits can be plausible while the fit on
// all data runs off (an IMU lever arm to its 300 mm bound on top of an acc bias, a z acc bias to its
// 2 m/s^2 bound on a PWM-driven Crazyflie): a clipped value is not an estimate.
struct FinalModel {
  std::map<std::string, double> parameters;     // reported (discarded: 0)
  std::map<std::string, double> predicted;      // what it predicts with (PredictionChi)
  std::map<std::string, double> parameter_std;  // empty: not known
  Effects effects;
  internal::EffectLinearization linearization;
  internal::EffectSubsetFit kept_fit;
};
FinalModel FitFinalModel(const internal::AllDataModel& all_data, internal::SelectionContext* context,
                         std::vector<EffectKind>* kept, internal::ForwardSelection* forward) {
  internal::TestedCandidates* tested = &forward->tested;
  HalfCutoffIdentification at_half(all_data.linear, context->options);
  for (EffectMask previous = internal::MaskOf(*kept);;) {
    FinalModel model;
    model.parameters = all_data.parameters;
    model.predicted = all_data.predicted;
    model.parameter_std = NamedParameters(all_data.linear.system, all_data.linear.solution.std);
    const EffectMask mask = internal::MaskOf(*kept);
    internal::EnsureFitted(context, {mask}, previous);  // the folds warm-start the fit on all data
    if (!context->records.count(mask)) {                // its refinement failed (a warning says so): the linear model
      kept->clear();
      continue;
    }
    previous = mask;
    std::vector<EffectKind> on_bound;
    RefineResult result;
    if (mask != 0) {
      result = RefineOnAllData(all_data.linear, KindsOf(mask), internal::MeanFoldEffects(context->records.at(mask)),
                               context->options);
      model.effects = result.effects;
      model.parameters = NamedParameters(all_data.linear.system, result.refined.chi);
      model.predicted = NamedParameters(all_data.linear.system, PredictionChi(result.refined));
      model.parameter_std.clear();
      if (result.has_covariance) model.parameter_std = NamedParameters(all_data.linear.system, result.refined.std);
      on_bound = result.on_bound;
    }
    model.linearization = internal::LinearizeEffects(all_data.linear.flights, model.predicted, all_data.free_parameters,
                                                     model.effects, context->options.candidates);
    model.kept_fit = internal::FitEffectSubset(model.linearization, KindsOf(mask));
    const auto rejected = std::find_if(kept->begin(), kept->end(), [&](EffectKind kind) {
      internal::TestedCandidate& t = (*tested)[kind];
      if (!t.Judge(kind, model.effects.Get(kind), internal::EffectColumns(model.kept_fit, kind, model.kept_fit.std),
                   context->vehicle, std::find(on_bound.begin(), on_bound.end(), kind) != on_bound.end()))
        return false;
      (t.implausible.empty() ? t.negligible : t.implausible) += " (refined on all identification data)";
      return true;
    });
    if (rejected != kept->end()) {
      kept->erase(rejected);
      continue;
    }
    const std::optional<EffectKind> faked =
        TimingEffectNotHoldingAtHalfCutoff(&at_half, KindsOf(mask), result, context, tested);
    if (faked) {
      kept->erase(std::find(kept->begin(), kept->end(), *faked));
      continue;
    }
    if (!SeparatedTimingTwin(&at_half, result.effects, context, kept, forward)) return model;
  }
}

}  // namespace

Diagnosis Diagnose(const std::vector<ProcessedFlight>& flights, const std::vector<ProcessedFlight>& held_out,
                   const DiagnosisOptions& requested, const DiagnosisProgress& progress) {
  if (const std::string problem = requested.Validate(); !problem.empty()) throw Error(problem);
  if (flights.empty()) throw Error("diagnose: no identification flights");
  DiagnosisOptions options = requested;
  options.candidates.clear();
  std::vector<EffectVerdict> unavailable;  // ranked last, with the reason
  for (EffectKind kind : requested.candidates) {
    if (std::optional<EffectVerdict> v = UnavailableVerdict(kind, flights))
      unavailable.push_back(std::move(*v));
    else
      options.candidates.push_back(kind);
  }
  Diagnosis diagnosis;
  internal::PhaseTimer timer(&diagnosis.phase_seconds);
  diagnosis.candidates = options.candidates;

  // Baseline: the linear model on all identification data.
  const IdentificationResult full = IdentifyProcessed(flights, options.identify);
  diagnosis.warnings = full.warnings;
  for (const EffectVerdict& v : unavailable) diagnosis.warnings.push_back(v.note);
  diagnosis.linear_parameters = NamedParameters(full.system, full.solution.chi);
  diagnosis.linear_parameter_std = NamedParameters(full.system, full.solution.std);
  timer.Mark("linear identification");

  // Held-out data: time-blocked folds, or the given flights with the model fitted on everything.
  HeldOutData data = held_out.empty() ? TimeBlockedHeldOut(flights, options) : GivenHeldOut(full, flights, held_out);
  diagnosis.validation = data.validation;
  timer.Mark("fold identifications");
  HeldOutEvaluator evaluator(options, std::move(data.folds), std::move(data.fold_linear), data.num_evaluation_flights,
                             progress);
  internal::SelectionContext context{options, evaluator, diagnosis.warnings, {}, flights.front().vehicle};
  context.records[0] = evaluator.Baseline();
  diagnosis.baseline = context.records[0].gap;
  diagnosis.held_out_row_samples = context.records[0].held_out.row_samples();
  timer.Mark("held-out baseline");

  // Which: forward selection on held-out data, then the backward pass.
  const internal::AllDataModel all_data{full, diagnosis.linear_parameters,
                                        NamedParameters(full.system, PredictionChi(full.solution)),
                                        internal::EstimatedParameterNames(full)};
  diagnosis.linear_predicts_with = all_data.predicted;
  internal::ForwardSelection forward = internal::SelectForward(&context, all_data, &timer);
  diagnosis.initial_delay_s = forward.initial_delay_s;
  internal::BackwardElimination backward = internal::EliminateBackward(&context, forward.selected);
  if (!backward.dropped.empty()) timer.Mark("backward elimination");

  // The final model on all identification data, without kept effects that run off there; std and
  // detectable sizes from the criterion linearised at it.
  const FinalModel final_model = FitFinalModel(all_data, &context, &backward.kept, &forward);
  const internal::EffectLinearization& linearization = final_model.linearization;
  const internal::EffectSubsetFit& kept_fit = final_model.kept_fit;
  diagnosis.final_effects = final_model.effects;
  diagnosis.final_parameters = final_model.parameters;
  diagnosis.final_parameter_std = final_model.parameter_std;
  diagnosis.final_predicts_with = final_model.predicted;
  diagnosis.final_model = backward.kept;
  const EffectMask kept = internal::MaskOf(backward.kept);
  const std::vector<EffectKind> kept_kinds = KindsOf(kept);
  for (EffectKind kind : kept_kinds)
    diagnosis.final_effects_std.Set(kind, internal::EffectColumns(kept_fit, kind, kept_fit.std));
  timer.Mark("final refinement and linearisation");

  // How far: the held-out gap after each kept effect, in the order they were added.
  diagnosis.steps = internal::GapAfterEachEffect(&context, backward.kept);
  diagnosis.final_gap = evaluator.ScoreWithOwnNoiseFloor(context.records.at(kept));

  // Verdicts, confounding, notes and ranking.
  const internal::SelectionOutcome outcome{forward,       backward, diagnosis.steps, diagnosis.final_effects,
                                           linearization, kept_fit};
  std::vector<EffectVerdict> verdicts;
  for (EffectKind kind : options.candidates) verdicts.push_back(internal::VerdictOf(kind, context, outcome));
  diagnosis.confounded = internal::AnalyzeConfounding(internal::FindRivals(forward.steps, kept), context,
                                                      evaluator.scales(), linearization, kept_kinds);
  internal::MarkConfounded(diagnosis.confounded, &verdicts);
  timer.Mark("confounding");

  // A candidate acting mostly in a component the held-out score leaves out: that component's row
  // alone, scale-free. Ranked first when it passes: it explains the component the linear model gave
  // up on (it lost a rotor coefficient there), and the other tests ran on a model it distorts.
  const internal::ScaleFreeData scale_free{
      evaluator.folds(),          context.records.at(kept).fold_effects, full.flights, diagnosis.final_effects,
      diagnosis.final_parameters, diagnosis.final_parameter_std};
  if (HasUnscoredComponent(diagnosis.baseline)) {
    // Where the signatures lie, at the linear model: the held-out score leaves out what it leaves
    // without rotor term, even where the final model brought the coefficient back (a motor lag
    // restores kd, and the final linearisation then weighs Mz).
    const internal::EffectLinearization at_linear = internal::LinearizeEffects(
        full.flights, all_data.predicted, all_data.free_parameters, Effects{}, options.candidates);
    diagnosis.selected_scale_free =
        internal::SelectInUnscoredComponents(at_linear, scale_free, options, context.vehicle, &verdicts);
  }
  diagnosis.selected = diagnosis.selected_scale_free;
  diagnosis.selected.insert(diagnosis.selected.end(), backward.kept.begin(), backward.kept.end());
  timer.Mark("scale-free tests");
  for (EffectVerdict& v : verdicts) {
    v.note = internal::VerdictNote(v, options, diagnosis.final_model);
    if (const std::string product = internal::DiscardedProductStatement(v, full.solution.discarded); !product.empty())
      v.note += "; " + product;
  }
  diagnosis.ranking = internal::Rank(std::move(verdicts), diagnosis.selected, unavailable);

  // Where.
  diagnosis.where_component = internal::WhereComponent(diagnosis.baseline);
  diagnosis.where =
      LocateGap(full, final_model.predicted, diagnosis.final_effects, options.candidates, options.location);
  diagnosis.unexplained = internal::FindUnexplained(diagnosis.baseline, diagnosis.final_gap, diagnosis.where, options);
  timer.Mark("where");

  diagnosis.refinements = evaluator.refinements();
  diagnosis.seconds = timer.SecondsSinceStart();
  return diagnosis;
}

}  // namespace rotorid

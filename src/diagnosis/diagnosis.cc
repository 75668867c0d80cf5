#include "rotorid/diagnosis/diagnosis.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>
#include <thread>

#include "diagnosis/held_out.h"
#include "diagnosis/linearization.h"
#include "diagnosis/statistics.h"
#include "refine/grid_search.h"
#include "refine/parallel_for.h"
#include "rotorid/core/error.h"
#include "rotorid/model/parameters.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

std::string DiagnosisOptions::Validate() const {
  if (const std::string problem = identify.Validate(); !problem.empty()) return problem;
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
  if (!(delay_search_max_s > delay_search_min_s)) return "delay search range is empty";
  if (!(delay_search_step_s > 0.0)) return "delay search step must be positive";
  if (refine_max_iterations < 1) return "refine_max_iterations must be at least 1";
  if (num_threads < 1) return "num_threads must be at least 1";
  return {};
}

namespace {

using internal::FlightResidual;
using internal::HeldOutResidual;

constexpr int kComponents = kNumWrenchComponents;

using EffectMask = unsigned;
EffectMask Bit(EffectKind kind) { return 1u << static_cast<unsigned>(kind->index()); }
bool Has(EffectMask mask, EffectKind kind) { return (mask & Bit(kind)) != 0; }
std::vector<EffectKind> KindsOf(EffectMask mask) {
  std::vector<EffectKind> kinds;
  for (EffectKind kind : AllEffects())
    if (Has(mask, kind)) kinds.push_back(kind);
  return kinds;
}

using internal::ParallelFor;

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

// Held-out shrinks closer than this fraction of the larger one are the same fit in practice.
constexpr double kPracticalEquivalence = 0.1;

// The work shared by all steps: folds, their linear fits, and the refinement settings.
class HeldOutEvaluator {
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
  int refinements() const { return refinements_; }
  const Eigen::MatrixXd& scales() const { return scales_; }

  ModelRecord Baseline() {
    ModelRecord record;
    for (int k = 0; k < num_folds(); ++k) {
      record.fold_effects.push_back(Effects{});
      record.fold_parameters.push_back(NamedParameters(fold_linear_[k].system, fold_linear_[k].solution.chi));
    }
    EvaluateHeldOut(&record);
    scored_.clear();
    for (const FlightResidual& segment : record.held_out.segments) {
      std::array<bool, kComponents> scored;
      for (int j = 0; j < kComponents; ++j) scored[j] = j < 2 || segment.rotor_wrench.col(j).squaredNorm() > 0.0;
      scored_.push_back(scored);
    }
    record.held_out.scored = scored_;
    scales_ = internal::HeldOutScales(record.held_out, num_evaluation_flights_);
    // The noise floor barely depends on the fitted parameters: the baseline's serves every model.
    noise_sq_.setZero();
    for (int k = 0; k < num_folds(); ++k)
      for (const ProcessedFlight& flight : folds_[k].evaluate)
        noise_sq_ += internal::NoiseResidualSquares(flight, record.fold_parameters[k]);
    record.gap = internal::ScoreHeldOut(record.held_out, scales_, noise_sq_);
    return record;
  }

  // Fits each model in every fold (in parallel), starting from `initial[m][k]`.
  std::vector<ModelRecord> Fit(const std::vector<EffectMask>& masks, const std::vector<std::vector<Effects>>& initial) {
    const int folds = num_folds();
    std::vector<ModelRecord> records(masks.size());
    for (size_t m = 0; m < masks.size(); ++m) {
      records[m].mask = masks[m];
      records[m].fold_effects.resize(folds);
      records[m].fold_parameters.resize(folds);
    }
    std::vector<std::string> errors(masks.size() * folds);
    ParallelFor(static_cast<int>(masks.size()) * folds, options_.num_threads, [&](int task) {
      const int m = task / folds, k = task % folds;
      try {
        RefineOptions refine;
        refine.effects = KindsOf(masks[m]);
        refine.initial = initial[m][k];
        refine.coarse_delay_search = false;  // started from the diagnosis' own search
        refine.compute_covariance = false;   // std come from the linearisation
        refine.max_iterations = options_.refine_max_iterations;
        refine.num_threads = 1;  // parallel over models and folds instead
        refine.reselect_essential = options_.reselect_essential;
        const RefineResult result = Refine(fold_linear_[k], refine);
        records[m].fold_effects[k] = result.effects;
        records[m].fold_parameters[k] = NamedParameters(fold_linear_[k].system, result.refined.chi);
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

  void Report() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++refinements_;
    if (progress_) progress_(refinements_);
  }

  const DiagnosisOptions& options_;
  std::vector<internal::Fold> folds_;
  std::vector<IdentificationResult> fold_linear_;
  int num_evaluation_flights_ = 0;
  const DiagnosisProgress& progress_;
  Eigen::MatrixXd scales_;
  ComponentVector noise_sq_ = ComponentVector::Zero();
  std::vector<std::array<bool, kComponents>> scored_;
  std::mutex mutex_;
  int refinements_ = 0;
};

Eigen::VectorXd MeanFoldEffect(const ModelRecord& record, EffectKind kind) {
  Eigen::VectorXd sum;
  for (const Effects& e : record.fold_effects) sum = sum.size() ? Eigen::VectorXd(sum + e.Get(kind)) : e.Get(kind);
  return record.fold_effects.empty() ? sum : Eigen::VectorXd(sum / static_cast<double>(record.fold_effects.size()));
}

// "; alone, motor_lag = 25.1 ms and delay = 24.6 ms fit as well" for two scalar effects (a delay
// and a lag, say): what the data do fix is what the two values share. Empty otherwise.
std::string AloneValues(EffectKind a, const ModelRecord& with_a, EffectKind b, const ModelRecord& with_b) {
  if (a->FixedDimension() != 1 || b->FixedDimension() != 1) return "";
  return "; alone, " + std::string(EffectName(a)) + " = " + a->Format(MeanFoldEffect(with_a, a), {}) + " and " +
         EffectName(b) + " = " + b->Format(MeanFoldEffect(with_b, b), {}) +
         " fit as well: the data fix what the two share, not which of them it is";
}

Effects MeanFoldEffects(const ModelRecord& record) {
  Effects mean;
  for (EffectKind kind : KindsOf(record.mask)) mean.Set(kind, MeanFoldEffect(record, kind));
  return mean;
}

// Smallest size per parameter at which the F-test and the shrink floor would flag the effect,
// from the linearised information: a parameter of size a removes (a / std)^2 / n_eff of the
// residual.
Eigen::VectorXd DetectableSizes(const Eigen::VectorXd& std_dev, int parameters, double effective_samples,
                                const DiagnosisOptions& options) {
  const double q = parameters;
  const double n_eff = std::max(effective_samples, q + 2.0);
  const double f_critical = internal::FCritical(options.alpha, q, n_eff - q);
  const double required_shrink = std::max(options.min_shrink_pct / 100.0, q * f_critical / n_eff);
  return std_dev * std::sqrt(required_shrink * n_eff);
}

std::string Join(const std::vector<EffectKind>& kinds) {
  std::string out;
  for (EffectKind kind : kinds) out += (out.empty() ? "" : ", ") + std::string(EffectName(kind));
  return out.empty() ? "none" : out;
}

// The values a strongly nonlinear scalar effect is screened over: its descriptor's grid, or for a
// grid-searched one the search range in steps of 10 ms; empty for the others.
std::vector<double> ScreeningGrid(EffectKind kind, const DiagnosisOptions& options) {
  std::vector<double> grid = kind->info().screening_grid;
  if (kind->info().grid_searched) {
    const std::vector<double> search =
        internal::SearchGrid(options.delay_search_min_s, options.delay_search_max_s, 0.01);
    grid.insert(grid.end(), search.begin(), search.end());
  }
  return grid;
}

// Best in-sample shrink (% of the TLS criterion) of a strongly nonlinear candidate over its
// screening grid, on top of `base` effects.
double GridShrinkPct(const IdentificationResult& full, const Effects& base, EffectKind kind,
                     const DiagnosisOptions& options) {
  const std::vector<double> grid = ScreeningGrid(kind, options);
  const double without = EffectCriterion(full, base);
  if (!(without > 0.0)) return 0.0;
  const std::vector<double> criterion = internal::CriterionOverGrid(full, base, kind, grid, options.num_threads);
  const double best = std::min(without, *std::min_element(criterion.begin(), criterion.end()));
  return 100.0 * (1.0 - best / without);
}

}  // namespace

std::string FormatEffectMagnitude(EffectKind kind, const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) {
  return kind->Format(value, std_dev);
}

Diagnosis Diagnose(const std::vector<ProcessedFlight>& flights, const std::vector<ProcessedFlight>& held_out,
                   const DiagnosisOptions& requested, const DiagnosisProgress& progress) {
  if (const std::string problem = requested.Validate(); !problem.empty()) throw Error(problem);
  if (flights.empty()) throw Error("diagnose: no identification flights");
  const auto dimension = [&flights](EffectKind kind) { return kind->Dimension(flights.front().vehicle); };
  // A candidate whose inputs a log lacks (velocity, voltage, ...) is unavailable for these logs.
  DiagnosisOptions options = requested;
  options.candidates.clear();
  std::vector<EffectVerdict> unavailable;  // ranked last, with the reason
  for (EffectKind kind : requested.candidates) {
    // Its folds and linearised steps keep every effect at a size known without the vehicle.
    if (kind->FixedDimension() < 0)
      throw Error("diagnose: " + kind->name() +
                  " has one value per rotor, which the diagnosis does not take yet; refine it by name (rotorid "
                  "refine --effects " +
                  kind->name() + ")");
    std::string reason;
    for (size_t f = 0; f < flights.size() && reason.empty(); ++f)
      if (const std::string why = kind->Unavailable(flights[f].inputs()); !why.empty())
        reason = flights[f].source + ": " + why + "; not a candidate";
    if (reason.empty()) {
      options.candidates.push_back(kind);
    } else {
      EffectVerdict v;
      v.kind = kind;
      v.status = "unavailable";
      v.value = Eigen::VectorXd::Zero(dimension(kind));
      v.note = reason;
      unavailable.push_back(v);
    }
  }
  const auto start_time = std::chrono::steady_clock::now();
  Diagnosis diagnosis;
  auto phase_start = start_time;
  auto mark = [&](const std::string& phase) {
    const auto now = std::chrono::steady_clock::now();
    diagnosis.phase_seconds.emplace_back(phase, std::chrono::duration<double>(now - phase_start).count());
    phase_start = now;
  };
  diagnosis.candidates = options.candidates;

  // Baseline: the linear model on all identification data.
  const IdentificationResult full = IdentifyProcessed(flights, options.identify);
  diagnosis.warnings = full.warnings;
  for (const EffectVerdict& v : unavailable) diagnosis.warnings.push_back(v.note);
  diagnosis.linear_parameters = NamedParameters(full.system, full.solution.chi);
  mark("linear identification");

  // Held-out data: time-blocked folds, or the given flights with the model fitted on everything.
  std::vector<internal::Fold> folds;
  std::vector<IdentificationResult> fold_linear;
  int num_evaluation_flights = 0;
  if (held_out.empty()) {
    folds = internal::TimeBlockedFolds(flights, options.folds, options.guard_s);
    fold_linear.resize(folds.size());
    std::vector<std::string> errors(folds.size());
    ParallelFor(static_cast<int>(folds.size()), options.num_threads, [&](int k) {
      try {
        fold_linear[k] = IdentifyProcessed(folds[k].train, options.identify);
      } catch (const std::exception& e) {
        errors[k] = e.what();
      }
    });
    for (size_t k = 0; k < errors.size(); ++k)
      if (!errors[k].empty())
        throw Error("held-out fold " + std::to_string(k + 1) + " of " + std::to_string(folds.size()) +
                    ": the linear model cannot be identified without that block (" + errors[k] +
                    "); use fewer folds or held-out flights");
    num_evaluation_flights = static_cast<int>(flights.size());
    diagnosis.validation = std::to_string(options.folds) + " time-blocked folds of " + std::to_string(flights.size()) +
                           (flights.size() == 1 ? " flight" : " flights");
  } else {
    for (const ProcessedFlight& f : held_out)
      if (std::find(full.system.config_names.begin(), full.system.config_names.end(), f.vehicle.name) ==
          full.system.config_names.end())
        throw Error(f.source + ": held-out flight of configuration '" + f.vehicle.name +
                    "', which none of the identification flights has");
    internal::Fold fold;
    fold.train = flights;
    fold.evaluate = held_out;
    for (size_t e = 0; e < held_out.size(); ++e) fold.evaluate_flight.push_back(static_cast<int>(e));
    folds.push_back(std::move(fold));
    fold_linear.push_back(full);
    num_evaluation_flights = static_cast<int>(held_out.size());
    diagnosis.validation =
        std::to_string(held_out.size()) + (held_out.size() == 1 ? " held-out flight" : " held-out flights");
  }
  mark("fold identifications");
  HeldOutEvaluator evaluator(options, std::move(folds), std::move(fold_linear), num_evaluation_flights, progress);

  std::map<EffectMask, ModelRecord> records;
  records[0] = evaluator.Baseline();
  diagnosis.baseline = records[0].gap;
  diagnosis.held_out_row_samples = records[0].held_out.row_samples();
  mark("held-out baseline");

  std::vector<std::string> free_parameters;
  for (int k = 0; k < full.system.num_parameters(); ++k)
    if (full.solution.essential[k]) free_parameters.push_back(full.system.parameter_names[k]);

  // Start of the rotor-signal candidates: a coarse search of the TLS criterion over the delay, done
  // when one of them is first refined.
  bool delay_searched = false;
  auto search_delay = [&]() {
    if (delay_searched) return;
    delay_searched = true;
    const EffectKind searched =
        *std::find_if(AllEffects().begin(), AllEffects().end(), [](EffectKind k) { return k->info().grid_searched; });
    const std::vector<double> grid =
        internal::SearchGrid(options.delay_search_min_s, options.delay_search_max_s, options.delay_search_step_s);
    const std::vector<double> criterion =
        internal::CriterionOverGrid(full, Effects{}, searched, grid, options.num_threads);
    diagnosis.initial_delay_s = grid[std::min_element(criterion.begin(), criterion.end()) - criterion.begin()];
    mark("coarse delay search");
  };

  auto columns_of = [&dimension](const internal::EffectSubsetFit& fit, EffectKind kind, const Eigen::VectorXd& v) {
    Eigen::VectorXd out(dimension(kind));
    int k = 0;
    for (size_t c = 0; c < fit.column_kind.size(); ++c)
      if (fit.column_kind[c] == kind) out[k++] = v[static_cast<Eigen::Index>(c)];
    return out;
  };

  // Forward selection on held-out data.
  struct Tested {
    int step = 0;
    EffectMask base = 0;
    EffectTest test;
    EffectTest screening;
    std::optional<EffectTest> alone;
    Eigen::VectorXd linearized_value;  // one Gauss-Newton step on top of the base model
    Effects linearized_step;           // that step for every effect of the model (base and candidate)
  };
  std::map<EffectKind, Tested, EffectOrder> tested;
  std::vector<std::vector<EffectKind>> step_fitted;  // per step: the candidates refined in the folds
  std::vector<std::map<EffectKind, EffectTest, EffectOrder>> step_tests;
  std::vector<SelectionStep> forward_steps;  // as selected, before the backward elimination
  EffectMask selected = 0;
  for (int step = 1;; ++step) {
    if (static_cast<int>(KindsOf(selected).size()) >= options.max_effects) break;
    std::vector<EffectKind> remaining;
    for (EffectKind kind : options.candidates)
      if (!Has(selected, kind)) remaining.push_back(kind);
    if (remaining.empty()) break;
    const ModelRecord& base = records.at(selected);

    // Screening by the criterion linearised at the current model (fold means): an effect removes
    // less residual out of sample than in sample, so a candidate whose first-order in-sample shrink
    // cannot reach the floor, or is far below the best candidate's, is not refined in the folds at
    // this step. Large, nonlinear effects (a 40 ms delay) still show a large first-order shrink.
    std::map<std::string, double> point_parameters = diagnosis.linear_parameters;
    Effects point_effects;
    if (selected != 0) {
      for (auto& [name, value] : point_parameters) {
        double sum = 0.0;
        for (const auto& fold : base.fold_parameters) sum += fold.at(name);
        value = sum / static_cast<double>(base.fold_parameters.size());
      }
      point_effects = MeanFoldEffects(base);
    }
    const internal::EffectLinearization linearization =
        internal::LinearizeEffects(full.flights, point_parameters, free_parameters, point_effects, options.candidates);
    const double base_shrink = internal::FitEffectSubset(linearization, KindsOf(selected)).predicted_shrink;
    double best_predicted = 0.0;
    for (EffectKind kind : remaining) {
      const internal::EffectSubsetFit fit = internal::FitEffectSubset(linearization, KindsOf(selected | Bit(kind)));
      Tested& t = tested[kind];
      t.step = step;
      t.base = selected;
      t.linearized_value = point_effects.Get(kind) + columns_of(fit, kind, fit.step);
      t.linearized_step = Effects{};
      for (EffectKind k : KindsOf(selected | Bit(kind))) t.linearized_step.Set(k, columns_of(fit, k, fit.step));
      // A sign-constrained effect (tau >= 0) stays in its range; at the bound, a first-order step
      // below it gains nothing.
      const bool sign_constrained = kind->info().lower_bound == 0.0;
      if (sign_constrained) t.linearized_value = t.linearized_value.cwiseMax(0.0);
      const bool blocked_by_bound = sign_constrained && (point_effects.Get(kind).array() <= 0.0).all() &&
                                    (columns_of(fit, kind, fit.step).array() < 0.0).all();
      double predicted = blocked_by_bound ? 0.0 : std::max(0.0, fit.predicted_shrink - base_shrink);
      // Delay and lag act nonlinearly: a 100 ms lag is far from the linearisation point and its
      // first-order shrink can be a tenth of the real one (PWM-driven Crazyflie flights). The
      // screening of such effects also takes the best in-sample shrink over a coarse grid.
      if (!ScreeningGrid(kind, options).empty())
        predicted = std::max(predicted, GridShrinkPct(full, point_effects, kind, options));
      t.screening = internal::ScreeningTest(predicted, dimension(kind), fit.effective_samples,
                                            linearization.scored_rows, options.alpha, options.min_shrink_pct);
      t.test = t.screening;
      if (step == 1) t.alone = t.test;
      best_predicted = std::max(best_predicted, t.screening.shrink_pct);
    }
    std::vector<EffectKind> to_fit;
    for (EffectKind kind : remaining) {
      const double predicted = tested[kind].screening.shrink_pct;
      if (predicted >= options.screen_fraction * options.min_shrink_pct &&
          predicted >= options.rival_fraction * best_predicted)
        to_fit.push_back(kind);
    }
    mark("step " + std::to_string(step) + " screening");
    if (to_fit.empty()) break;

    std::vector<EffectMask> masks;
    std::vector<std::vector<Effects>> initial;
    for (EffectKind kind : to_fit) {
      const bool on_rotor = kind->stage() == EffectStage::kRotorSignal;
      if (on_rotor) search_delay();
      masks.push_back(selected | Bit(kind));
      std::vector<Effects> starts = base.fold_effects;
      const Effects& step_effects = tested[kind].linearized_step;
      for (Effects& start : starts) {
        // Warm start: the fold's base fit plus the linearised step of the joint model, which also
        // moves the effects already selected (adding a lag on top of a delay shortens the delay).
        // The rotor-signal effects are nonlinear far from zero: alone, they start where the coarse
        // delay search points instead.
        bool rotor_alone = on_rotor;
        for (EffectKind k : KindsOf(selected)) rotor_alone = rotor_alone && k->stage() != EffectStage::kRotorSignal;
        for (EffectKind k : KindsOf(selected | Bit(kind))) {
          Eigen::VectorXd value = start.Get(k) + step_effects.Get(k);
          if (k->info().lower_bound == 0.0) value = value.cwiseMax(0.0);
          start.Set(k, value);
        }
        if (rotor_alone) start.Set(kind, kind->FromEquivalentDelay(diagnosis.initial_delay_s));
      }
      initial.push_back(std::move(starts));
    }
    std::vector<ModelRecord> fitted = evaluator.Fit(masks, initial);
    mark("step " + std::to_string(step) + " fold refinements");
    step_fitted.push_back({});
    step_tests.push_back({});
    int best = -1;
    for (size_t c = 0; c < to_fit.size(); ++c) {
      ModelRecord& record = fitted[c];
      if (!record.ok) {
        diagnosis.warnings.push_back(std::string(EffectName(to_fit[c])) + " on top of " + Join(KindsOf(selected)) +
                                     ": refinement failed (" + record.error + ")");
        continue;
      }
      Tested& t = tested[to_fit[c]];
      t.test = internal::TestAddedEffects(base.gap, record.gap, dimension(to_fit[c]), options.alpha,
                                          options.min_shrink_pct);
      if (step == 1) t.alone = t.test;
      step_fitted.back().push_back(to_fit[c]);
      step_tests.back()[to_fit[c]] = t.test;
      if (best < 0 || record.gap.whitened_ssr < fitted[best].gap.whitened_ssr) best = static_cast<int>(c);
      records[record.mask] = std::move(record);
    }
    if (best < 0) break;
    const EffectKind best_kind = to_fit[best];
    const EffectTest best_test = tested[best_kind].test;
    if (!best_test.significant) break;
    SelectionStep s;
    s.added = best_kind;
    s.before = records.at(selected).gap;
    selected |= Bit(best_kind);
    s.after = records.at(selected).gap;
    s.test = best_test;
    forward_steps.push_back(s);
    diagnosis.selected.push_back(best_kind);
  }

  // Fits (in the folds) the models that are not refined yet, warm-started from `from` without the
  // effects they lack.
  auto ensure_fitted = [&](const std::vector<EffectMask>& masks, EffectMask from) {
    std::vector<EffectMask> missing;
    std::vector<std::vector<Effects>> initial;
    for (EffectMask mask : masks) {
      if (records.count(mask) || std::find(missing.begin(), missing.end(), mask) != missing.end()) continue;
      missing.push_back(mask);
      std::vector<Effects> starts;
      for (const Effects& e : records.at(from).fold_effects) {
        Effects start;
        for (EffectKind k : KindsOf(mask)) start.Set(k, e.Get(k));
        starts.push_back(start);
      }
      initial.push_back(std::move(starts));
    }
    if (missing.empty()) return;
    for (ModelRecord& record : evaluator.Fit(missing, initial)) {
      if (!record.ok) {
        diagnosis.warnings.push_back("model " + Join(KindsOf(record.mask)) + ": refinement failed (" + record.error +
                                     ")");
        continue;
      }
      records[record.mask] = std::move(record);
    }
  };

  // Backward elimination: an effect selected early can become redundant once later ones are in (an
  // acc bias standing in for a misalignment while a large lag dominated the residual). Each kept
  // effect, earliest first, is tested on top of all the others; the first that is not significant
  // is dropped and the pass restarts.
  struct Dropped {
    EffectKind kind;
    EffectMask others;
    EffectTest test;
  };
  std::vector<Dropped> dropped;
  for (bool changed = true; changed && diagnosis.selected.size() >= 2;) {
    changed = false;
    for (size_t i = 0; i < diagnosis.selected.size(); ++i) {
      const EffectKind kind = diagnosis.selected[i];
      const EffectMask others = selected & ~Bit(kind);
      ensure_fitted({others}, selected);
      if (!records.count(others)) continue;
      const EffectTest test = internal::TestAddedEffects(records.at(others).gap, records.at(selected).gap,
                                                         dimension(kind), options.alpha, options.min_shrink_pct);
      if (test.significant) continue;
      dropped.push_back({kind, others, test});
      selected = others;
      diagnosis.selected.erase(diagnosis.selected.begin() + static_cast<std::ptrdiff_t>(i));
      changed = true;
      break;
    }
  }
  if (!dropped.empty()) mark("backward elimination");

  // How far: the held-out gap after each kept effect, in the order they were added.
  {
    EffectMask prefix = 0;
    std::vector<EffectMask> prefixes;
    for (EffectKind kind : diagnosis.selected) prefixes.push_back(prefix |= Bit(kind));
    ensure_fitted(prefixes, selected);
    prefix = 0;
    for (EffectKind kind : diagnosis.selected) {
      SelectionStep s;
      s.added = kind;
      s.before = records.at(prefix).gap;
      prefix |= Bit(kind);
      if (!records.count(prefix)) break;
      s.after = records.at(prefix).gap;
      s.test =
          internal::TestAddedEffects(s.before, s.after, dimension(kind), options.alpha, options.min_shrink_pct);
      diagnosis.steps.push_back(s);
    }
  }
  diagnosis.final_gap = records.at(selected).gap;

  // The final model on all identification data.
  diagnosis.final_parameters = diagnosis.linear_parameters;
  if (selected != 0) {
    RefineOptions refine;
    refine.effects = KindsOf(selected);
    refine.initial = MeanFoldEffects(records.at(selected));
    refine.coarse_delay_search = false;
    refine.compute_covariance = false;
    refine.num_threads = options.num_threads;
    const RefineResult result = Refine(full, refine);
    diagnosis.final_effects = result.effects;
    diagnosis.final_parameters = NamedParameters(full.system, result.refined.chi);
    mark("final refinement");
  }

  // Std and detectable sizes from the criterion linearised at the final model.
  const internal::EffectLinearization linearization = internal::LinearizeEffects(
      full.flights, diagnosis.final_parameters, free_parameters, diagnosis.final_effects, options.candidates);
  const std::vector<EffectKind> selected_kinds = KindsOf(selected);
  const internal::EffectSubsetFit selected_fit = internal::FitEffectSubset(linearization, selected_kinds);
  for (EffectKind kind : selected_kinds)
    diagnosis.final_effects_std.Set(kind, columns_of(selected_fit, kind, selected_fit.std));
  mark("linearisation");

  // Verdicts.
  std::vector<EffectVerdict> verdicts;
  for (EffectKind kind : options.candidates) {
    EffectVerdict v;
    v.kind = kind;
    v.selected = Has(selected, kind);
    const auto t = tested.find(kind);
    const auto record = t != tested.end() ? records.find(t->second.base | Bit(kind)) : records.end();
    if (t != tested.end()) {
      v.step = t->second.step;
      v.tested_on_top_of = KindsOf(t->second.base);
      v.test = t->second.test;
      v.alone_test = t->second.alone;
      v.screening = t->second.screening;
      if (record != records.end()) v.relative_error_pct = record->second.gap.relative_error_pct;
    }
    v.significant = v.test.significant;
    std::vector<EffectKind> subset = selected_kinds;
    if (!v.selected) subset.push_back(kind);
    const internal::EffectSubsetFit fit = v.selected ? selected_fit : internal::FitEffectSubset(linearization, subset);
    v.std = columns_of(fit, kind, fit.std);
    v.detectable_above = DetectableSizes(v.std, dimension(kind), fit.effective_samples, options);
    if (v.selected) {
      v.value = diagnosis.final_effects.Get(kind);
      v.status = "selected";
    } else {
      if (record != records.end() && !v.test.screened)
        v.value = MeanFoldEffect(record->second, kind);
      else if (t != tested.end())
        v.value = t->second.linearized_value;
      else
        v.value = Eigen::VectorXd::Zero(dimension(kind));
      v.status = "not significant";
    }
    // Kept effects: their test on top of the kept effects added before them.
    EffectMask prefix = 0;
    for (size_t i = 0; i < diagnosis.steps.size(); ++i) {
      if (diagnosis.steps[i].added == kind) {
        v.step = static_cast<int>(i) + 1;
        v.tested_on_top_of = KindsOf(prefix);
        v.test = diagnosis.steps[i].test;
        v.significant = v.test.significant;
        v.relative_error_pct = diagnosis.steps[i].after.relative_error_pct;
      }
      prefix |= Bit(diagnosis.steps[i].added);
    }
    // Dropped effects: their test on top of all the others at the moment they were dropped.
    for (const Dropped& d : dropped) {
      if (d.kind != kind) continue;
      const ModelRecord& with = records.at(d.others | Bit(kind));
      v.dropped_as_redundant = true;
      v.tested_on_top_of = KindsOf(d.others);
      v.test = d.test;
      v.significant = false;
      v.relative_error_pct = with.gap.relative_error_pct;
      v.value = MeanFoldEffect(with, kind);
    }
    verdicts.push_back(std::move(v));
  }
  auto verdict_of = [&](EffectKind kind) -> EffectVerdict& {
    return *std::find_if(verdicts.begin(), verdicts.end(), [&](const EffectVerdict& v) { return v.kind == kind; });
  };

  // Confounding: an alternative that removed held-out residual at the step an effect was selected
  // (significant, at least half as much) is compared with it directly on the held-out rows. If the
  // selected effect does not fit significantly better, the data cannot tell them apart.
  EffectMask before = 0;
  for (size_t s = 0; s < forward_steps.size(); ++s) {
    const SelectionStep& step = forward_steps[s];
    if (!Has(selected, step.added)) {
      before |= Bit(step.added);
      continue;
    }
    for (EffectKind other : step_fitted[s]) {
      if (other == step.added || Has(selected, other)) continue;
      const EffectTest& other_test = step_tests[s].at(other);
      if (!other_test.significant || other_test.shrink_pct < 0.5 * step.test.shrink_pct) continue;
      ConfoundedEffects c;
      c.selected = step.added;
      c.other = other;
      c.selected_shrink_pct = step.test.shrink_pct;
      c.other_shrink_pct = other_test.shrink_pct;
      const internal::PairedComparison comparison = internal::CompareHeldOut(
          records.at(before | Bit(step.added)).held_out, records.at(before | Bit(other)).held_out, evaluator.scales());
      c.t_statistic = comparison.t_statistic;
      c.p_value = comparison.p_value;
      // Practical equivalence (issue 11): a significant t on two held-out shrinks that are almost
      // equal says the better one is better by a hair, not that the data tell them apart.
      const bool practically_equal = std::abs(c.selected_shrink_pct - c.other_shrink_pct) <
                                     kPracticalEquivalence * std::max(c.selected_shrink_pct, c.other_shrink_pct);
      c.distinguishable = comparison.p_value < options.alpha && !practically_equal;
      // Their correlation, from the criterion linearised at the final model with both in it (the
      // refinement's Ceres covariance drops weak directions, see linearization.h).
      std::vector<EffectKind> pair = selected_kinds;
      pair.push_back(other);
      const internal::EffectSubsetFit joint_fit = internal::FitEffectSubset(linearization, pair);
      for (size_t a = 0; a < joint_fit.labels.size(); ++a)
        for (size_t b = 0; b < joint_fit.labels.size(); ++b) {
          if (joint_fit.column_kind[a] != step.added || joint_fit.column_kind[b] != other) continue;
          const double r = joint_fit.correlation(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
          if (!c.correlation || std::abs(r) > std::abs(*c.correlation)) {
            c.correlation = r;
            c.correlated_labels = joint_fit.labels[a] + " / " + joint_fit.labels[b];
          }
        }
      std::ostringstream note;
      note << std::fixed << std::setprecision(1) << EffectName(other) << " alone removes " << c.other_shrink_pct
           << " % of the held-out residual, " << EffectName(step.added) << " " << c.selected_shrink_pct << " %";
      if (c.distinguishable)
        note << "; " << EffectName(step.added)
             << " fits the held-out rows significantly better (t = " << std::setprecision(1) << c.t_statistic
             << "): the data tell them apart";
      else if (practically_equal)
        note << "; they differ by less than " << std::setprecision(0) << 100 * kPracticalEquivalence
             << " % of that (t = " << std::setprecision(1) << c.t_statistic
             << " measures a hair, not a difference): these flights cannot tell " << EffectName(step.added)
             << " and " << EffectName(other) << " apart"
             << AloneValues(step.added, records.at(before | Bit(step.added)), other,
                            records.at(before | Bit(other)));
      else
        note << "; the difference is not significant (t = " << std::setprecision(1) << c.t_statistic
             << "): these flights cannot tell " << EffectName(step.added) << " and " << EffectName(other) << " apart"
             << AloneValues(step.added, records.at(before | Bit(step.added)), other,
                            records.at(before | Bit(other)));
      c.note = note.str();
      EffectVerdict& verdict = verdict_of(other);
      verdict.confounded_with.push_back(step.added);
      if (!c.distinguishable) verdict.status = "confounded";
      verdict_of(step.added).confounded_with.push_back(other);
      diagnosis.confounded.push_back(c);
    }
    before |= Bit(step.added);
  }
  mark("confounding");

  // Notes and ranking: the selected effects in the order they were added, then the others by the
  // held-out residual they removed.
  for (EffectVerdict& v : verdicts) {
    std::ostringstream note;
    if (v.status == "selected") {
      note << "held-out gap shrinks " << std::fixed << std::setprecision(1) << v.test.shrink_pct << " %";
    } else if (v.dropped_as_redundant) {
      note << "selected early, but not significant once " << Join(v.tested_on_top_of) << " were in (held-out shrink "
           << std::setprecision(2) << std::fixed << v.test.shrink_pct << " %): dropped as redundant";
    } else if (v.test.screened && v.test.shrink_pct >= options.screen_fraction * options.min_shrink_pct) {
      note << "not refined: its predicted in-sample shrink (" << std::setprecision(2) << std::fixed << v.test.shrink_pct
           << " %) was well below the leading candidate's at step " << v.step << ", where the selection stopped";
    } else if (v.test.screened) {
      note << "not refined: its first-order in-sample shrink is only " << std::setprecision(2) << std::fixed
           << v.test.shrink_pct << " %; this data would reveal it above "
           << FormatEffectMagnitude(v.kind, v.detectable_above, Eigen::VectorXd());
    } else if (v.status == "confounded") {
      note << "removes as much held-out residual as " << EffectName(v.confounded_with.front())
           << "; the data cannot tell them apart";
    } else {
      const Eigen::VectorXd ratio = v.value.cwiseAbs().cwiseQuotient(v.detectable_above.cwiseMax(1e-300));
      note << (ratio.maxCoeff() < 1.0 ? "not detected" : "not significant") << "; this data would reveal it above "
           << FormatEffectMagnitude(v.kind, v.detectable_above, Eigen::VectorXd());
    }
    v.note = note.str();
  }
  for (EffectKind kind : diagnosis.selected) diagnosis.ranking.push_back(verdict_of(kind));
  std::vector<EffectVerdict> rest;
  for (const EffectVerdict& v : verdicts)
    if (!v.selected) rest.push_back(v);
  std::stable_sort(rest.begin(), rest.end(), [](const EffectVerdict& a, const EffectVerdict& b) {
    return a.test.shrink_pct > b.test.shrink_pct;
  });
  diagnosis.ranking.insert(diagnosis.ranking.end(), rest.begin(), rest.end());
  diagnosis.ranking.insert(diagnosis.ranking.end(), unavailable.begin(), unavailable.end());

  // Where.
  // The component with the largest model error (gap beyond the noise floor) among those whose gap is
  // at least sqrt(2) times the floor (as much model error as noise); when none is, the one whose gap
  // exceeds its floor the most.
  const HeldOutGap& b = diagnosis.baseline;
  double largest_error = -1.0, largest_ratio = -1.0;
  int by_error = -1, by_ratio = 0;
  for (int j = 0; j < kComponents; ++j) {
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
  diagnosis.where_component = by_error >= 0 ? by_error : by_ratio;
  diagnosis.where =
      LocateGap(full, diagnosis.final_parameters, diagnosis.final_effects, options.candidates, options.location);
  mark("where");

  diagnosis.refinements = evaluator.refinements();
  diagnosis.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return diagnosis;
}

std::string DiagnosisVerdict(const Diagnosis& d) {
  std::ostringstream out;
  out << std::fixed;
  const int j = d.where_component;
  auto pct = [](const std::optional<double>& v) {
    std::ostringstream s;
    if (v)
      s << std::fixed << std::setprecision(2) << *v << " %";
    else
      s << "n/a";
    return s.str();
  };
  out << "held out: " << d.validation << " (" << d.held_out_row_samples << " row samples)\n";
  // Where: component, band, stretch.
  const bool beyond_noise = d.baseline.gap_pct[j] && d.baseline.noise_floor_pct[j] &&
                            *d.baseline.gap_pct[j] >= std::sqrt(2.0) * *d.baseline.noise_floor_pct[j];
  if (beyond_noise)
    out << "where: the largest held-out gap beyond the noise floor is in " << kWrenchComponentNames[j] << ": "
        << pct(d.baseline.model_error_pct[j]) << (j < 2 ? " of the thrust" : "") << " (gap "
        << pct(d.baseline.gap_pct[j]) << ", noise floor " << pct(d.baseline.noise_floor_pct[j]) << ")";
  else
    out << "where: no component's held-out gap is well above its noise floor (closest: " << kWrenchComponentNames[j]
        << ", gap " << pct(d.baseline.gap_pct[j]) << " against " << pct(d.baseline.noise_floor_pct[j]) << ")";
  if (!d.where.bands.empty()) {
    // The band where the selected effects remove the most residual energy, else the band that
    // holds the most of it.
    auto removed = [&](const BandGap& b) {
      return b.residual_rms[j] * b.residual_rms[j] - b.final_residual_rms[j] * b.final_residual_rms[j];
    };
    size_t band = 0;
    for (size_t b = 1; b < d.where.bands.size(); ++b) {
      const bool better = d.selected.empty() ? d.where.bands[b].share_pct[j] > d.where.bands[band].share_pct[j]
                                             : removed(d.where.bands[b]) > removed(d.where.bands[band]);
      if (better) band = b;
    }
    const BandGap& bg = d.where.bands[band];
    out << ";\n       mostly at " << std::setprecision(0) << bg.low_hz << "-" << bg.high_hz << " Hz ("
        << bg.share_pct[j] << " % of its residual energy";
    if (!d.selected.empty() && bg.residual_rms[j] > 0.0)
      out << ", of which the selected effects remove "
          << 100.0 * removed(bg) / (bg.residual_rms[j] * bg.residual_rms[j]) << " %";
    out << ")";
  }
  if (!d.where.worst_stretches.empty()) {
    const FlightStretch& w = d.where.worst_stretches.front();
    out << ";\n       worst stretch " << std::setprecision(1) << w.start_s << "-" << w.end_s << " s (";
    for (size_t a = 0; a < w.activities.size(); ++a) out << (a ? ", " : "") << w.activities[a];
    out << "; rates " << std::setprecision(2) << w.angular_velocity_rms[0] << "/" << w.angular_velocity_rms[1] << "/"
        << w.angular_velocity_rms[2] << " rad/s RMS; " << std::setprecision(1) << w.mean_square_ratio
        << "x the flight's mean square, mostly " << kWrenchComponentNames[w.dominant_component] << ")";
  }
  out << "\n";
  // Which.
  if (d.selected.empty()) {
    out << "which: no candidate effect removes significant held-out residual; the model explains these flights "
           "as well as the candidates can\n";
  }
  for (const EffectVerdict& v : d.ranking) {
    if (v.selected) {
      out << (v.kind == d.selected.front() ? "which: " : "     + ") << EffectName(v.kind) << " = "
          << FormatEffectMagnitude(v.kind, v.value, v.std) << " (F = " << std::setprecision(1) << v.test.f_statistic
          << ", p = " << std::scientific << std::setprecision(1) << v.test.p_value << std::fixed
          << "; held-out gap shrinks " << std::setprecision(1) << v.test.shrink_pct << " %)\n";
    }
  }
  for (const ConfoundedEffects& c : d.confounded) {
    out << "       " << c.note;
    if (c.correlation) out << " (correlation " << std::setprecision(2) << *c.correlation << ")";
    out << "\n";
  }
  for (const EffectVerdict& v : d.ranking)
    if (!v.selected) out << "       " << EffectName(v.kind) << ": " << v.note << "\n";
  // How far: the held-out gap after each selected effect.
  out << "how far (held-out gap, %; Fx, Fy against the thrust): baseline";
  for (EffectKind kind : d.selected) out << " -> +" << EffectName(kind);
  out << "\n";
  for (int c = 0; c < kComponents; ++c) {
    out << "       " << kWrenchComponentNames[c] << " ";
    auto value = [&](const std::optional<double>& v) {
      if (v)
        out << std::setprecision(2) << *v;
      else
        out << "n/a";
    };
    value(d.baseline.gap_pct[c]);
    for (const SelectionStep& step : d.steps) {
      out << " -> ";
      value(step.after.gap_pct[c]);
    }
    out << "  (noise floor ";
    value(d.baseline.noise_floor_pct[c]);
    out << ")\n";
  }
  return out.str();
}

}  // namespace rotorid

#include "diagnosis/selection.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "diagnosis/verdict_text.h"
#include "refine/grid_search.h"
#include "rotorid/refine/refine.h"

namespace rotorid::internal {

EffectMask Bit(EffectKind kind) { return 1u << static_cast<unsigned>(kind->index()); }
bool Has(EffectMask mask, EffectKind kind) { return (mask & Bit(kind)) != 0; }
std::vector<EffectKind> KindsOf(EffectMask mask) {
  std::vector<EffectKind> kinds;
  for (EffectKind kind : AllEffects())
    if (Has(mask, kind)) kinds.push_back(kind);
  return kinds;
}

EffectMask MaskOf(const std::vector<EffectKind>& kinds) {
  EffectMask mask = 0;
  for (EffectKind kind : kinds) mask |= Bit(kind);
  return mask;
}

std::string Join(const std::vector<EffectKind>& kinds) {
  std::string out;
  for (EffectKind kind : kinds) out += (out.empty() ? "" : ", ") + std::string(EffectName(kind));
  return out.empty() ? "none" : out;
}

Eigen::VectorXd MeanFoldEffect(const ModelRecord& record, EffectKind kind) {
  Eigen::VectorXd sum;
  for (const Effects& e : record.fold_effects) sum = sum.size() ? Eigen::VectorXd(sum + e.Get(kind)) : e.Get(kind);
  return record.fold_effects.empty() ? sum : Eigen::VectorXd(sum / static_cast<double>(record.fold_effects.size()));
}

Effects MeanFoldEffects(const ModelRecord& record) {
  Effects mean;
  for (EffectKind kind : KindsOf(record.mask)) mean.Set(kind, MeanFoldEffect(record, kind));
  return mean;
}

bool TestedCandidate::Judge(EffectKind kind, const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev,
                            const Vehicle& vehicle, bool on_bound) {
  implausible = kind->Implausible(value, std_dev, vehicle);
  if (implausible.empty() && on_bound) implausible = OnBoundStatement(kind, value);
  negligible = implausible.empty() ? kind->Negligible(value, std_dev) : "";
  return Rejected();
}

void EnsureFitted(SelectionContext* context, const std::vector<EffectMask>& masks, EffectMask from) {
  std::vector<EffectMask> missing;
  std::vector<std::vector<Effects>> initial;
  for (EffectMask mask : masks) {
    if (context->records.count(mask) || std::find(missing.begin(), missing.end(), mask) != missing.end()) continue;
    missing.push_back(mask);
    std::vector<Effects> starts;
    for (const Effects& e : context->records.at(from).fold_effects) {
      Effects start;
      for (EffectKind k : KindsOf(mask)) start.Set(k, e.Get(k));
      starts.push_back(start);
    }
    initial.push_back(std::move(starts));
  }
  if (missing.empty()) return;
  for (ModelRecord& record : context->fitter.Fit(missing, initial)) {
    if (!record.ok) {
      context->warnings.push_back("model " + Join(KindsOf(record.mask)) + ": refinement failed (" + record.error + ")");
      continue;
    }
    context->records[record.mask] = std::move(record);
  }
}

PhaseTimer::PhaseTimer(std::vector<std::pair<std::string, double>>* phase_seconds) : phase_seconds_(phase_seconds) {}

void PhaseTimer::Mark(const std::string& phase) {
  const Clock::time_point now = Clock::now();
  phase_seconds_->emplace_back(phase, std::chrono::duration<double>(now - phase_start_).count());
  phase_start_ = now;
}

double PhaseTimer::SecondsSinceStart() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

std::vector<double> ScreeningGrid(EffectKind kind, const DiagnosisOptions& options) {
  std::vector<double> grid = kind->info().screening_grid;
  if (kind->info().grid_searched) {
    const std::vector<double> search = SearchGrid(options.delay_search.min_s, options.delay_search.max_s, 0.01);
    grid.insert(grid.end(), search.begin(), search.end());
  }
  return grid;
}

namespace {

// Best in-sample shrink (fraction of the TLS criterion) of a strongly nonlinear candidate over its
// screening grid, on top of `base` effects.
double GridShrinkFraction(const IdentificationResult& full, const Effects& base, EffectKind kind,
                          const DiagnosisOptions& options) {
  const std::vector<double> grid = ScreeningGrid(kind, options);
  const double without = EffectCriterion(full, base);
  if (!(without > 0.0)) return 0.0;
  const std::vector<double> criterion = CriterionOverGrid(full, base, kind, grid, options.num_threads);
  const double best = std::min(without, *std::min_element(criterion.begin(), criterion.end()));
  return 1.0 - best / without;
}

// Where the screening linearises: the base model's fold means (the linear model at step 1).
struct ScreeningPoint {
  std::map<std::string, double> parameters;
  Effects effects;
};

ScreeningPoint ScreeningPointOf(const AllDataModel& all_data, EffectMask selected, const ModelRecord& base) {
  ScreeningPoint point{all_data.predicted, Effects{}};
  if (selected == 0) return point;
  for (auto& [name, value] : point.parameters) {
    double sum = 0.0;
    for (const auto& fold : base.fold_parameters) sum += fold.at(name);
    value = sum / static_cast<double>(base.fold_parameters.size());
  }
  point.effects = MeanFoldEffects(base);
  return point;
}

// The first-order screening of one candidate on top of t->base: its Gauss-Newton step and the
// in-sample shrink beyond the base model's (`base_shrink`, a fraction).
void ScreenCandidate(EffectKind kind, const EffectLinearization& linearization, const ScreeningPoint& point,
                     double base_shrink, const IdentificationResult& full, const DiagnosisOptions& options,
                     TestedCandidate* t) {
  const EffectSubsetFit fit = FitEffectSubset(linearization, KindsOf(t->base | Bit(kind)));
  const Vehicle& vehicle = full.flights.front().vehicle;
  const Eigen::VectorXd own_step = EffectColumns(fit, kind, fit.step);
  t->linearized_value = point.effects.Get(kind, vehicle) + own_step;
  t->linearized_std = EffectColumns(fit, kind, fit.std);
  t->linearized_step = Effects{};
  for (EffectKind k : KindsOf(t->base | Bit(kind))) t->linearized_step.Set(k, EffectColumns(fit, k, fit.step));
  // A sign-constrained effect (tau >= 0) stays in its range; at the bound, a first-order step
  // below it gains nothing.
  const bool sign_constrained = kind->info().lower_bound == 0.0;
  if (sign_constrained) t->linearized_value = t->linearized_value.cwiseMax(0.0);
  const bool blocked_by_bound =
      sign_constrained && (point.effects.Get(kind).array() <= 0.0).all() && (own_step.array() < 0.0).all();
  double predicted = blocked_by_bound ? 0.0 : std::max(0.0, fit.predicted_shrink - base_shrink);
  // Delay and lag act nonlinearly: a 100 ms lag is far from the linearisation point and its
  // first-order shrink can be a tenth of the real one (PWM-driven Crazyflie flights). The
  // screening of such effects also takes the best in-sample shrink over a coarse grid.
  if (!ScreeningGrid(kind, options).empty())
    predicted = std::max(predicted, GridShrinkFraction(full, point.effects, kind, options));
  t->screening =
      ScreeningTest(predicted, kind->FreeDimension(vehicle), fit.effective_samples, linearization.scored_rows);
  t->test = t->screening;
  if (t->step == 1) t->alone = t->test;
}

}  // namespace

std::vector<EffectKind> ScreenCandidates(const AllDataModel& all_data, const DiagnosisOptions& options, int step,
                                         EffectMask selected, const ModelRecord& base,
                                         const std::vector<EffectKind>& remaining, TestedCandidates* tested) {
  // Linearised at the current model: large, nonlinear effects (a 40 ms delay) still show a large
  // first-order shrink there.
  const ScreeningPoint point = ScreeningPointOf(all_data, selected, base);
  const EffectLinearization linearization = LinearizeEffects(
      all_data.linear.flights, point.parameters, all_data.free_parameters, point.effects, options.candidates);
  const double base_shrink = FitEffectSubset(linearization, KindsOf(selected)).predicted_shrink;
  for (EffectKind kind : remaining) {
    TestedCandidate& t = (*tested)[kind];
    t.step = step;
    t.base = selected;
    t.worsens.clear();
    ScreenCandidate(kind, linearization, point, base_shrink, all_data.linear, options, &t);
  }
  return CandidatesWorthRefining(remaining, *tested, options);
}

std::vector<EffectKind> CandidatesWorthRefining(const std::vector<EffectKind>& remaining,
                                                const TestedCandidates& tested, const DiagnosisOptions& options) {
  double best_predicted = 0.0;
  for (EffectKind kind : remaining) best_predicted = std::max(best_predicted, tested.at(kind).screening.shrink_pct);
  std::vector<EffectKind> to_fit;
  for (EffectKind kind : remaining) {
    const double predicted = tested.at(kind).screening.shrink_pct;
    if (predicted >= options.screen_fraction * options.min_shrink_pct &&
        predicted >= options.rival_fraction * best_predicted)
      to_fit.push_back(kind);
  }
  return to_fit;
}

namespace {

// Per fold, the start of `kind` refined on top of `selected` (fitted as `base`): the fold's base fit
// plus the linearised step of the joint model, which also moves the effects already selected
// (adding a lag on top of a delay shortens the delay). The rotor-signal effects are nonlinear far
// from zero: alone, they start where the coarse delay search points instead.
std::vector<Effects> WarmStarts(EffectKind kind, EffectMask selected, const ModelRecord& base,
                                const Effects& step_effects, double initial_delay_s, const Vehicle& vehicle) {
  bool rotor_alone = kind->stage() == EffectStage::kRotorSignal;
  for (EffectKind k : KindsOf(selected)) rotor_alone = rotor_alone && k->stage() != EffectStage::kRotorSignal;
  std::vector<Effects> starts = base.fold_effects;
  for (Effects& start : starts) {
    for (EffectKind k : KindsOf(selected | Bit(kind))) {
      Eigen::VectorXd value = start.Get(k, vehicle) + step_effects.Get(k, vehicle);
      if (k->info().lower_bound == 0.0) value = value.cwiseMax(0.0);
      start.Set(k, value);
    }
    if (rotor_alone) start.Set(kind, kind->FromEquivalentDelay(initial_delay_s));
  }
  return starts;
}

// "My: residual 4.04e-05 -> 4.87e-05 N m (+20.6 % against its rotor moment, t = 1.8) over none": the
// components `model` makes worse than `reference` (the base model or the linear one) beyond their
// noise, measured as the held-out score measures them; empty when none.
std::string WorseningStatement(const SelectionContext& context, const ModelRecord& reference,
                               const ModelRecord& model) {
  const HeldOutResidual& baseline = context.records.at(0).held_out;
  const int flights =
      baseline.flight.empty() ? 1 : *std::max_element(baseline.flight.begin(), baseline.flight.end()) + 1;
  const HeldOutScales scales = BaselineScales(baseline, flights);
  ComponentVector noise_share = ComponentVector::Zero();  // of the reference's residual (floor / gap)^2
  for (int j = 0; j < kNumWrenchComponents; ++j)
    if (const auto& floor = reference.gap.noise_floor_pct[j], &gap = reference.gap.gap_pct[j];
        floor && gap && *gap > 0.0)
      noise_share[j] = std::min(1.0, std::pow(*floor / *gap, 2));
  std::ostringstream out;
  for (const ComponentWorsening& w :
       WorsenedComponents(reference.held_out, model.held_out, scales, noise_share,
                          context.options.max_component_growth_pct, context.options.component_growth_alpha))
    out << (out.tellp() > 0 ? "; " : "") << kWrenchComponentNames[static_cast<size_t>(w.component)] << ": residual "
        << std::scientific << std::setprecision(2) << w.rms_before << " -> " << w.rms_after
        << (w.component < 3 ? " N" : " N m") << std::fixed << std::setprecision(1) << " (+" << w.growth_pct
        << " % against its rotor " << (w.component < 3 ? "force" : "moment") << ", t = " << w.t_statistic << ") over "
        << Join(KindsOf(reference.mask));
  return out.str();
}

// Tests each refined candidate on top of `base` and keeps its record; marks the significant ones whose
// fold-mean value is outside the physical range (they buy their shrink with it, absorbing something
// else) or too small to matter, and those that make a held-out component worse (WorseningStatement
// over the base and the linear model); returns the index of the plausible, non-worsening one with the
// smallest held-out residual (-1 when there is none).
int JudgeRefined(SelectionContext* context, const std::vector<EffectKind>& to_fit, const ModelRecord& base,
                 EffectMask selected, std::vector<ModelRecord> fitted, TestedCandidates* tested,
                 std::vector<std::pair<EffectKind, EffectTest>>* refined) {
  const DiagnosisOptions& options = context->options;
  int best = -1;
  double best_ssr = 0.0;
  for (size_t c = 0; c < to_fit.size(); ++c) {
    ModelRecord& record = fitted[c];
    if (!record.ok) {
      context->warnings.push_back(std::string(EffectName(to_fit[c])) + " on top of " + Join(KindsOf(selected)) +
                                  ": refinement failed (" + record.error + ")");
      continue;
    }
    TestedCandidate& t = (*tested)[to_fit[c]];
    t.test = TestAddedEffects(base.gap, record.gap, to_fit[c]->FreeDimension(context->vehicle), options.alpha,
                              options.min_shrink_pct);
    if (t.step == 1) t.alone = t.test;
    if (t.test.significant)
      t.Judge(to_fit[c], MeanFoldEffect(record, to_fit[c]), t.linearized_std, context->vehicle, /*on_bound=*/false);
    if (t.test.significant && !t.Rejected()) {
      t.worsens = WorseningStatement(*context, base, record);
      if (t.worsens.empty() && selected != 0) t.worsens = WorseningStatement(*context, context->records.at(0), record);
    }
    const double ssr = record.gap.whitened_ssr;
    context->records[record.mask] = std::move(record);
    if (t.Rejected()) continue;  // neither selected nor a rival of the selected one
    refined->emplace_back(to_fit[c], t.test);
    if (!t.worsens.empty()) continue;  // a rival, but not the one selected
    if (best < 0 || ssr < best_ssr) {
      best = static_cast<int>(c);
      best_ssr = ssr;
    }
  }
  return best;
}

// Refines `to_fit` on top of `selected` in the folds and judges them; returns the plausible candidate
// with the smallest held-out residual (null when there is none).
EffectKind FitAndJudge(SelectionContext* context, const AllDataModel& all_data, const std::vector<EffectKind>& to_fit,
                       EffectMask selected, int step, bool* delay_searched, ForwardSelection* forward,
                       ForwardStep* added, PhaseTimer* timer) {
  const DiagnosisOptions& options = context->options;
  const ModelRecord& base = context->records.at(selected);
  std::vector<EffectMask> masks;
  std::vector<std::vector<Effects>> initial;
  for (EffectKind kind : to_fit) {
    if (kind->stage() == EffectStage::kRotorSignal && !*delay_searched) {
      *delay_searched = true;
      RefineOptions search;  // the linear model, no effects, over the diagnosis' delay range
      search.delay_search = options.delay_search;
      search.num_threads = options.num_threads;
      const EffectKind searched =
          *std::find_if(AllEffects().begin(), AllEffects().end(), [](EffectKind k) { return k->info().grid_searched; });
      forward->initial_delay_s = CoarseDelaySearch(all_data.linear, search, searched);
      timer->Mark("coarse delay search");
    }
    masks.push_back(selected | Bit(kind));
    initial.push_back(WarmStarts(kind, selected, base, forward->tested[kind].linearized_step, forward->initial_delay_s,
                                 context->vehicle));
  }
  std::vector<ModelRecord> fitted = context->fitter.Fit(masks, initial);
  timer->Mark("step " + std::to_string(step) + " fold refinements");
  const int best = JudgeRefined(context, to_fit, base, selected, std::move(fitted), &forward->tested, &added->refined);
  return best < 0 ? nullptr : to_fit[best];
}

// A timing effect that removed practically the same held-out residual as `best` at this step (a
// delay and a motor lag) is its twin: the final model decides between them at half the cut-off.
void NoteTimingTwin(EffectKind best, const TestedCandidates& tested, ForwardStep* step) {
  if (!best->info().checked_at_half_cutoff) return;
  const double best_shrink = tested.at(best).test.shrink_pct;
  for (const auto& [other, test] : step->refined) {
    if (other == best || !other->info().checked_at_half_cutoff || !test.significant) continue;
    if (std::abs(best_shrink - test.shrink_pct) < kPracticalEquivalence * std::max(best_shrink, test.shrink_pct)) {
      step->timing_twin = other;
      step->timing_twin_test = test;
      return;
    }
  }
}

}  // namespace

ForwardSelection SelectForward(SelectionContext* context, const AllDataModel& all_data, PhaseTimer* timer) {
  const DiagnosisOptions& options = context->options;
  ForwardSelection forward;
  bool delay_searched = false;
  EffectMask selected = 0;
  for (int step = 1;; ++step) {
    if (static_cast<int>(forward.selected.size()) >= options.max_effects) break;
    std::vector<EffectKind> remaining;
    for (EffectKind kind : options.candidates) {
      const auto t = forward.tested.find(kind);
      if (!Has(selected, kind) && (t == forward.tested.end() || !t->second.Rejected())) remaining.push_back(kind);
    }
    if (remaining.empty()) break;
    std::vector<EffectKind> to_fit =
        ScreenCandidates(all_data, options, step, selected, context->records.at(selected), remaining, &forward.tested);
    timer->Mark("step " + std::to_string(step) + " screening");
    ForwardStep added;
    EffectKind best_kind = nullptr;
    // When the leaders fail out of sample (an acc bias that predicts much in sample and makes the
    // held-out gap worse), the candidates screened out as their rivals get their turn before the
    // selection stops.
    while (!best_kind && !to_fit.empty()) {
      best_kind = FitAndJudge(context, all_data, to_fit, selected, step, &delay_searched, &forward, &added, timer);
      if (best_kind && !forward.tested[best_kind].test.significant) best_kind = nullptr;
      for (EffectKind kind : to_fit) remaining.erase(std::find(remaining.begin(), remaining.end(), kind));
      to_fit = CandidatesWorthRefining(remaining, forward.tested, options);
    }
    if (!best_kind) break;
    NoteTimingTwin(best_kind, forward.tested, &added);
    const EffectTest best_test = forward.tested[best_kind].test;
    added.base = selected;
    added.selection.added = best_kind;
    added.selection.before = context->records.at(selected).gap;
    selected |= Bit(best_kind);
    added.selection.after = context->records.at(selected).gap;
    added.selection.test = best_test;
    forward.steps.push_back(std::move(added));
    forward.selected.push_back(best_kind);
  }
  return forward;
}

void SwapTimingTwin(const SelectionContext& context, const TimingSeparation& separation, ForwardStep* step) {
  SelectionStep& selection = step->selection;
  std::swap(selection.added, step->timing_twin);
  std::swap(selection.test, step->timing_twin_test);
  step->timing_separation = separation;
  selection.after = context.records.at(step->base | Bit(selection.added)).gap;
}

BackwardElimination EliminateBackward(SelectionContext* context, const std::vector<EffectKind>& selected) {
  BackwardElimination result;
  result.kept = selected;
  EffectMask mask = MaskOf(selected);
  for (bool changed = true; changed && result.kept.size() >= 2;) {
    changed = false;
    for (size_t i = 0; i < result.kept.size(); ++i) {
      const EffectKind kind = result.kept[i];
      const EffectMask others = mask & ~Bit(kind);
      EnsureFitted(context, {others}, mask);
      if (!context->records.count(others)) continue;
      const EffectTest test = TestAddedEffects(context->records.at(others).gap, context->records.at(mask).gap,
                                               kind->FreeDimension(context->vehicle), context->options.alpha,
                                               context->options.min_shrink_pct);
      if (test.significant) continue;
      result.dropped.push_back({kind, others, test});
      mask = others;
      result.kept.erase(result.kept.begin() + static_cast<std::ptrdiff_t>(i));
      changed = true;
      break;
    }
  }
  return result;
}

std::vector<SelectionStep> GapAfterEachEffect(SelectionContext* context, const std::vector<EffectKind>& kept) {
  EffectMask prefix = 0;
  std::vector<EffectMask> prefixes;
  for (EffectKind kind : kept) prefixes.push_back(prefix |= Bit(kind));
  EnsureFitted(context, prefixes, prefix);
  std::vector<SelectionStep> steps;
  prefix = 0;
  for (EffectKind kind : kept) {
    SelectionStep s;
    s.added = kind;
    s.before = context->records.at(prefix).gap;
    prefix |= Bit(kind);
    if (!context->records.count(prefix)) break;
    s.after = context->records.at(prefix).gap;
    s.test = TestAddedEffects(s.before, s.after, kind->FreeDimension(context->vehicle), context->options.alpha,
                              context->options.min_shrink_pct);
    steps.push_back(s);
  }
  return steps;
}

}  // namespace rotorid::internal

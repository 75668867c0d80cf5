#pragma once

// Diagnosis of the sim-to-real gap (MODEL.md section 5): where the rigid-body + rotor model's
// residual lies, which unmodelled effect causes it, and how far the held-out gap shrinks once that
// effect is added. docs/diagnosis.md explains how to read the result.
//
//   DiagnosisOptions options;                       // all candidate effects, 4 time-blocked folds
//   Diagnosis d = Diagnose(ProcessFlights(flights, options.identify.observation), {}, options);
//   std::cout << DiagnosisVerdict(d);
//
// Which effect is judged only on data that was not used to fit it: K contiguous blocks of every
// flight (each block is held out in turn, the model refined on the others) or separate held-out
// flights. Effects enter by forward selection: every candidate is refined on top of the effects
// selected so far, the one that removes the most held-out residual is kept when an F-test on the
// whitened held-out residuals (effective sample size corrected for autocorrelation, charged for
// the parameters the effect adds) is significant and its held-out shrink exceeds a floor learned
// from clean simulated flights. A backward pass then drops a kept effect that is no longer
// significant on top of the others.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rotorid/diagnosis/gap_location.h"
#include "rotorid/ident/identify.h"
#include "rotorid/model/effects.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

// The diagnosis' candidates by default (`diagnose --effects all`): DefaultCandidates() and the
// vehicle's own effects a blind diagnosis must also consider, which `refine --effects all` leaves out
// (an estimate of theirs is only worth refining where the diagnosis names them): per-rotor thrust
// scales and the IMU lever arm (x, y; z held). docs/diagnosis.md, "Thrust scales and lever arms".
std::vector<EffectKind> DiagnosisCandidates();

struct DiagnosisOptions {
  // Signal processing and TLS of the linear model (the baseline).
  IdentifyOptions identify;
  // Effects considered as causes of the gap.
  std::vector<EffectKind> candidates = DiagnosisCandidates();
  // Time-blocked folds per flight when no held-out flights are given.
  int folds = 4;
  // Rows within this many seconds of a held-out block are left out of its training data, so that
  // the low-pass filter's memory does not leak the held-out residual into the fit.
  double guard_s = 0.5;
  // Level of the F-test of each added effect (one-sided; about 5 candidates x 3 steps share it).
  double alpha = 1e-3;
  // Held-out gap reduction (% of the whitened residual) an effect must exceed to be kept, learned
  // from clean simulated flights (docs/diagnosis.md): below it, improvements are of the size that
  // small simulation/model mismatches produce on clean data.
  double min_shrink_pct = 0.3;
  // Candidates whose first-order (linearised) in-sample shrink on top of the current model is below
  // this fraction of min_shrink_pct are not refined in the folds: an effect removes less residual out
  // of sample than in sample, so they cannot pass. Saves most of the refinements on clean data.
  double screen_fraction = 0.5;
  // ... and so are those whose first-order shrink is below this fraction of the best candidate's at
  // that step: they cannot remove the most held-out residual (they are refined at the next step, on
  // top of the winner, if they pass the screening there).
  double rival_fraction = 0.7;
  // A candidate that removes held-out residual in some components but makes a scored component's
  // held-out residual RMS grow by more than this (%), significantly at level component_growth_alpha
  // (one-sided, paired per row), over the model it is added to or over the linear model, is not
  // selected at that step: it trades components rather than explaining the gap (real jana06: an IMU
  // lever arm removed 48 % of Fy and 13 % of Mx and added 21 % to My, t = 1.85 with the residual's
  // autocorrelation; docs/diagnosis.md, "No component worse"). A guard: the burden of proof is on the
  // candidate, so its level is loose.
  double max_component_growth_pct = 5.0;
  double component_growth_alpha = 0.05;
  // Forward selection stops after this many effects.
  int max_effects = 3;
  // Start of the delay (and lag) candidate in the folds: a coarse search of the TLS criterion over
  // this grid, which also bounds the delay in every refinement; its range in 10 ms steps is the
  // delay's screening grid.
  DelaySearch delay_search;
  // Ceres iterations per fold refinement (warm-started, they rarely need more; the nearly flat
  // delay/lag ridge is where more would be spent for no change of the criterion).
  int refine_max_iterations = 20;
  // RefineOptions::reselect_essential in the fold refinements: parameters an effect made
  // unidentifiable in the linear model (a motor lag spoils kd and I_zz) come back, so the held-out
  // gap with the effect is the one `rotorid refine` would reach. Off: about half the cost.
  bool reselect_essential = true;
  // Where: frequency bands, stretches of the flight.
  GapLocationOptions location;
  // What no candidate explains (Diagnosis::unexplained): a component whose held-out gap after the
  // selection is at least this many times its noise floor (then at least 89 % of its residual energy
  // is model error), and whose model error beyond the floor is at least unexplained_min_pct (% of the
  // rotor wrench; Fx, Fy of the thrust). Clean simulated flights end at 1.0-1.3 x the floor
  // (docs/diagnosis.md, "What no candidate explains").
  double unexplained_floor_ratio = 3.0;
  double unexplained_min_pct = 1.0;
  // Refinements run in parallel on this many threads.
  int num_threads = 2;

  std::string Validate() const;
};

// The held-out gap of one model: pooled over all held-out blocks (or flights).
struct HeldOutGap {
  std::vector<std::optional<double>> relative_error_pct;  // Table III per component (null: 0 denominator)
  std::vector<std::optional<double>> gap_pct;             // as relative_error_pct; Fx, Fy against the thrust
  Eigen::Matrix<double, 6, 1> residual_rms = Eigen::Matrix<double, 6, 1>::Zero();  // N or N m
  // The part of the gap that the sensor noise alone explains (from the noise levels of the signals
  // propagated through the regressor) and the rest, sqrt(max(0, gap^2 - floor^2)): the model error.
  std::vector<std::optional<double>> noise_floor_pct;
  std::vector<std::optional<double>> model_error_pct;
  double whitened_ssr = 0.0;            // sum of squared residuals, each flight and component scaled so that the
                                        // baseline's mean square is 1
  int entries = 0;                      // residual entries (6 per held-out row sample)
  double autocorrelation_factor = 1.0;  // variance inflation of the whitened residuals
};

// Whether adding effects to a model removes significantly more held-out residual than noise.
struct EffectTest {
  double shrink_pct = 0.0;   // 100 (1 - SSR_with / SSR_without), whitened held-out residual
  double f_statistic = 0.0;  // ((SSR_without - SSR_with) / q) / (SSR_with / (n_eff - q))
  double p_value = 1.0;
  int added_parameters = 0;        // q
  double effective_samples = 0.0;  // n_eff = entries / autocorrelation factor
  bool significant = false;        // p < alpha and shrink_pct > min_shrink_pct
  // Not refined in the folds: shrink_pct, F and p are the linearised in-sample ones (a score test),
  // which were below the screening threshold.
  bool screened = false;
};

// The scale-free test of a candidate whose signature lies mostly in a component the held-out score
// leaves out (Mz when the linear identification discarded kd: the yaw row I_zz w_z' + J sum(+-Omega')
// = kd sum(+-Omega^2) fixes only ratios to kd, not their common scale). That component's row alone is
// fitted with its rotor coefficient's column fixed at 1, every other coefficient a ratio to it, on the
// same held-out folds or flights, without and with the candidate; its held-out relative error
// (||row residual|| / ||rotor term||, Table III's, which the common scale drops out of) is what the
// F-test judges (docs/diagnosis.md, "The scale-free test of an unscored component").
struct ScaleFreeTest {
  int component = 5;                       // the row tested (kWrenchComponentNames)
  std::string rotor_coefficient;           // its rotor coefficient, fixed at 1: "kd" (Mz) or "kt"
  EffectTest test;                         // held out: the whitened row residual without vs with the candidate
  double relative_error_before_pct = 0.0;  // held out, without the candidate
  double relative_error_after_pct = 0.0;   // held out, with it
  // Fitted on all identification data, per coordinate: the value in the units the row fixes, a
  // ratio to the rotor coefficient where the candidate's term does not scale with it (a rotor
  // inertia's torque: J / kd, dimensionless), else the parameter itself; with its label
  // ("rotor_inertia_kgm2 / kd") and std.
  std::vector<std::string> labels;
  Eigen::VectorXd ratio, ratio_std;
  std::vector<bool> over_rotor_coefficient;
  // The value in SI (ratio times the rotor coefficient of the final fit), only when that fit fixes
  // the coefficient (relative std below 10 %); else empty.
  Eigen::VectorXd value, std;
  // Significant, but with a sign its physics excludes (J / kd < 0 beyond 3 std): which, else empty.
  std::string implausible;
};

// One candidate effect, as the diagnosis judged it.
struct EffectVerdict {
  EffectKind kind = nullptr;
  // "selected", "confounded" (significant alone, but indistinguishable from a selected effect),
  // "implausible" (significant, but only with a value outside its physical range: it absorbs something
  // else, and is never selected; `implausible` says which value and range), "negligible" (significant,
  // but with a value below the size that matters for that effect: never selected; `negligible` says
  // which), "worsens a component" (significant, but a held-out component got worse beyond its noise:
  // not selected at that step; `worsens` says which), "not significant", or
  // "unavailable" (a flight lacks an input it needs: `note` says which).
  std::string status;
  bool selected = false;
  bool significant = false;
  int step = 0;                              // forward-selection step at which it was last tested (1-based)
  std::vector<EffectKind> tested_on_top_of;  // the effects already selected at that step
  EffectTest test;                           // added on top of tested_on_top_of
  std::optional<EffectTest> alone_test;      // added to the linear model alone (step 1)
  EffectTest screening;                      // first-order in-sample test at `step` (always computed)
  // Magnitude: selected effects from the final fit on all data, the others the mean of their fold
  // fits; std from the linearised criterion (chi and the selected effects profiled out, inflated
  // for autocorrelation).
  Eigen::VectorXd value;
  Eigen::VectorXd std;
  // Smallest size per parameter that this data would reveal as significant (F-test and shrink
  // floor), from the same linearisation.
  Eigen::VectorXd detectable_above;
  std::vector<std::optional<double>> relative_error_pct;  // held-out, with it added
  std::vector<EffectKind> confounded_with;
  // Selected by the forward selection, then dropped by the backward pass: not significant on top of
  // the effects selected after it (`test` is that test).
  bool dropped_as_redundant = false;
  std::string note;  // one line for people
  // Status "implausible": which value lies outside which physical range (also in `note`).
  std::string implausible;
  // Status "negligible": which value lies below which size, and why that size (also in `note`).
  std::string negligible;
  // Status "worsens a component": significant, but it made a held-out component worse beyond its
  // noise (DiagnosisOptions::max_component_growth_pct): which, by how much (also in `note`).
  std::string worsens;
  // Selected delay or motor lag: its value refitted at half the low-pass cut-off, where a true one
  // holds and one the controller's reply to sensor noise fakes vanishes (also in `note`).
  std::string held_at_half_cutoff;
  // Selected, and its value is relative to a known value the vehicle file does not give
  // (EffectDescriptor::UnstatedReference: rotor_drag's k_f and the IMU's height; also in `note`).
  std::string unstated_reference;
  // Not selected, and most of its signature falls in a component no test scores (Mz when the linear
  // identification discarded kd): why this data cannot rule it out (also in `note`).
  std::string unscored;
  // Its scale-free test there (ScaleFreeTest), when it was run. A candidate that passes it is
  // selected (`status` "selected", `test` this test's) but not refined into the final model, whose
  // scale for it the data do not fix: `value` and `std` are then its SI value when the final fit
  // fixes the rotor coefficient, else empty.
  std::optional<ScaleFreeTest> scale_free;
};

struct ConfoundedEffects {
  EffectKind selected = nullptr;
  EffectKind other = nullptr;
  // Largest |correlation| between their parameters with both in the final model (linearised
  // criterion on all data), with the labels it occurs between.
  std::optional<double> correlation;
  std::string correlated_labels;
  double selected_shrink_pct = 0.0;  // each alone on top of the same model, held-out
  double other_shrink_pct = 0.0;
  // Paired comparison of their held-out residuals (per row sample, autocorrelation-robust
  // variance): t > 0 when `selected` fits better; distinguishable when p < alpha.
  double t_statistic = 0.0;
  double p_value = 1.0;
  bool distinguishable = false;
  std::string note;
};

// One kept effect, in the order they were added: the held-out gap before and after (on top of the
// kept effects added before it).
struct SelectionStep {
  EffectKind added = nullptr;
  HeldOutGap before;
  HeldOutGap after;
  EffectTest test;
};

// What remains after the selection that no candidate explains (INTERFACE.md 6, `unexplained[]`): a
// held-out component whose gap with the selected effects lies far above its noise floor
// (DiagnosisOptions::unexplained_floor_ratio, unexplained_min_pct).
struct UnexplainedResidual {
  int component = 0;  // kWrenchComponentNames
  // Held out, with the selected effects (Fx, Fy against the thrust): the gap, its noise floor, and
  // the share of the component's held-out residual energy beyond that floor, 100 (1 - floor^2 / gap^2).
  double gap_pct = 0.0;
  double noise_floor_pct = 0.0;
  double share_pct = 0.0;
  // Where it lies: the frequency band holding most of the final model's residual energy in the
  // component (identification data), with that share; the worst stretch of the flight (of the
  // linear model's residual) this component dominates, when one does.
  double band_low_hz = 0.0;
  double band_high_hz = 0.0;
  double band_share_pct = 0.0;
  std::optional<FlightStretch> stretch;
  // What it can be: "a force off the thrust axis that no sensor effect reproduces: ...".
  std::string note;
};

struct Diagnosis {
  std::string validation;  // "4 time-blocked folds of 1 flight" or "2 held-out flights"
  int held_out_row_samples = 0;
  std::vector<EffectKind> candidates;
  HeldOutGap baseline;      // linear model, held-out
  int where_component = 0;  // largest baseline model_error_pct (the gap beyond the noise floor)
  GapLocation where;
  std::vector<EffectVerdict> ranking;  // selected in order, then the others by shrink
  // Every selected effect: those a scale-free test selected (selected_scale_free) first, then the
  // final model's (final_effects, steps) in the order they were added.
  std::vector<EffectKind> selected;
  // Selected by the scale-free test of a component the held-out score leaves out: not in the final
  // model (EffectVerdict::scale_free).
  std::vector<EffectKind> selected_scale_free;
  // The selected effects the final model carries, in the order they were added.
  std::vector<EffectKind> final_model;
  std::vector<SelectionStep> steps;
  HeldOutGap final_gap;  // with the selected effects, held-out
  // What the selected effects leave far above the noise floor; empty when nothing is left.
  std::vector<UnexplainedResidual> unexplained;
  // The final model fitted on all identification data.
  std::map<std::string, double> linear_parameters;
  std::map<std::string, double> final_parameters;
  // Their std (empty when not known: the final fit's covariance can be rank deficient); the
  // physical checks count a violation only beyond 3 std.
  std::map<std::string, double> linear_parameter_std;
  std::map<std::string, double> final_parameter_std;
  // What each model predicts with (PredictionChi: a discarded inertia within the range a body allows),
  // which physical_consistency checks.
  std::map<std::string, double> linear_predicts_with;
  std::map<std::string, double> final_predicts_with;
  Effects final_effects;
  Effects final_effects_std;
  std::vector<ConfoundedEffects> confounded;
  double initial_delay_s = 0.0;  // coarse delay search result
  int refinements = 0;
  double seconds = 0.0;
  std::vector<std::pair<std::string, double>> phase_seconds;  // where the time went
  std::vector<std::string> warnings;
};

// Progress of the fold refinements, the diagnosis's long work, batch by batch: `done` of the
// `total` refinements of the current batch (every model it compares, in every fold), with a label
// that names the batch ("fitting 8 models in 4 folds"). Called under a lock, one call at a time.
using DiagnosisProgress = std::function<void(const std::string& batch, int done, int total)>;

// Diagnoses the identification flights; `held_out` (may be empty) replaces the time-blocked folds.
// Throws rotorid::Error on invalid options, when the linear model cannot be identified, or when a
// held-out flight's configuration is not among the identification flights.
Diagnosis Diagnose(const std::vector<ProcessedFlight>& flights, const std::vector<ProcessedFlight>& held_out,
                   const DiagnosisOptions& options, const DiagnosisProgress& progress = {});

// A short human verdict: which component, which band and stretch, which effect with its magnitude
// and std, the shrink, and the held-out gap per component before and after.
std::string DiagnosisVerdict(const Diagnosis& diagnosis);

// Formats an effect's value with std in the effect's natural unit ("12.31 +- 0.14 ms").
std::string FormatEffectMagnitude(EffectKind kind, const Eigen::VectorXd& value, const Eigen::VectorXd& std);

}  // namespace rotorid

#pragma once

// Gray-box refinement (MODEL.md section 4): starting from the TLS solution, a Ceres problem refines
// the same parameters jointly with unmodelled effects. The criterion is the TLS one,
//     sum_i lambda_i (w_i(effects) . chi_t)^2 / (chi_t^T N chi_t)  (up to a constant factor),
// with the row weights lambda and column metric N of the TLS step, so that with every effect off
// it returns the TLS solution and any difference is caused by the effects alone. The "anchored"
// variant (MODEL.md 9, the default) also divides each moment row by the rotor-signal effects' gain
// on the part of its residual that passes through the rotor moment (idim_residual.h), so that an
// effect which only attenuates the rotor moment cannot win by letting the inertia shrink with it;
// with no rotor-signal effect it is the TLS criterion.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/core/step_progress.h"
#include "rotorid/ident/identify.h"
#include "rotorid/model/effects.h"

namespace rotorid {

// The global search of the command-to-IMU delay (the grid-searched effect) and the bounds a
// refinement keeps it in: one range and step for refine, delay and diagnose, so that every command
// searches the same delays and bounds the delay alike.
struct DelaySearch {
  double min_s = -0.1;
  double max_s = 0.2;
  double step_s = 0.004;

  // min, min + step, ... up to max.
  std::vector<double> Grid() const;
  // Empty when valid, else a message naming the violated constraint.
  std::string Validate() const;
};

struct RefineOptions {
  // Effects whose parameters are estimated; the others are held at their initial values.
  std::vector<EffectKind> effects = AllEffects();
  // Initial (and, for disabled effects, fixed) values.
  Effects initial;
  // Grid-searched effects (the delay) start from a global search of the TLS criterion over this
  // range, which also bounds them.
  bool coarse_delay_search = true;
  DelaySearch delay_search;
  // Robust loss on the whitened residuals: "none", "huber" or "cauchy", with its scale.
  std::string robust_loss = "none";
  double robust_scale = 3.0;
  // "anchored" or "tls" (see above).
  std::string criterion = "anchored";
  // The other effects are kept in the physical bounds of their descriptors (beyond them the model
  // is not what is wrong); an estimate that ends on a bound is reported as such.
  int max_iterations = 100;
  bool compute_covariance = true;
  int num_threads = 1;
  // After a first refinement, re-run the TLS (with its essential-parameter selection) on the rows
  // corrected by the estimated effects, and refine again from there: parameters that the effects
  // had made unidentifiable (a delay spoils the yaw equation, say) come back. Off: the linear
  // step's discarded parameters stay fixed at zero.
  bool reselect_essential = true;
  // Physically consistent bodies by construction (MODEL.md 10): each configuration's first moment and
  // inertia move on the log-Cholesky chart of its pseudo-inertia with the known mass held, started from
  // the TLS estimate's nearest body in its metric. Off: the unconstrained refinement.
  bool consistent_bodies = true;

  std::string Validate() const;
  bool Enabled(EffectKind kind) const;
};

struct SolverReport {
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  std::string termination;
  std::string message;
  double seconds = 0.0;
  std::string full_report;  // Ceres' FullReport()
};

// How the refinement kept its bodies physical (RefineOptions::consistent_bodies).
struct BodyConstraint {
  std::vector<std::string> charted;  // the bodies on a log-Cholesky chart ("A")
  std::vector<std::string> notes;    // what is not, and why
  // The TLS estimate that started the final pass, where it was no body: its distance (std of that
  // estimate) to the body the pass started from, per body ("A 12.3 std"); the largest of them.
  std::vector<std::string> start_moved;
  double start_distance_std = 0.0;
  // The unconstrained optimum's distance from the refined (consistent) estimate, in the refined std:
  // one Gauss-Newton step from it with the chart lifted (0 where no body bounds the estimate; 0 without
  // a covariance); the parameter that moves most, in its std ("A.ms_z 2.1 std").
  double unconstrained_distance_std = 0.0;
  std::string largest_move;
};

struct RefineResult {
  TlsSolution refined;  // chi, covariance and std of the refined parameters and which are essential
  // The TLS on effect-corrected rows that started the final pass (when essential parameters were
  // re-selected); its discarded list says what the refinement still cannot identify.
  std::optional<TlsSolution> reselected;
  Effects effects;
  Effects effects_std;
  std::vector<EffectKind> enabled;
  // Enabled effects whose estimate ended on the bound of its physical range (not an estimate).
  std::vector<EffectKind> on_bound;
  // Correlation matrix of the enabled effects' scalar parameters, with their labels
  // (delay_s, motor_tau_s, acc_bias_x, ...).
  std::vector<std::string> effect_labels;
  Eigen::MatrixXd effect_correlation;
  std::vector<std::optional<double>> relative_error_pct;  // identification flights, refined model
  double linear_criterion = 0.0;  // TLS criterion (mean squared whitened residual) before and after
  double refined_criterion = 0.0;
  // Factor by which autocorrelated residuals inflate the parameter variance (already applied).
  double autocorrelation_factor = 1.0;
  SolverReport solver;
  // The std of the refined parameters and effects were computed (options.compute_covariance and a
  // full-rank problem); otherwise they are 0 meaning "not known".
  bool has_covariance = false;
  // The joint problem was rank-deficient: these parameters and effect coordinates span its null space.
  bool rank_deficient = false;
  std::vector<std::string> confounded;
  // Effect coordinates that a parameter held at 0 by the essential selection would explain almost
  // entirely ("imu_position_m_z ~ B.ms_z"): their value assumes that parameter is 0.
  std::vector<std::string> resting_on_discarded;
  BodyConstraint body_constraint;
  std::vector<std::string> warnings;
};

// Steps Refine reports: the coarse delay search when it runs, then each Ceres pass (at most four
// with the re-selection); a refinement that settles early jumps to the total.
int RefineSteps(const RefineOptions& options);
RefineResult Refine(const IdentificationResult& linear, const RefineOptions& options,
                    const StepProgress& progress = {});

// The coarse global search Refine starts a grid-searched effect from (options.delay_search_*, the
// other effects at options.initial): the grid value with the smallest TLS criterion, searched coarse
// to fine (internal::CoarseToFineGridMinimum: every third grid value, then the best one's neighbours).
double CoarseDelaySearch(const IdentificationResult& linear, const RefineOptions& options, EffectKind kind);

// Table III of several flights with named parameters and effects applied.
std::vector<std::optional<double>> RelativeErrorWithEffects(const std::vector<ProcessedFlight>& flights,
                                                            const std::map<std::string, double>& parameters,
                                                            const Effects& effects);

// Named parameter values of a solution.
std::map<std::string, double> NamedParameters(const IdimLayout& system, const Eigen::VectorXd& chi);

// The TLS criterion (mean squared whitened residual, minimised over the essential parameters with
// the linear solution's weights and metric) of the flights with these effects applied.
double EffectCriterion(const IdentificationResult& linear, const Effects& effects);

}  // namespace rotorid

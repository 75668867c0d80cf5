#pragma once

// The residual of the IDIM model at a point (parameters, effects) and its derivatives with respect
// to the parameters chi and to effect parameters (internal). Used for the effect signatures of the
// where-analysis, for the std of fitted effects and for the smallest detectable size of absent
// ones. Rows are scaled per flight and wrench component by the residual's RMS there, so that every
// component weighs the same (the held-out scores are scaled the same way).
//
// Ceres' covariance in the refinement is not used for these std: its dense SVD with a fixed
// reciprocal condition number drops weak directions of the unequilibrated Jacobian (the rotor
// columns are ~1e6 times the others), which makes gyro-bias and acc-bias-z std come out orders of
// magnitude too small. Here the columns are equilibrated first.

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/ident/observation.h"
#include "rotorid/model/effects.h"

namespace rotorid::internal {

// Residual rho = W(effects) chi_t and rotor-model wrench -(W[:, 0:2] chi_t[0:2]) of one flight at
// its row samples (row sample x component).
struct FlightResidual {
  Eigen::MatrixXd residual;
  Eigen::MatrixXd rotor_wrench;
};
FlightResidual ResidualOf(const ProcessedFlight& flight, const std::map<std::string, double>& parameters,
                          const Effects& effects);

// Names (as in NamedParameters) of the parameters the linear solution estimates: the essential ones
// and the profiled ones PredictionChi predicts with (not the rotor coefficients); the chi columns of a
// linearisation around it, as the refinement keeps them free.
std::vector<std::string> EstimatedParameterNames(const IdentificationResult& linear);

// Labels of an effect's scalar parameters for this vehicle: {"delay_s"} or {"acc_bias_x", "acc_bias_y",
// "acc_bias_z"}.
std::vector<std::string> EffectLabels(EffectKind kind, const Vehicle& vehicle);

struct EffectLinearization {
  std::vector<EffectKind> kinds;       // effect blocks in column order
  std::vector<std::string> labels;     // one per effect column
  std::vector<int> column_kind;        // index into kinds, per effect column
  std::vector<Eigen::MatrixXd> held_directions;  // per kind (HeldDirections), held as the refinement holds them
  Eigen::VectorXd residual;            // scaled rho, all rows of all flights (sample-major, 6 per sample)
  Eigen::MatrixXd parameter_jacobian;  // scaled d rho / d chi, free parameters
  Eigen::MatrixXd effect_jacobian;     // scaled d rho / d effect parameters
  std::vector<int> row_component;      // 0..5 per row
  // Rows that carry weight: components the model leaves without rotor term (Mz when kd is
  // discarded; not Fx, Fy) get none, as in the held-out score.
  Eigen::Index scored_rows = 0;
  // Per effect column: the share of its signature (d rho / d effect in N m, forces times the mean
  // arm, squared, summed over the rows) that falls in components without weight. An effect acting
  // there (a rotor inertia on Mz with kd discarded) is invisible to every test here.
  Eigen::VectorXd effect_unscored_share;
  std::vector<int> unscored_components;  // components without weight in some flight
  double autocorrelation_factor = 1.0;   // of the scaled residual
  // The normal equations of [parameter_jacobian effect_jacobian]: its Gram matrix, the product with
  // the residual and the residual's square norm, from which every subset fit is a small solve.
  Eigen::MatrixXd gram;
  Eigen::VectorXd gram_residual;
  double residual_ssr = 0.0;
};

// Linearises the model of `flights` at (parameters, effects): chi columns for `free_parameters`
// (names as in NamedParameters), effect columns for `kinds` (derivatives by the rows' Jets, as in the
// refinement: src/refine/effect_rows.h). With max_row_samples > 0 and more row samples than that,
// the rows (residual, Jacobians, row_component) are those of every stride-th row sample of each
// flight only, stride = ceil(all / max_row_samples), and the normal equations are scaled by all / kept
// samples to stand for every row; the scales, scored_rows and the autocorrelation factor still come
// from the residual of every row sample. The Jets cost about 13 times the rows' values, so this bounds
// the cost and memory of a long log's linearisation. The Jets run on `num_threads` threads; the result
// is the same for any number.
EffectLinearization LinearizeEffects(const std::vector<ProcessedFlight>& flights,
                                     const std::map<std::string, double>& parameters,
                                     const std::vector<std::string>& free_parameters, const Effects& effects,
                                     const std::vector<EffectKind>& kinds, int max_row_samples = 0,
                                     int num_threads = 1);

// Weighted least squares of the scaled residual on chi and the effect columns of `subset`.
struct EffectSubsetFit {
  std::vector<std::string> labels;
  std::vector<EffectKind> column_kind;
  Eigen::VectorXd step;  // Gauss-Newton step of the effect parameters (chi profiled out)
  Eigen::VectorXd std;   // sigma * sqrt(autocorrelation factor * (J^T J)^-1)
  Eigen::MatrixXd correlation;
  Eigen::VectorXd residual_correlation;  // cosine of the residual with each chi-projected signature
  double predicted_shrink = 0.0;         // fraction of the residual the step removes
  double effective_samples = 0.0;        // rows / autocorrelation factor
};

EffectSubsetFit FitEffectSubset(const EffectLinearization& linearization, const std::vector<EffectKind>& subset);

// The entries of `per_column` (one per column of `fit`: its step, std, ...) that belong to `kind`.
Eigen::VectorXd EffectColumns(const EffectSubsetFit& fit, EffectKind kind, const Eigen::VectorXd& per_column);

}  // namespace rotorid::internal

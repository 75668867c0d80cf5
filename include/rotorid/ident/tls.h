#pragma once

// Total least squares on the IDIM (MODEL.md section 2): the paper's procedure and rotorid's
// noise-aware default, with statistics and essential-parameter selection.
//
// Both are Rayleigh-quotient problems over chi_t = [chi; 1]:
//     minimise  sum_i lambda_i (w_i . chi_t)^2 / (chi_t^T N chi_t)
// with row weights lambda_i and a column error metric N:
//   paper:       lambda from the per-component error spread (weighted TLS), N = identity on the raw
//                SI columns, i.e. the criterion ||W_t chi_t||^2 / (1 + |chi|^2);
//   noise-aware: lambda normalises every row to unit error variance, N is the covariance of the
//                errors in the row entries caused by sensor noise (exact columns such as the
//                commanded rotor signal get none) plus the equation error, which acts on the
//                column whose coefficient is fixed to 1. This is the errors-in-variables maximum
//                likelihood estimate (a generalized TLS); it is invariant to column scaling.
// The refinement minimises the same criterion with the same lambda and N, so that with every
// effect off it returns this solution.

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rotorid/ident/observation.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

// W_t of one or several flights (IdimSystem: its layout, IdimLayout, and the rows w). Flights of the same vehicle name
// share that configuration's chi; kt and kd are shared by all. Columns: [kt kd chi_config1 ... chi_configC | mass
// column]. A flight with a first-moment label (ProcessedFlight::first_moment_label, per-flight first moments) has its
// own three first-moment columns: its configuration's block is then [ms of its first label, ms of its second label,
// ..., the six inertia entries].
struct IdimLayout {
  std::vector<std::string> parameter_names;  // one per column but the last
  std::vector<std::string> config_names;
  // Per row: its group (wrench component + 6 * flight) and its sample number within the flight
  // (the 6 rows of one sample share it), for weighting and autocorrelation-robust statistics.
  std::vector<int> row_group;
  std::vector<int> row_sample;
  std::vector<double> flight_weight;
  std::vector<int> flight_config;              // configuration index per flight
  std::vector<std::string> flight_source;
  // Per flight, the system column of each of its nine body parameters.
  std::vector<std::array<int, kNumBodyParameters>> flight_body_columns;
  std::vector<Eigen::MatrixXd> group_noise_cov;  // per group, sum over its rows (columns as w)

  int num_parameters() const { return static_cast<int>(parameter_names.size()); }
  Eigen::Index num_rows() const { return static_cast<Eigen::Index>(row_group.size()); }  // equations
  int num_flights() const { return static_cast<int>(flight_weight.size()); }
  int num_groups() const { return 6 * num_flights(); }
  static int Component(int group) { return group % 6; }
  static int Flight(int group) { return group / 6; }
  // Column of a named parameter, -1 when the system has none.
  int Column(const std::string& name) const;
  // Column of this system that column k of flight f's own rows (BuildIdimMatrix: kt, kd, the nine
  // body parameters, the known column) goes to.
  int SystemColumn(int f, int k) const;
  // Writes flight f's own rows `wf` into w's columns, from `first_row` on.
  void PlaceFlightRows(int f, const Eigen::MatrixXd& wf, Eigen::Index first_row, Eigen::MatrixXd* w) const;
};
// The layout and its rows. The layout apart lets the refinement pair the same layout with rows
// corrected by effects without copying the linear rows first (W_t of a 1 h log is 100 MB).
struct IdimSystem : IdimLayout {
  Eigen::MatrixXd w;
};

IdimSystem BuildIdimSystem(const std::vector<ProcessedFlight>& flights);

enum class TlsMethod { kPaper, kNoiseAware };
const char* TlsMethodName(TlsMethod method);
TlsMethod ParseTlsMethod(const std::string& name);

struct TlsOptions {
  TlsMethod method = TlsMethod::kNoiseAware;
  // Paper III-B: weight rows by the inverse spread of their component's equation error.
  bool weight_by_component = true;
  // Essential parameters. Paper: drop the worst %sigma until max/min %sigma < r_sigma.
  bool select_essential = true;
  double r_sigma = 250.0;
  // Noise-aware: drop the worst parameter while its %sigma exceeds this (a parameter is kept when
  // it is known to better than this, whatever the others' precision).
  double max_rel_std_pct = 10.0;
  // Fixed-point iterations of the noise-aware weights.
  int max_iterations = 30;
  // Parameters (by name) never dropped and never estimated: held at 0 ("discard").
  std::vector<std::string> fixed_zero;
  // Parameters (by name) discarded before the selection starts, as if it had dropped them (the
  // refinement's re-selection holds those that come back with a sign their physics excludes).
  std::vector<std::string> discarded_from_start;

  std::string Validate() const;
};

struct DiscardedParameter {
  std::string name;
  double value = 0.0;             // estimate, std and %sigma at the moment it was dropped
  double std = 0.0;
  double rel_std_pct = 0.0;
  std::string most_correlated;    // the free parameter it was most correlated with
  double correlation = 0.0;
  std::string reason;
};

struct TlsSolution {
  TlsMethod method = TlsMethod::kNoiseAware;
  Eigen::VectorXd chi;            // all parameters; discarded ones are 0
  std::vector<bool> essential;
  Eigen::MatrixXd covariance;     // all parameters; rows/cols of discarded ones are 0
  Eigen::VectorXd std;
  Eigen::VectorXd rel_std_pct;
  std::vector<DiscardedParameter> discarded;
  // The criterion actually minimised (for the refinement): row weights and column metric.
  Eigen::VectorXd row_weight;     // lambda_i
  Eigen::MatrixXd column_metric;  // N, (p+1)x(p+1)
  double sigma_w = 0.0;           // paper eq. 19 (paper) or the RMS whitened residual (noise-aware)
  Eigen::VectorXd singular_values;  // of the final weighted (and, noise-aware, whitened) system
  double scale_entry = 1.0;       // |last entry| of the unit solution vector in equilibrated columns
  int iterations = 0;
  bool usable = true;
  std::string message;            // why it is not usable
  std::vector<std::string> warnings;
  // Discarded parameters whose physics excludes 0 (PositiveByPhysics: kt, kd, the inertia's
  // diagonal), noise-aware method: not reported (chi, std and covariance hold 0, as for the other
  // discarded ones) but estimated beside the essential ones,
  // in the TLS and in the refinement. Held at 0 their signal would stay in the rows and move the
  // parameters whose columns correlate with it: on a take-off flight with little yaw, I_zz w'_z left
  // in the yaw rows moved the first moment through the lateral specific force (c x w' in the
  // accelerometer), and per-rotor thrust scales took its place (docs/method.md 3).
  std::vector<bool> profiled;
  Eigen::VectorXd profiled_chi;  // their estimates, 0 elsewhere (the refinement starts there)
  Eigen::VectorXd profiled_std;  // and their std (the refinement's scale for them)
  bool Profiled(int k) const { return !profiled.empty() && profiled[k]; }
  // A discarded diagonal inertia entry: the range of values with which its configuration is a physical
  // body, the other parameters at what the model predicts with (SetAllowedRanges; NaN where not
  // computed), and the value the model predicts with when its profiled estimate lies outside that
  // range or it has none (NaN: PredictionChi's rule without the range).
  Eigen::VectorXd allowed_low, allowed_high;
  Eigen::VectorXd within_range_chi;
  bool HasAllowedRange(int k) const { return allowed_low.size() > k && std::isfinite(allowed_low[k]); }
  bool PredictsWithinRange(int k) const { return within_range_chi.size() > k && std::isfinite(within_range_chi[k]); }
};

TlsSolution SolveIdim(const IdimSystem& system, const TlsOptions& options);

// The essential-parameter selection's rule (TlsOptions: the paper's r_sigma ratio, or the noise-aware
// %sigma limit), one for the TLS and the refinement: the index of the parameter to drop from
// `rel_std_pct` (each estimated parameter's %sigma; negative: not a candidate), or -1 to keep them all.
int EssentialSelectionDrops(const Eigen::VectorXd& rel_std_pct, const TlsOptions& options);
// The record of dropping `columns[dropped]` from an estimate `chi` with `covariance` (both over
// `columns`): its value, std and %sigma, and the parameter it is most correlated with.
DiscardedParameter DiscardedOf(const std::vector<std::string>& names, const std::vector<int>& columns,
                               const Eigen::VectorXd& chi, const Eigen::MatrixXd& covariance, int dropped,
                               double rel_std_pct);
// std and rel_std_pct from the solution's chi and covariance; a discarded parameter keeps the %sigma
// at which it was dropped.
void SetStdFromCovariance(const std::vector<std::string>& names, TlsSolution* solution);

// The parameters a model predicts with: chi, and the profiled parameters' estimates in place of their
// zeros where PredictsWithProfiled (a discarded inertia is estimated beside the others, and its gyroscopic terms act in Mx and My:
// held at 0 in the prediction, jana06's Table III read Mx 29.1 % for 21.9 %), except the rotor
// coefficients': a discarded kd is no identified rotor term, so Mz keeps none and stays out of
// Table III (INTERFACE.md 5). The reported values stay chi (discarded: 0).
// A discarded inertia whose profiled estimate lies outside the range a physical body allows, or that
// has none, is predicted with a value inside that range (TlsSolution::within_range_chi).
Eigen::VectorXd PredictionChi(const TlsSolution& solution);
// Whether PredictionChi takes parameter k's profiled estimate (a profiled parameter, not a rotor
// coefficient, with the sign its physics requires): what the model estimates beside its essential
// parameters and predicts with. A profiled inertia estimated negative (jana04's PWM-driven I_xx
// -9.0e-6) is no inertia to predict with: it stays at 0, as reported.
bool PredictsWithProfiled(const TlsSolution& solution, int k);

// min over the essential parameters of sum_i lambda_i (w_i . chi_t)^2 / (chi_t^T N chi_t) / rows for
// the rows `w` (same layout as the system the solution came from), with the solution's lambda and N:
// the TLS criterion of other data (e.g. with an effect applied) under fixed weights.
double MinimumTlsCriterion(const Eigen::MatrixXd& w, const TlsSolution& solution);
// The columns of w that criterion uses: the essential parameters', then the known column.
std::vector<int> CriterionColumns(const TlsSolution& solution);
// The same criterion from any factor r of the weighted rows, r^T r = W^T diag(lambda) W over
// CriterionColumns (in that order; r need not be triangular): the delay's grid search assembles it
// from a factor of the columns that stay fixed along the grid.
double MinimumTlsCriterionOfFactor(const Eigen::MatrixXd& r, const TlsSolution& solution);
// The same criterion from the rows' CriterionColumns alone (rows x those columns, in that order),
// weighted and factored in place: no second W-sized matrix (W_t of a 1 h log is 100 MB).
double MinimumTlsCriterionOfColumns(Eigen::MatrixXd columns, const TlsSolution& solution);

// Table III of the paper: per wrench component, ||rho_j|| / ||W_k chi_k (j)|| in %, over the
// given rows (raw SI, unweighted); nullopt when the denominator is zero.
std::vector<std::optional<double>> RelativeErrorPct(const Eigen::MatrixXd& w, const Eigen::VectorXd& chi_t);

// The sums behind RelativeErrorPct, for rows that come in pieces with their own chi_t (flights of
// several configurations): Add each piece, then Pct.
struct RelativeErrorSums {
  std::vector<double> residual_sq = std::vector<double>(6, 0.0), rotor_sq = std::vector<double>(6, 0.0);
  void Add(const Eigen::Ref<const Eigen::MatrixXd>& w, const Eigen::VectorXd& chi_t);  // rows 6 per sample
  void Add(const RelativeErrorSums& other);
  std::vector<std::optional<double>> Pct() const;
};

}  // namespace rotorid

#pragma once

// Held-out data for the diagnosis (internal): time-blocked folds of the identification flights,
// the residual of a fitted model on the held-out rows, and the held-out gap and F-test built
// from it.

#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "diagnosis/linearization.h"
#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/ident/observation.h"

namespace rotorid::internal {

// A copy of `flight` whose IDIM rows are only these row samples (the signals are untouched, so
// delay, lag and filters see the whole flight).
ProcessedFlight WithRowSamples(const ProcessedFlight& flight, std::vector<int> row_samples);

struct Fold {
  std::vector<ProcessedFlight> train;
  std::vector<ProcessedFlight> evaluate;
  std::vector<int> evaluate_flight;  // which evaluation flight each `evaluate` entry belongs to
};

// Fold k holds out the k-th of `folds` contiguous blocks of every flight's rows; its training data
// is the rest of every flight without the rows within `guard_s` of the held-out block.
std::vector<Fold> TimeBlockedFolds(const std::vector<ProcessedFlight>& flights, int folds, double guard_s);

// A model's residual on held-out rows: contiguous segments, each of one evaluation flight.
struct HeldOutResidual {
  std::vector<int> flight;
  std::vector<FlightResidual> segments;
  // Per segment, the components that enter the whitened score: Fx and Fy always, the others when the
  // baseline models them (a discarded kd leaves the yaw equation without rotor term, and its tiny
  // residual would make every model that brings kd back look worse). Set from the baseline.
  std::vector<std::array<bool, 6>> scored;
  int row_samples() const;
};

// Per evaluation flight (row) and component (column), from the baseline: the RMS of its residual
// (1 where it is 0), so that the baseline's mean square is 1 in every flight and component and the
// components weigh the same; and the RMS of its rotor-model wrench (0 where it has none), in Mx and
// My about each held-out segment's mean (the static moment a first moment balances is no scale).
struct HeldOutScales {
  Eigen::MatrixXd residual_rms;
  Eigen::MatrixXd wrench_rms;
};
HeldOutScales BaselineScales(const HeldOutResidual& baseline, int num_flights);

// The factor each entry of `model`'s residual is multiplied by, per evaluation flight and
// component: 1 / the baseline's residual RMS, times the baseline's rotor-wrench RMS over this
// model's where both have one. The second factor makes the score blind to a row group's free
// scale: in the yaw row kd and I_zz can shrink together (a delay the model lacks makes the linear
// fit do so), and a model's residual shrinks with them whether it is right or not; measured
// against its own rotor wrench, as Table III measures it, it cannot. In Mx and My the wrench is
// measured about its mean: else a static moment that a moved first moment cancels (per-rotor thrust
// scales near hover) inflates the divisor, and the score, without the residual falling.
Eigen::MatrixXd ResidualWeights(const HeldOutResidual& model, const HeldOutScales& scales);

// Expected sum of squared residuals per component that the white sensor noise of the signals
// causes in these rows (IdimNoiseCovariance with the fitted chi_t).
ComponentVector NoiseResidualSquares(const ProcessedFlight& flight, const std::map<std::string, double>& parameters);

// `noise_sq`: NoiseResidualSquares summed over the held-out rows (for the noise floor).
HeldOutGap ScoreHeldOut(const HeldOutResidual& residual, const HeldOutScales& scales, const ComponentVector& noise_sq);

// F-test of a nested model with `added_parameters` more effect parameters:
//   F = ((SSR_without - SSR_with) / q) / (a SSR_with / (N - q)),  F(q, N/a - q) under "no effect",
// with a the autocorrelation factor of the larger model's held-out residual. Out-of-sample, an
// effect fitted to noise makes the held-out residual larger, so the test is conservative.
EffectTest TestAddedEffects(const HeldOutGap& without, const HeldOutGap& with, int added_parameters, double alpha,
                            double min_shrink_pct);

// Non-nested comparison of two models on the same held-out rows: d = sum_j (e_b^2 - e_a^2) per row
// sample (residuals weighted by ResidualWeights), t = mean(d) / sqrt(long-run variance / n) with a Bartlett
// (Newey-West) long-run variance; p = P(N(0,1) > t). t > 0 when `a` fits better.
struct PairedComparison {
  double mean_difference = 0.0;
  double t_statistic = 0.0;
  double p_value = 1.0;
};
PairedComparison CompareHeldOut(const HeldOutResidual& a, const HeldOutResidual& b, const HeldOutScales& scales);

// A scored component whose held-out residual grew, on the same rows, beyond what noise makes of it:
// the RMS before and after (N or N m) and, measured as the score measures it (ResidualWeights: each
// against its own model's rotor wrench, so that a row group's free scale neither pays nor costs: true
// thrust scales on a paper flight raise Mz's residual 16 % with kd), the growth and the paired t
// statistic of the per-row growth of its squared residual (Bartlett long-run variance, as
// CompareHeldOut). An effect that removes residual in some
// components and adds it in another is a trade, not an explanation (real jana06: an IMU lever arm
// took 48 % of Fy and 13 % of Mx and added 21 % to My).
struct ComponentWorsening {
  int component = 0;
  double rms_before = 0.0;
  double rms_after = 0.0;
  double growth_pct = 0.0;
  double t_statistic = 0.0;
};
// The components scored in both whose model error (the residual beyond the noise floor; `noise_share`:
// the share of `without`'s residual sum of squares that the sensor noise explains, per component)
// grows by more than min_growth_pct from `without` to `with`, ends at least as large as the noise
// (a component left within sqrt(2) of its floor is not worse beyond its noise: independent
// CF_battery_motor_lag's true battery adds 5.6 % to Fy at 1.03 x its floor), with a one-sided p below
// alpha. growth_pct reports the whole residual's growth.
std::vector<ComponentWorsening> WorsenedComponents(const HeldOutResidual& without, const HeldOutResidual& with,
                                                   const HeldOutScales& scales, const ComponentVector& noise_share,
                                                   double min_growth_pct, double alpha);

// The in-sample score test of the screening: a first-order fit of the effect removes this
// fraction of the (scaled) residual; F = f / (1 - f) (N - q) / (q a) with N rows and a the
// autocorrelation factor (effective_samples = N / a).
EffectTest ScreeningTest(double shrink_fraction, int added_parameters, double effective_samples, Eigen::Index rows);

// Relative error per component (Table III: ||rho_j|| / ||rotor wrench_j||, null when 0) and the gap
// (Fx and Fy against the thrust instead) of residual / wrench sums of squares.
std::vector<std::optional<double>> RelativeErrorFromSums(const ComponentVector& residual_sq,
                                                         const ComponentVector& wrench_sq);
std::vector<std::optional<double>> GapFromSums(const ComponentVector& residual_sq, const ComponentVector& wrench_sq);

}  // namespace rotorid::internal

#pragma once

// Autocorrelation of residual series, for statistics that must not treat correlated samples as
// independent: the Newey-West lag of the TLS covariance, the variance inflation of the refinement's
// noise scale and of the diagnosis's held-out tests. One definition of the lag for all three.

#include <Eigen/Core>
#include <limits>
#include <vector>

namespace rotorid {

// The first lag in [1, max_lag) at which the pooled autocorrelation of `series` (contiguous pieces
// of one process, each correlated only with itself) falls below `threshold`; max_lag when it never
// does, 1 when max_lag <= 1 or the series are all zero.
Eigen::Index FirstLagBelow(const std::vector<Eigen::VectorXd>& series, double threshold, Eigen::Index max_lag);

// Factor by which autocorrelation inflates the variance of a mean over these series:
// 1 + 2 sum_l (1 - l/(L+1)) rho_l (Bartlett window) with L twice the first lag at which the pooled
// autocorrelation falls below 0.1, that lag searched up to max_search_lag, L at most a tenth of the
// samples and half the longest piece. At least 1; 1 for fewer than 20 samples or all-zero series.
double AutocorrelationFactor(const std::vector<Eigen::VectorXd>& series,
                             Eigen::Index max_search_lag = std::numeric_limits<Eigen::Index>::max());

// The Newey-West long-run sum of the columns s_t of `scores` (one column per sample):
// sum_t s_t s_t^T + sum_{l=1..lag} (1 - l/(lag+1)) (C_l + C_l^T), C_l = sum_t s_t s_{t+l}^T.
Eigen::MatrixXd BartlettLongRunSum(const Eigen::MatrixXd& scores, Eigen::Index lag);

}  // namespace rotorid

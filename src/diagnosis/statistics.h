#pragma once

// Small statistics the diagnosis needs (internal): the F distribution for the significance test
// and the variance inflation of autocorrelated residuals for its effective sample size.

#include <vector>

#include <Eigen/Core>

namespace rotorid::internal {

// Regularized incomplete beta function I_x(a, b), a, b > 0, x in [0, 1] (continued fraction).
double RegularizedIncompleteBeta(double a, double b, double x);

// P(F > f) for F ~ F(d1, d2) (d1, d2 > 0, real degrees of freedom allowed).
double FSurvival(double f, double d1, double d2);

// The f with P(F > f) = alpha, by bisection on FSurvival.
double FCritical(double alpha, double d1, double d2);

// Factor by which autocorrelation inflates the variance of a mean over these series (contiguous
// pieces of one process, e.g. held-out blocks): 1 + 2 sum_l (1 - l/(L+1)) rho_l with the lag L
// twice the first lag at which the pooled autocorrelation falls below 0.1 (Bartlett window, as the
// refinement's). At least 1.
double AutocorrelationFactor(const std::vector<Eigen::VectorXd>& series);

}  // namespace rotorid::internal

#pragma once

// Small statistics the diagnosis needs (internal): the F distribution for the significance test.
// The variance inflation of autocorrelated residuals is rotorid/signal/autocorrelation.h's.

#include "rotorid/signal/autocorrelation.h"

namespace rotorid::internal {

// Regularized incomplete beta function I_x(a, b), a, b > 0, x in [0, 1] (continued fraction).
double RegularizedIncompleteBeta(double a, double b, double x);

// P(F > f) for F ~ F(d1, d2) (d1, d2 > 0, real degrees of freedom allowed).
double FSurvival(double f, double d1, double d2);

// The f with P(F > f) = alpha, by bisection on FSurvival.
double FCritical(double alpha, double d1, double d2);

}  // namespace rotorid::internal

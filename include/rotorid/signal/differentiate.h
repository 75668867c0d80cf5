#pragma once

#include <Eigen/Core>

namespace rotorid {

// Derivative of uniformly sampled columns by central differences (x[k+1] - x[k-1]) / (2 dt),
// second-order one-sided differences at the two ends.
Eigen::MatrixXd CentralDifference(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt);

// Derivative by the fourth-order central stencil (x[k-2] - 8x[k-1] + 8x[k+1] - x[k+2]) / (12 dt) in
// the interior (CentralDifference's values for the two outermost samples at each end). The
// second-order stencil underestimates a sinusoid's derivative by (w dt)^2 / 6, which biases
// inertia identified from w' by that fraction; this one by (w dt)^4 / 30.
Eigen::MatrixXd FourthOrderCentralDifference(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt);

// Robust estimate of the standard deviation of white noise on a smooth, densely sampled signal,
// from the median absolute second difference: sigma = median|x[k-1] - 2x[k] + x[k+1]| / (0.6745 sqrt 6).
// The signal's own curvature must be small at the sample rate (true for IMU data at >= 100 Hz).
double WhiteNoiseStd(const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace rotorid

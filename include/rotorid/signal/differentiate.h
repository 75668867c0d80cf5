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

namespace internal {
// Row k of FourthOrderCentralDifference of the n-row series whose row j is row(j), with the same
// operations in the same order as the whole-series version (which requires n >= 3).
template <typename Row, typename RowOf>
Row FourthOrderCentralDifferenceRow(const RowOf& row, Eigen::Index n, Eigen::Index k, double dt) {
  if (n >= 5 && k >= 2 && k <= n - 3)
    return (row(k - 2) - 8.0 * row(k - 1) + 8.0 * row(k + 1) - row(k + 2)) / (12.0 * dt);
  const double inv_2dt = 0.5 / dt;
  if (k == 0) return (-3.0 * row(0) + 4.0 * row(1) - row(2)) * inv_2dt;
  if (k == n - 1) return (3.0 * row(n - 1) - 4.0 * row(n - 2) + row(n - 3)) * inv_2dt;
  return (row(k + 1) - row(k - 1)) * inv_2dt;
}
}  // namespace internal

// Row k of FourthOrderCentralDifference(x, dt), and row k of that applied twice, to the last bit,
// from the few rows of x around k (x has at least 3 rows): for derivatives needed at a few samples
// only (the IDIM's row samples), without a whole-flight series of each.
template <typename Derived>
Eigen::Matrix<double, 1, Derived::ColsAtCompileTime> FourthOrderCentralDifferenceAt(const Eigen::MatrixBase<Derived>& x,
                                                                                    Eigen::Index k, double dt) {
  using Row = Eigen::Matrix<double, 1, Derived::ColsAtCompileTime>;
  return internal::FourthOrderCentralDifferenceRow<Row>([&x](Eigen::Index j) -> Row { return x.row(j); }, x.rows(), k,
                                                        dt);
}
template <typename Derived>
Eigen::Matrix<double, 1, Derived::ColsAtCompileTime> SecondFourthOrderCentralDifferenceAt(
    const Eigen::MatrixBase<Derived>& x, Eigen::Index k, double dt) {
  using Row = Eigen::Matrix<double, 1, Derived::ColsAtCompileTime>;
  return internal::FourthOrderCentralDifferenceRow<Row>(
      [&x, dt](Eigen::Index j) { return FourthOrderCentralDifferenceAt(x, j, dt); }, x.rows(), k, dt);
}

// Robust estimate of the standard deviation of white noise on a smooth, densely sampled signal,
// from the median absolute second difference: sigma = median|x[k-1] - 2x[k] + x[k+1]| / (0.6745 sqrt 6).
// The signal's own curvature must be small at the sample rate (true for IMU data at >= 100 Hz).
double WhiteNoiseStd(const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace rotorid

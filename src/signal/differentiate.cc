#include "rotorid/signal/differentiate.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "rotorid/core/error.h"

namespace rotorid {

Eigen::MatrixXd CentralDifference(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt) {
  const Eigen::Index n = x.rows();
  if (n < 3) {
    throw Error("CentralDifference needs at least 3 samples (got " + std::to_string(n) + ")");
  }
  if (!(std::isfinite(dt) && dt > 0.0)) {
    std::ostringstream message;
    message << "CentralDifference needs a positive, finite time step (got dt = " << dt << " s)";
    throw Error(message.str());
  }
  const double inv_2dt = 0.5 / dt;
  Eigen::MatrixXd derivative(n, x.cols());
  derivative.middleRows(1, n - 2) = (x.bottomRows(n - 2) - x.topRows(n - 2)) * inv_2dt;
  // One-sided differences exact for quadratics, so the ends keep the O(dt^2) error of the interior.
  derivative.row(0) = (-3.0 * x.row(0) + 4.0 * x.row(1) - x.row(2)) * inv_2dt;
  derivative.row(n - 1) = (3.0 * x.row(n - 1) - 4.0 * x.row(n - 2) + x.row(n - 3)) * inv_2dt;
  return derivative;
}

Eigen::MatrixXd FourthOrderCentralDifference(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt) {
  Eigen::MatrixXd derivative = CentralDifference(x, dt);
  const Eigen::Index n = x.rows();
  if (n < 5) return derivative;
  // (x[k-2] - 8 x[k-1] + 8 x[k+1] - x[k+2]) / (12 dt): error (w dt)^4 / 30 instead of (w dt)^2 / 6,
  // i.e. 3e-7 instead of 1.5e-3 for a 3 Hz motion sampled at 200 Hz.
  derivative.middleRows(2, n - 4) = (x.topRows(n - 4) - 8.0 * x.middleRows(1, n - 4) + 8.0 * x.middleRows(3, n - 4) -
                                     x.bottomRows(n - 4)) /
                                    (12.0 * dt);
  return derivative;
}

double WhiteNoiseStd(const Eigen::Ref<const Eigen::VectorXd>& x) {
  const Eigen::Index n = x.size();
  if (n < 3) throw Error("WhiteNoiseStd needs at least 3 samples (got " + std::to_string(n) + ")");
  std::vector<double> curvature(static_cast<std::size_t>(n - 2));
  for (Eigen::Index k = 1; k + 1 < n; ++k) {
    const double second_difference = x[k - 1] - 2.0 * x[k] + x[k + 1];
    // A NaN would break the ordering that the median relies on.
    if (!std::isfinite(second_difference)) {
      throw Error("WhiteNoiseStd: non-finite value near sample " + std::to_string(k));
    }
    curvature[static_cast<std::size_t>(k - 1)] = std::abs(second_difference);
  }
  // For white noise of std sigma the second difference has std sqrt(6) sigma, and the median of
  // |N(0, s^2)| is 0.6745 s; the median ignores the few samples where the signal itself curves.
  const std::size_t half = curvature.size() / 2;
  std::nth_element(curvature.begin(), curvature.begin() + half, curvature.end());
  double median = curvature[half];
  if (curvature.size() % 2 == 0) {
    median = 0.5 * (median + *std::max_element(curvature.begin(), curvature.begin() + half));
  }
  return median / (0.6745 * std::sqrt(6.0));
}

}  // namespace rotorid

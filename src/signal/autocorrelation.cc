#include "rotorid/signal/autocorrelation.h"

#include <algorithm>

namespace rotorid {

namespace {

// Sum over the pieces of x[t] x[t + lag].
double PooledAutocovariance(const std::vector<Eigen::VectorXd>& series, Eigen::Index lag) {
  double sum = 0.0;
  for (const Eigen::VectorXd& s : series)
    if (s.size() > lag) sum += s.head(s.size() - lag).dot(s.tail(s.size() - lag));
  return sum;
}

}  // namespace

Eigen::Index FirstLagBelow(const std::vector<Eigen::VectorXd>& series, double threshold, Eigen::Index max_lag) {
  const double c0 = PooledAutocovariance(series, 0);
  if (!(c0 > 0.0)) return 1;
  Eigen::Index lag = 1;
  while (lag < max_lag && PooledAutocovariance(series, lag) / c0 >= threshold) ++lag;
  return lag;
}

double AutocorrelationFactor(const std::vector<Eigen::VectorXd>& series, Eigen::Index max_search_lag) {
  Eigen::Index total = 0, longest = 0;
  for (const Eigen::VectorXd& s : series) {
    total += s.size();
    longest = std::max(longest, s.size());
  }
  const double c0 = PooledAutocovariance(series, 0);
  if (total < 20 || !(c0 > 0.0)) return 1.0;
  const Eigen::Index max_lag = std::max<Eigen::Index>(1, std::min(total / 10, longest / 2));
  const Eigen::Index lag = std::min(2 * FirstLagBelow(series, 0.1, std::min(max_lag, max_search_lag)), max_lag);
  double factor = 1.0;
  for (Eigen::Index l = 1; l <= lag; ++l)
    factor +=
        2.0 * (1.0 - static_cast<double>(l) / static_cast<double>(lag + 1)) * PooledAutocovariance(series, l) / c0;
  return std::max(factor, 1.0);
}

Eigen::MatrixXd BartlettLongRunSum(const Eigen::MatrixXd& scores, Eigen::Index lag) {
  // The lagged terms are scores * V^T with V_t = sum_l (lag + 1 - l) s_{t+l} / (lag + 1): one
  // product instead of one per lag (those were most of a refinement's reselection passes). V is
  // built from the end by a sliding window: A_t = sum_l (lag + 1 - l) s_{t+l} and the window sum
  // B_t = sum_l s_{t+l} (l = 1..lag, zero past the last sample) give A_{t-1} = A_t + lag s_t - B_t.
  const Eigen::Index n = scores.rows(), samples = scores.cols();
  Eigen::MatrixXd weighted_ahead(n, samples);
  Eigen::VectorXd a = Eigen::VectorXd::Zero(n), b = Eigen::VectorXd::Zero(n);
  const double lag_d = static_cast<double>(lag);
  for (Eigen::Index t = samples - 1; t >= 0; --t) {
    weighted_ahead.col(t) = a / (lag_d + 1.0);
    a += lag_d * scores.col(t) - b;
    b += scores.col(t);
    if (t + lag < samples) b -= scores.col(t + lag);
  }
  const Eigen::MatrixXd lagged = scores * weighted_ahead.transpose();
  return scores * scores.transpose() + lagged + lagged.transpose();
}

}  // namespace rotorid

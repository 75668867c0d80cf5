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

}  // namespace rotorid

#include "rotorid/signal/autocorrelation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rotorid {
namespace {

// AR(1) noise x[i] = phi x[i-1] + e[i]: autocorrelation phi^l.
Eigen::VectorXd Ar1Noise(double phi, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x(n);
  double state = 0.0;
  for (int i = 0; i < n; ++i) x[i] = state = phi * state + normal(rng);
  return x;
}

TEST(AutocorrelationTest, FactorOfWhiteAndAr1Noise) {
  EXPECT_NEAR(AutocorrelationFactor({Ar1Noise(0.0, 200000, 7)}), 1.0, 0.05);
  // The variance of the mean of AR(1) is inflated by (1 + phi) / (1 - phi) = 9; the Bartlett window
  // truncated where the autocorrelation has decayed recovers most of it.
  const Eigen::VectorXd ar = Ar1Noise(0.8, 200000, 8);
  const double factor = AutocorrelationFactor({ar.head(100000), ar.tail(100000)});
  EXPECT_GT(factor, 7.0);
  EXPECT_LT(factor, 9.5);
}

TEST(AutocorrelationTest, FirstLagBelowIsWhereTheAutocorrelationDecays) {
  // phi^l < 0.1 first at l = ceil(log 0.1 / log phi): 11 for phi = 0.8, 22 for phi = 0.9.
  EXPECT_NEAR(FirstLagBelow({Ar1Noise(0.8, 400000, 9)}, 0.1, 1000), 11, 1);
  EXPECT_NEAR(FirstLagBelow({Ar1Noise(0.9, 400000, 10)}, 0.1, 1000), 22, 1);
  // The search stops at max_lag; white noise decorrelates at once; all-zero series give 1.
  EXPECT_EQ(FirstLagBelow({Ar1Noise(0.9, 400000, 10)}, 0.1, 5), 5);
  EXPECT_EQ(FirstLagBelow({Ar1Noise(0.0, 400000, 11)}, 0.1, 1000), 1);
  EXPECT_EQ(FirstLagBelow({Eigen::VectorXd::Zero(100)}, 0.1, 1000), 1);
}

TEST(AutocorrelationTest, SearchCapLimitsTheWindowOfSlowlyDecorrelatingSeries) {
  // phi = 0.995: the autocorrelation stays above 0.1 for about 460 lags (factor about 300 with the
  // window at twice that). Capping the search at 20 lags keeps the window at 40 lags:
  // 1 + 2 sum_{l<=40} (1 - l/41) 0.995^l = 38.
  const Eigen::VectorXd slow = Ar1Noise(0.995, 200000, 12);
  const double uncapped = AutocorrelationFactor({slow});
  const double capped = AutocorrelationFactor({slow}, 20);
  EXPECT_GT(uncapped, 100.0);
  EXPECT_NEAR(capped, 38.0, 5.0);
  // Fewer than 20 samples: no estimate, factor 1.
  EXPECT_EQ(AutocorrelationFactor({slow.head(19)}), 1.0);
}

// The sliding-window form equals the definition, one product per lag, to round-off: correlated
// scores (three AR(1) rows), lags from none to beyond the samples.
TEST(AutocorrelationTest, BartlettLongRunSumIsThePerLagSum) {
  const int samples = 300;
  Eigen::MatrixXd scores(3, samples);
  for (int k = 0; k < 3; ++k) scores.row(k) = Ar1Noise(0.3 * k, samples, 20 + k).transpose();
  scores.row(2) += 0.5 * scores.row(0);
  for (int lag : {0, 1, 7, 60, 299, 400}) {
    Eigen::MatrixXd expected = scores * scores.transpose();
    for (int l = 1; l <= lag && l < samples; ++l) {
      const Eigen::MatrixXd cross = scores.leftCols(samples - l) * scores.rightCols(samples - l).transpose();
      expected += (1.0 - static_cast<double>(l) / (lag + 1)) * (cross + cross.transpose());
    }
    const Eigen::MatrixXd sum = BartlettLongRunSum(scores, lag);
    EXPECT_LT((sum - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff()) << "lag " << lag;
  }
  // The lagged terms matter: with lag 60 the sum differs from the lag-0 one by a sizeable amount.
  EXPECT_GT((BartlettLongRunSum(scores, 60) - BartlettLongRunSum(scores, 0)).norm(),
            0.1 * BartlettLongRunSum(scores, 0).norm());
}

}  // namespace
}  // namespace rotorid

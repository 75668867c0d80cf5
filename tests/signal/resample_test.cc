#include "rotorid/signal/resample.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "rotorid/core/error.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Expects `call` to throw rotorid::Error whose message contains `expected`.
template <typename Call>
void ExpectErrorContaining(Call call, const std::string& expected) {
  try {
    call();
    ADD_FAILURE() << "no exception; expected: " << expected;
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
  }
}

TEST(UniformTimeBase, InclusiveEndAndExactSpacing) {
  const Eigen::VectorXd t = UniformTimeBase(2.0, 3.0, 250.0);
  ASSERT_EQ(t.size(), 251);
  EXPECT_EQ(t[0], 2.0);
  EXPECT_NEAR(t[250], 3.0, 1e-12);
  for (Eigen::Index k = 0; k < t.size(); ++k) EXPECT_NEAR(t[k], 2.0 + k * 0.004, 1e-12);
  // 0.1 s at 30 Hz is 3 intervals up to rounding: the end is kept.
  EXPECT_EQ(UniformTimeBase(0.0, 0.1, 30.0).size(), 4);
  // An end between grid points is not reached.
  EXPECT_EQ(UniformTimeBase(0.0, 1.0099, 100.0).size(), 101);
  EXPECT_EQ(UniformTimeBase(5.0, 5.0, 100.0).size(), 1);
  // One hour at 200 Hz: no drift at the end.
  const Eigen::VectorXd hour = UniformTimeBase(100.0, 3700.0, 200.0);
  ASSERT_EQ(hour.size(), 720001);
  EXPECT_NEAR(hour[720000], 3700.0, 1e-9);
}

TEST(UniformTimeBase, RejectsBadArguments) {
  ExpectErrorContaining([] { UniformTimeBase(0.0, 1.0, 0.0); }, "rate must be positive");
  ExpectErrorContaining([] { UniformTimeBase(0.0, 1.0, -5.0); }, "rate must be positive");
  ExpectErrorContaining([] { UniformTimeBase(2.0, 1.0, 100.0); }, "t_begin <= t_end");
  ExpectErrorContaining([] { UniformTimeBase(0.0, std::nan(""), 100.0); }, "t_begin <= t_end");
  ExpectErrorContaining([] { UniformTimeBase(0.0, 3600.0, 1e9); }, "would have");
}

TEST(InterpolateLinear, ReproducesALinearFunctionOnJitteredStamps) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> jitter(-0.3e-3, 0.3e-3);
  const Eigen::Index n = 2000;
  Eigen::VectorXd t(n);
  for (Eigen::Index k = 0; k < n; ++k) t[k] = 10.0 + k * 1e-3 + jitter(random);
  Eigen::MatrixXd x(n, 2);
  x.col(0) = 2.0 * t.array() + 1.0;
  x.col(1) = -3.0 * t.array() + 0.5;

  const Eigen::VectorXd query = UniformTimeBase(t[0], t[n - 1], 777.0);
  const Eigen::MatrixXd y = InterpolateLinear(t, x, query);
  ASSERT_EQ(y.rows(), query.size());
  ASSERT_EQ(y.cols(), 2);
  const Eigen::VectorXd expected0 = 2.0 * query.array() + 1.0;
  const Eigen::VectorXd expected1 = -3.0 * query.array() + 0.5;
  EXPECT_LT((y.col(0) - expected0).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((y.col(1) - expected1).cwiseAbs().maxCoeff(), 1e-12);

  // At the sample times the samples come back exactly.
  EXPECT_EQ(InterpolateLinear(t, x, t), x);

  // Unsorted queries give the same values as sorted ones.
  std::vector<Eigen::Index> order(static_cast<std::size_t>(query.size()));
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), random);
  Eigen::VectorXd shuffled(query.size());
  for (Eigen::Index i = 0; i < query.size(); ++i) shuffled[i] = query[order[static_cast<std::size_t>(i)]];
  const Eigen::MatrixXd y_shuffled = InterpolateLinear(t, x, shuffled);
  for (Eigen::Index i = 0; i < query.size(); ++i) {
    ASSERT_EQ(y_shuffled.row(i), y.row(order[static_cast<std::size_t>(i)])) << i;
  }
}

TEST(InterpolateLinear, MidpointsAndClampedEnds) {
  Eigen::VectorXd t(3);
  t << 0.0, 1.0, 3.0;
  Eigen::MatrixXd x(3, 1);
  x << 10.0, 20.0, 0.0;
  Eigen::VectorXd query(7);
  query << -5.0, 0.0, 0.25, 1.0, 2.0, 3.0, 1e9;
  Eigen::VectorXd expected(7);
  expected << 10.0, 10.0, 12.5, 20.0, 10.0, 0.0, 0.0;
  EXPECT_EQ(InterpolateLinear(t, x, query).col(0), expected);
  // A single sample is a constant.
  EXPECT_EQ(InterpolateLinear(t.head(1), x.topRows(1), query), Eigen::MatrixXd::Constant(7, 1, 10.0));
  EXPECT_EQ(InterpolateLinear(t, x, Eigen::VectorXd()).rows(), 0);
}

TEST(InterpolateHold, LastValueAtOrBefore) {
  Eigen::VectorXd t(3);
  t << 0.0, 1.0, 2.0;
  Eigen::MatrixXd x(3, 2);
  x << 10.0, -1.0, 20.0, -2.0, 30.0, -3.0;
  Eigen::VectorXd query(8);
  query << -1.0, 0.0, 0.5, 1.0, 1.999, 2.0, 5.0, 0.999;
  Eigen::MatrixXd expected(8, 2);
  // Before the first sample the first value is held.
  expected << 10, -1, 10, -1, 10, -1, 20, -2, 20, -2, 30, -3, 30, -3, 10, -1;
  EXPECT_EQ(InterpolateHold(t, x, query), expected);
}

TEST(Interpolate, ErrorsNameTheProblem) {
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(30, 0.0, 2.9);
  const Eigen::MatrixXd x = Eigen::MatrixXd::Zero(30, 2);
  const Eigen::VectorXd query = Eigen::VectorXd::LinSpaced(5, 0.0, 1.0);
  t[17] = t[16];
  ExpectErrorContaining([&] { InterpolateLinear(t, x, query); }, "time stamps not strictly increasing at sample 17");
  ExpectErrorContaining([&] { InterpolateHold(t, x, query); }, "time stamps not strictly increasing at sample 17");
  t[17] = t[16] - 0.5;
  ExpectErrorContaining([&] { InterpolateLinear(t, x, query); }, "not strictly increasing at sample 17");
  t[17] = std::nan("");
  ExpectErrorContaining([&] { InterpolateLinear(t, x, query); }, "sample 17 is not finite");
  t = Eigen::VectorXd::LinSpaced(30, 0.0, 2.9);
  ExpectErrorContaining([&] { InterpolateLinear(t, x.topRows(29), query); }, "30 time stamps but 29 rows");
  ExpectErrorContaining([&] { InterpolateHold(t.head(0), x.topRows(0), query); }, "at least one sample");
  Eigen::VectorXd bad_query = query;
  bad_query[3] = std::nan("");
  ExpectErrorContaining([&] { InterpolateLinear(t, x, bad_query); }, "query time 3 is NaN");
}

TEST(Decimate, EveryFactorRowFromTheOffset) {
  Eigen::MatrixXd x(10, 2);
  for (Eigen::Index k = 0; k < 10; ++k) x.row(k) << k, 100 + k;
  auto first_column = [](const Eigen::MatrixXd& m) {
    return std::vector<double>(m.col(0).data(), m.col(0).data() + m.rows());
  };
  EXPECT_EQ(first_column(Decimate(x, 3)), (std::vector<double>{0, 3, 6, 9}));
  EXPECT_EQ(first_column(Decimate(x, 3, 1)), (std::vector<double>{1, 4, 7}));
  EXPECT_EQ(first_column(Decimate(x, 3, 2)), (std::vector<double>{2, 5, 8}));
  EXPECT_EQ(first_column(Decimate(x, 4, 9)), (std::vector<double>{9}));
  EXPECT_EQ(Decimate(x, 4, 10).rows(), 0);
  EXPECT_EQ(Decimate(x, 1), x);
  EXPECT_EQ(Decimate(x, 3, 1).col(1), Eigen::Vector3d(101, 104, 107));
  // A block view with an outer stride.
  Eigen::MatrixXd big = Eigen::MatrixXd::Zero(20, 3);
  big.block(5, 1, 10, 2) = x;
  EXPECT_EQ(Decimate(big.block(5, 1, 10, 2), 3, 2), Decimate(x, 3, 2));
  ExpectErrorContaining([&] { Decimate(x, 0); }, "factor must be >= 1");
  ExpectErrorContaining([&] { Decimate(x, 2, -1); }, "offset must be >= 0");
}

TEST(UnwrapAngle, RampThatWrapsSeveralTimes) {
  for (double rate : {0.37, -0.51, 3.0}) {  // rad per sample; all below pi.
    const Eigen::Index n = 200;
    Eigen::VectorXd ramp(n), wrapped(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      ramp[k] = 0.2 + rate * k;
      wrapped[k] = std::atan2(std::sin(ramp[k]), std::cos(ramp[k]));  // In (-pi, pi].
    }
    ASSERT_GT(std::abs(ramp[n - 1] - ramp[0]), 10 * kPi) << "the ramp must wrap several times";
    const Eigen::VectorXd unwrapped = UnwrapAngle(wrapped);
    EXPECT_LT((unwrapped - ramp).cwiseAbs().maxCoeff(), 1e-9) << rate;
    EXPECT_LT((unwrapped.tail(n - 1) - unwrapped.head(n - 1)).cwiseAbs().maxCoeff(), kPi) << rate;
  }
  EXPECT_EQ(UnwrapAngle(Eigen::VectorXd()).size(), 0);
  // Values already continuous are left alone, even far from (-pi, pi].
  Eigen::VectorXd smooth(4);
  smooth << 100.0, 101.0, 103.5, 100.5;
  EXPECT_EQ(UnwrapAngle(smooth), smooth);
  // numpy.unwrap's convention at exactly pi: a jump of +pi stays, so does -pi.
  Eigen::VectorXd half_turns(3);
  half_turns << 0.0, kPi, 0.0;
  EXPECT_EQ(UnwrapAngle(half_turns), half_turns);
}

}  // namespace
}  // namespace rotorid

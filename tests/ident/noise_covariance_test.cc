#include <gtest/gtest.h>

#include <random>

#include "rotorid/ident/observation.h"
#include "rotorid/model/rigid_body.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

using Rows = Eigen::Matrix<double, 6, kNumIdimColumns>;

Rows RowsAt(const Eigen::Matrix<double, 9, 1>& x, const Eigen::VectorXd& omega, const Vehicle& vehicle) {
  return IdimRows<double>(Eigen::Vector3d(x.segment<3>(0)), Eigen::Vector3d(x.segment<3>(3)),
                          Eigen::Vector3d(x.segment<3>(6)), omega, vehicle);
}

// Central difference of IdimRows by signal k of x = [w; w'; s].
Rows NumericDerivative(const Eigen::Matrix<double, 9, 1>& x, const Eigen::VectorXd& omega, const Vehicle& vehicle,
                       int k, double h) {
  Eigen::Matrix<double, 9, 1> plus = x, minus = x;
  plus[k] += h;
  minus[k] -= h;
  return (RowsAt(plus, omega, vehicle) - RowsAt(minus, omega, vehicle)) / (2.0 * h);
}

TEST(NoiseCovarianceTest, SignalDerivativeMatchesNumericDifferences) {
  const Vehicle vehicle = testing::SimulatePreset("B", 1.0, 1).vehicle;
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Matrix<double, 9, 1> x;
    for (int k = 0; k < 9; ++k) x[k] = (k < 3 ? 3.0 : k < 6 ? 30.0 : 10.0) * n(rng);
    Eigen::VectorXd omega(vehicle.num_rotors());
    for (int r = 0; r < omega.size(); ++r) omega[r] = 800.0 + 100.0 * n(rng);
    for (int k = 0; k < 9; ++k) {
      const Rows analytic = IdimRowsSignalDerivative(Eigen::Vector3d(x.segment<3>(0)), vehicle.mass_kg, k);
      const Rows numeric = NumericDerivative(x, omega, vehicle, k, 1e-4);
      ASSERT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-8 * (1.0 + numeric.cwiseAbs().maxCoeff()))
          << "signal " << k << ", trial " << trial << "\nanalytic\n"
          << analytic << "\nnumeric\n"
          << numeric;
    }
  }
}

// The covariance from the moments of w equals the sum over the rows of each row's Jacobian outer
// products (the definition), on a simulated flight.
TEST(NoiseCovarianceTest, EqualsTheSumOverRowsOfNumericJacobians) {
  const SimulationResult sim = testing::SimulatePreset("B", 8.0, 3);
  const ProcessedFlight flight = ProcessFlight(sim.log, sim.vehicle, 1.0, ObservationOptions{});
  Eigen::Matrix<double, 9, 1> sigma;
  sigma << flight.noise.angular_velocity, flight.noise.angular_acceleration, flight.noise.specific_force;
  ASSERT_GT(sigma.minCoeff(), 0.0);
  std::vector<Eigen::MatrixXd> expected(kNumWrenchComponents, Eigen::MatrixXd::Zero(kNumIdimColumns, kNumIdimColumns));
  for (int i : flight.row_samples) {
    Eigen::Matrix<double, 9, 1> x;
    x << flight.angular_velocity.row(i).transpose(), flight.angular_acceleration.row(i).transpose(),
        flight.specific_force.row(i).transpose();
    const Eigen::VectorXd omega = flight.rotor.row(i).transpose();
    for (int k = 0; k < 9; ++k) {
      const Rows jac = NumericDerivative(x, omega, flight.vehicle, k, 1.0);  // exact: at most quadratic
      for (int c = 0; c < kNumWrenchComponents; ++c)
        expected[c] += sigma[k] * sigma[k] * jac.row(c).transpose() * jac.row(c);
    }
  }
  const std::vector<Eigen::MatrixXd> cov = IdimNoiseCovariance(flight);
  ASSERT_EQ(cov.size(), expected.size());
  for (int c = 0; c < kNumWrenchComponents; ++c) {
    const double scale = expected[c].cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    EXPECT_LT((cov[c] - expected[c]).cwiseAbs().maxCoeff(), 1e-12 * scale) << kWrenchComponentNames[c] << "\n"
                                                                           << cov[c] << "\n\n"
                                                                           << expected[c];
  }
}

}  // namespace
}  // namespace rotorid

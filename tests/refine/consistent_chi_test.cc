#include "refine/consistent_chi.h"

#include <gtest/gtest.h>

#include <cmath>

#include "rotorid/model/physical_consistency.h"

namespace rotorid {
namespace {

// kt, kd, then one body (ms_x ms_y ms_z I_xx I_yy I_zz I_xy I_xz I_yz) with kd and the products of
// inertia held at 0 (discarded), in scaled units.
struct Fixture {
  std::vector<int> fixed = {1, 8, 9, 10};
  Eigen::VectorXd scale =
      (Eigen::VectorXd(11) << 1e-6, 1e-8, 1e-3, 1e-3, 1e-3, 0.01, 0.01, 0.02, 1e-4, 1e-4, 1e-4).finished();
  Eigen::VectorXd chi =
      (Eigen::VectorXd(11) << 5.1e-6, 0.0, 2e-3, -1e-3, -6e-3, 0.015, 0.016, 0.029, 0, 0, 0).finished();

  internal::ConsistentChiManifold Manifold() const {
    std::array<bool, kNumBodyParameters> held{};
    held[6] = held[7] = held[8] = true;
    internal::ChartedBody body{"A", ConsistentBodyChart(1.285, held, chi.segment<9>(2)), {2, 3, 4, 5, 6, 7, 8, 9, 10}};
    return internal::ConsistentChiManifold(11, fixed, {body}, scale);
  }
  Eigen::VectorXd X() const { return chi.cwiseQuotient(scale); }
};

Eigen::Matrix<double, kNumBodyParameters, 1> BodyOf(const Eigen::VectorXd& x, const Eigen::VectorXd& scale) {
  return x.segment<9>(2).cwiseProduct(scale.segment<9>(2));
}

// Every step lands on a body with the held parameters at 0, and Minus undoes Plus.
TEST(ConsistentChiManifoldTest, PlusStaysOnBodiesAndMinusUndoesIt) {
  const Fixture f;
  const internal::ConsistentChiManifold manifold = f.Manifold();
  ASSERT_EQ(manifold.AmbientSize(), 11);
  ASSERT_EQ(manifold.TangentSize(), 7);  // kt, then d1 d2 d3 t1 t2 t3
  const Eigen::VectorXd x = f.X();
  Eigen::VectorXd zero = Eigen::VectorXd::Zero(7), same(11);
  ASSERT_TRUE(manifold.Plus(x.data(), zero.data(), same.data()));
  EXPECT_LT((same - x).cwiseAbs().maxCoeff(), 1e-12);
  // A large step: the roll extent shrinks 20-fold and the centre of mass drops by 60 mm, which no
  // Euclidean step could take without leaving the bodies.
  Eigen::VectorXd delta(7);
  delta << 0.3, -3.0, 0.5, 0.2, 0.001, -0.002, -0.06;
  Eigen::VectorXd moved(11), back(7);
  ASSERT_TRUE(manifold.Plus(x.data(), delta.data(), moved.data()));
  EXPECT_TRUE(CheckPhysicalConsistency(1.285, BodyParameters::FromVector(BodyOf(moved, f.scale))).consistent);
  for (int k : f.fixed) EXPECT_EQ(moved[k], 0.0) << k;
  ASSERT_TRUE(manifold.Minus(moved.data(), x.data(), back.data()));
  EXPECT_LT((back - delta).cwiseAbs().maxCoeff(), 1e-9) << back.transpose();
}

// PlusJacobian against central differences of Plus at delta = 0; MinusJacobian is its left inverse.
TEST(ConsistentChiManifoldTest, JacobiansMatchCentralDifferences) {
  const Fixture f;
  const internal::ConsistentChiManifold manifold = f.Manifold();
  const Eigen::VectorXd x = f.X();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> plus_jacobian(11, 7), minus_jacobian(7, 11);
  ASSERT_TRUE(manifold.PlusJacobian(x.data(), plus_jacobian.data()));
  ASSERT_TRUE(manifold.MinusJacobian(x.data(), minus_jacobian.data()));
  const double h = 1e-6;
  for (int j = 0; j < 7; ++j) {
    Eigen::VectorXd plus = Eigen::VectorXd::Zero(7), minus = Eigen::VectorXd::Zero(7), at_plus(11), at_minus(11);
    plus[j] = h;
    minus[j] = -h;
    ASSERT_TRUE(manifold.Plus(x.data(), plus.data(), at_plus.data()));
    ASSERT_TRUE(manifold.Plus(x.data(), minus.data(), at_minus.data()));
    const Eigen::VectorXd numeric = (at_plus - at_minus) / (2.0 * h);
    for (int i = 0; i < 11; ++i)
      EXPECT_NEAR(plus_jacobian(i, j), numeric[i], 1e-6 * std::max(1.0, std::abs(numeric[i]))) << i << ", " << j;
  }
  EXPECT_LT(((minus_jacobian * plus_jacobian) - Eigen::MatrixXd::Identity(7, 7)).cwiseAbs().maxCoeff(), 1e-9);
}

}  // namespace
}  // namespace rotorid

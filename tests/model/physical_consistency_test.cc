#include "rotorid/model/physical_consistency.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "rotorid/core/error.h"

namespace rotorid {
namespace {

// A box of mass m and sides a x b x c centred at p: its first moment and inertia at O_d.
BodyParameters Box(double m, const Eigen::Vector3d& sides, const Eigen::Vector3d& p) {
  const Eigen::Vector3d sq = sides.cwiseAbs2();
  BodyParameters centred;
  centred.inertia = (m / 12.0 * Eigen::Vector3d(sq.y() + sq.z(), sq.x() + sq.z(), sq.x() + sq.y())).asDiagonal();
  return AddPointMass(centred, m, p);
}

TEST(PhysicalConsistencyTest, PseudoInertiaOfAPointMassIsRankOne) {
  const Eigen::Vector3d p(0.1, -0.2, 0.05);
  const Eigen::Matrix4d j = PseudoInertia(0.5, AddPointMass(BodyParameters{}, 0.5, p));
  Eigen::Vector4d p1;
  p1 << p, 1.0;
  EXPECT_LT((j - 0.5 * p1 * p1.transpose()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(PhysicalConsistencyTest, ABoxOffTheOriginIsConsistentAndItsExtentsAreRecovered) {
  const Eigen::Vector3d sides(0.3, 0.2, 0.06), p(0.01, -0.02, -0.03);
  const PhysicalConsistency result = CheckPhysicalConsistency(1.2, Box(1.2, sides, p));
  EXPECT_TRUE(result.consistent) << result.problem;
  EXPECT_TRUE(result.problem.empty());
  EXPECT_LT((result.centre_of_mass_m - p).norm(), 1e-12);
  // A uniform box's RMS extent along a side of length a is a / sqrt(12).
  EXPECT_NEAR(result.rms_extent_m[0], 0.06 / std::sqrt(12.0), 1e-12);
  EXPECT_NEAR(result.rms_extent_m[2], 0.3 / std::sqrt(12.0), 1e-12);
  // The smallest pseudo-inertia eigenvalue is positive exactly when the check passes.
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(PseudoInertia(1.2, Box(1.2, sides, p))).eigenvalues()[0],
            0.0);
}

// NanoBench's identification (issue 37): a centre of mass 23 mm below the rotor plane with a small
// roll inertia at O_d leaves a negative inertia about the centre of mass, though I at O_d is
// positive definite and meets the triangle inequalities.
TEST(PhysicalConsistencyTest, ACentreOfMassFarBelowWithASmallRollInertiaIsFlagged) {
  BodyParameters body;
  body.first_moment = Eigen::Vector3d(0.0, 0.0, -9.5e-4);
  body.inertia = Eigen::Vector3d(3.4e-6, 2.6e-5, 2.9e-5).asDiagonal();
  const Eigen::Matrix3d i = body.inertia;
  ASSERT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(i).eigenvalues()[0], 0.0);
  ASSERT_LE(i(2, 2), i(0, 0) + i(1, 1));
  const PhysicalConsistency result = CheckPhysicalConsistency(0.04085, body);
  EXPECT_FALSE(result.consistent);
  EXPECT_LT(result.principal_moments_at_com[0], 0.0);
  EXPECT_LT(result.rms_extent_m[0], 0.0);
  EXPECT_NE(result.problem.find("mm along"), std::string::npos) << result.problem;
  EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(PseudoInertia(0.04085, body)).eigenvalues()[0], 0.0);
}

// The bundled flight A's identification (issue 37): I_zz far below truth gives I_yy > I_xx + I_zz.
TEST(PhysicalConsistencyTest, ATriangleInequalityViolatedIsFlagged) {
  BodyParameters body;
  body.inertia = Eigen::Vector3d(0.015, 0.015, 1.9e-4).asDiagonal();
  body.inertia(1, 1) = 0.0152 + 1.9e-4;
  EXPECT_FALSE(CheckPhysicalConsistency(1.285, body).consistent);
  body.inertia(2, 2) = 0.029;
  EXPECT_TRUE(CheckPhysicalConsistency(1.285, body).consistent);
}

TEST(PhysicalConsistencyTest, NonPositiveMassOrNonFiniteValuesAreNotABody) {
  const BodyParameters box = Box(1.0, Eigen::Vector3d(0.2, 0.2, 0.05), Eigen::Vector3d::Zero());
  EXPECT_FALSE(CheckPhysicalConsistency(0.0, box).consistent);
  EXPECT_FALSE(CheckPhysicalConsistency(-1.0, box).consistent);
  BodyParameters nan = box;
  nan.inertia(0, 0) = std::nan("");
  EXPECT_FALSE(CheckPhysicalConsistency(1.0, nan).consistent);
}

Eigen::Matrix<double, kNumBodyParameters, 1> ChiOf(const Eigen::Matrix<double, kNumLogCholesky, 1>& theta,
                                                   double* mass) {
  Eigen::Matrix<double, kNumBodyParameters, 1> chi;
  BodyFromLogCholesky(theta.data(), chi.data(), mass);
  return chi;
}

// A tilted box with products of inertia, off the origin.
BodyParameters TiltedBox() {
  BodyParameters box = Box(0.7, Eigen::Vector3d(0.25, 0.18, 0.05), Eigen::Vector3d(0.012, -0.008, -0.02));
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d c = box.first_moment / 0.7;
  BodyParameters at_com;
  at_com.inertia = box.inertia - 0.7 * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  at_com.inertia = r * at_com.inertia * r.transpose();
  return AddPointMass(at_com, 0.7, c);
}

TEST(LogCholeskyTest, RoundTripsAConsistentBody) {
  const BodyParameters body = TiltedBox();
  const Eigen::Matrix<double, kNumLogCholesky, 1> theta = LogCholeskyOf(0.7, body);
  double mass = 0.0;
  const Eigen::Matrix<double, kNumBodyParameters, 1> chi = ChiOf(theta, &mass);
  EXPECT_NEAR(mass, 0.7, 1e-14);
  EXPECT_LT((chi - body.ToVector()).cwiseAbs().maxCoeff(), 1e-14) << chi.transpose();
  // And the other way: any theta is a consistent body, whose theta is the one it came from.
  Eigen::Matrix<double, kNumLogCholesky, 1> any;
  any << -0.3, 0.5, -1.2, -2.0, 0.1, -0.2, 0.05, 0.02, -0.01, -0.03;
  const Eigen::Matrix<double, kNumBodyParameters, 1> other = ChiOf(any, &mass);
  EXPECT_TRUE(CheckPhysicalConsistency(mass, BodyParameters::FromVector(other)).consistent);
  EXPECT_LT((LogCholeskyOf(mass, BodyParameters::FromVector(other)) - any).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(LogCholeskyTest, RejectsAnImpossibleBody) {
  BodyParameters body;
  body.inertia = Eigen::Vector3d(0.015, 0.0152 + 2e-3, 1.9e-4).asDiagonal();
  EXPECT_THROW(LogCholeskyOf(1.285, body), Error);
}

TEST(LogCholeskyTest, JacobianMatchesCentralDifferences) {
  using Jet = ceres::Jet<double, kNumLogCholesky>;
  const Eigen::Matrix<double, kNumLogCholesky, 1> theta = LogCholeskyOf(0.7, TiltedBox());
  Jet theta_jet[kNumLogCholesky], chi_jet[kNumBodyParameters], mass_jet;
  for (int k = 0; k < kNumLogCholesky; ++k) theta_jet[k] = Jet(theta[k], k);
  BodyFromLogCholesky(theta_jet, chi_jet, &mass_jet);
  const double h = 1e-6;
  for (int k = 0; k < kNumLogCholesky; ++k) {
    Eigen::Matrix<double, kNumLogCholesky, 1> plus = theta, minus = theta;
    plus[k] += h;
    minus[k] -= h;
    double mass_plus = 0.0, mass_minus = 0.0;
    const Eigen::Matrix<double, kNumBodyParameters, 1> numeric =
        (ChiOf(plus, &mass_plus) - ChiOf(minus, &mass_minus)) / (2.0 * h);
    EXPECT_NEAR(mass_jet.v[k], (mass_plus - mass_minus) / (2.0 * h), 1e-8);
    for (int i = 0; i < kNumBodyParameters; ++i)
      EXPECT_NEAR(chi_jet[i].v[k], numeric[i], 1e-8 * std::max(1.0, std::abs(numeric[i])))
          << "d chi_" << i << " / d theta_" << k;
  }
}

// NanoBench's impossible body, with stds of its order: the projection is a consistent body no farther
// than any other consistent body (here the same airframe with its centre of mass 8 mm below O_d).
TEST(ConsistentProjectionTest, FindsTheNearestConsistentBodyInTheEstimatesMetric) {
  BodyParameters estimate;
  estimate.first_moment = Eigen::Vector3d(1e-5, -2e-5, -9.5e-4);
  estimate.inertia = Eigen::Vector3d(3.4e-6, 2.6e-5, 2.9e-5).asDiagonal();
  Eigen::Matrix<double, kNumBodyParameters, 1> std_dev;
  std_dev << 2e-5, 2e-5, 3e-4, 2e-6, 2e-6, 3e-6, 5e-7, 5e-7, 5e-7;
  const Eigen::MatrixXd sqrt_information = std_dev.cwiseInverse().asDiagonal();
  const double mass = 0.04085;
  ASSERT_FALSE(CheckPhysicalConsistency(mass, estimate).consistent);
  const ConsistentProjection projection = ProjectOntoConsistentBodies(mass, estimate, sqrt_information, std_dev);
  EXPECT_TRUE(projection.converged);
  EXPECT_TRUE(CheckPhysicalConsistency(mass, projection.body).consistent);
  EXPECT_GT(projection.distance_std, 0.5);
  BodyParameters other = estimate;
  other.first_moment.z() = -mass * 0.008;
  other.inertia(0, 0) = 1.6e-5;
  ASSERT_TRUE(CheckPhysicalConsistency(mass, other).consistent);
  const double other_distance = (sqrt_information * (other.ToVector() - estimate.ToVector())).norm();
  EXPECT_LT(projection.distance_std, other_distance);
  // The consistent body nearest to the estimate moves the least known of ms_z and I_xx most.
  EXPECT_TRUE(projection.largest_move_parameter == 2 || projection.largest_move_parameter == 3)
      << projection.largest_move_parameter;
}

TEST(ConsistentProjectionTest, AConsistentEstimateIsItsOwnProjection) {
  const BodyParameters box = TiltedBox();
  const Eigen::Matrix<double, kNumBodyParameters, 1> std_dev =
      Eigen::Matrix<double, kNumBodyParameters, 1>::Constant(1e-4);
  const ConsistentProjection projection =
      ProjectOntoConsistentBodies(0.7, box, std_dev.cwiseInverse().asDiagonal(), std_dev);
  EXPECT_EQ(projection.distance_std, 0.0);
  EXPECT_EQ((projection.body.ToVector() - box.ToVector()).norm(), 0.0);
}

// Centred at O_d, the triangle inequality is the whole range: |I_xx - I_yy| <= I_zz <= I_xx + I_yy.
// Off the origin it narrows by the centre of mass's offsets.
TEST(AllowedDiagonalInertiaTest, IsTheTriangleInequalityForACentredBody) {
  BodyParameters body;
  body.inertia = Eigen::Vector3d(0.018, 0.019, 0.0).asDiagonal();
  const InertiaRange range = AllowedDiagonalInertia(1.285, body, 2);
  EXPECT_NEAR(range.low, 0.001, 1e-12);
  EXPECT_NEAR(range.high, 0.037, 1e-12);
  // A centre of mass 10 mm below O_d moves I_xx and I_yy at O_d up by m c_z^2 but not I_zz.
  const double shift = 1.285 * 0.01 * 0.01;
  BodyParameters below;
  below.first_moment = Eigen::Vector3d(0.0, 0.0, -1.285 * 0.01);
  below.inertia = Eigen::Vector3d(0.018 + shift, 0.019 + shift, 0.0).asDiagonal();
  const InertiaRange offset = AllowedDiagonalInertia(1.285, below, 2);
  EXPECT_NEAR(offset.low, 0.001, 1e-12);
  EXPECT_NEAR(offset.high, 0.037, 1e-12);
  // A roll inertia smaller than m c_z^2 leaves no value of I_zz that makes a body.
  below.inertia(0, 0) = 0.5 * shift;
  EXPECT_TRUE(AllowedDiagonalInertia(1.285, below, 2).empty());
}

// The refinement's chart: with ms_x, ms_y and I_xy held (at 0 and at a given product), every coordinate
// vector is a body with those values, and a body with them round-trips.
TEST(ConsistentBodyChartTest, HoldsItsParametersAndRoundTrips) {
  std::array<bool, kNumBodyParameters> held{};
  held[0] = held[1] = held[6] = true;
  ConsistentBodyChart::Vector9 value = ConsistentBodyChart::Vector9::Zero();
  value[6] = -2e-4;
  const ConsistentBodyChart chart(0.7, held, value);
  ASSERT_EQ(chart.dimension(), 6);
  const double coordinates[6] = {-1.5, -1.7, -3.0, 0.03, -0.02, 0.011};
  ConsistentBodyChart::Vector9 chi;
  chart.Body(coordinates, chi.data());
  EXPECT_EQ(chi[0], 0.0);
  EXPECT_EQ(chi[1], 0.0);
  EXPECT_EQ(chi[6], -2e-4);
  EXPECT_TRUE(CheckPhysicalConsistency(0.7, BodyParameters::FromVector(chi)).consistent);
  Eigen::VectorXd back;
  ASSERT_TRUE(chart.Coordinates(chi, &back));
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(back[k], coordinates[k], 1e-12) << k;
  // The Jacobian of the held solve (s12 from I_xy) against central differences.
  using Jet = ceres::Jet<double, 6>;
  Jet point[6], chi_jet[kNumBodyParameters];
  for (int k = 0; k < 6; ++k) point[k] = Jet(coordinates[k], k);
  chart.Body(point, chi_jet);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    double plus[6], minus[6];
    std::copy(coordinates, coordinates + 6, plus);
    std::copy(coordinates, coordinates + 6, minus);
    plus[k] += h;
    minus[k] -= h;
    ConsistentBodyChart::Vector9 chi_plus, chi_minus;
    chart.Body(plus, chi_plus.data());
    chart.Body(minus, chi_minus.data());
    for (int i = 0; i < kNumBodyParameters; ++i)
      EXPECT_NEAR(chi_jet[i].v[k], (chi_plus[i] - chi_minus[i]) / (2.0 * h), 1e-9) << i << " " << k;
  }
  // No chart holds a diagonal inertia; an impossible body has no coordinates.
  std::array<bool, kNumBodyParameters> diagonal{};
  diagonal[5] = true;
  EXPECT_THROW(ConsistentBodyChart(0.7, diagonal, value), Error);
  BodyParameters impossible;
  impossible.inertia = Eigen::Vector3d(0.015, 0.0172, 1.9e-4).asDiagonal();
  EXPECT_FALSE(chart.Coordinates(impossible.ToVector(), &back));
}

// The projection holding parameters (a refinement's start) keeps them and is a body.
TEST(ConsistentProjectionTest, KeepsTheHeldParameters) {
  BodyParameters estimate;
  estimate.first_moment = Eigen::Vector3d(0.0, 0.0, -9.5e-4);
  estimate.inertia = Eigen::Vector3d(3.4e-6, 4.0e-6, 2.9e-5).asDiagonal();
  Eigen::Matrix<double, kNumBodyParameters, 1> std_dev;
  std_dev << 0.0, 0.0, 4e-5, 7e-7, 6e-7, 3e-6, 0.0, 0.0, 0.0;
  Eigen::MatrixXd sqrt_information = Eigen::MatrixXd::Zero(kNumBodyParameters, kNumBodyParameters);
  for (int k = 0; k < kNumBodyParameters; ++k)
    if (std_dev[k] > 0.0) sqrt_information(k, k) = 1.0 / std_dev[k];
  std::array<bool, kNumBodyParameters> held{};
  held[0] = held[1] = held[6] = held[7] = held[8] = true;
  const ConsistentProjection projection =
      ProjectOntoConsistentBodies(0.04085, estimate, sqrt_information, std_dev, nullptr, held);
  const Eigen::Matrix<double, kNumBodyParameters, 1> chi = projection.body.ToVector();
  for (int k : {0, 1, 6, 7, 8}) EXPECT_EQ(chi[k], 0.0) << k;
  Eigen::VectorXd coordinates;
  EXPECT_TRUE(ConsistentBodyChart(0.04085, held, chi).Coordinates(chi, &coordinates)) << chi.transpose();
  EXPECT_GT(projection.distance_std, 3.0);
}

}  // namespace
}  // namespace rotorid

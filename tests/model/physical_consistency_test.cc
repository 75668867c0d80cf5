#include "rotorid/model/physical_consistency.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

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
  body.inertia = Eigen::Vector3d(3.4e-6, 1.7e-5, 1.9e-5).asDiagonal();
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

}  // namespace
}  // namespace rotorid

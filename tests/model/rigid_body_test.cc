#include "rotorid/model/rigid_body.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rotorid/model/rotation.h"

namespace rotorid {
namespace {

Vehicle PlusQuad() {
  Vehicle v{"P", 1.285, {}, {}};
  const double d = 0.225;
  v.rotors = {{{0, -d, 0}, 1}, {{0, d, 0}, 1}, {{d, 0, 0}, -1}, {{-d, 0, 0}, -1}};
  return v;
}

Vehicle XQuad() {
  Vehicle v{"X", 0.8, {}, {}};
  const double a = 0.16;
  v.rotors = {{{a, -a, 0.01}, 1}, {{-a, -a, 0.01}, -1}, {{-a, a, 0.01}, 1}, {{a, a, 0.01}, -1}};
  return v;
}

Vehicle Hexa() {
  Vehicle v{"H", 2.1, {}, {}};
  for (int i = 0; i < 6; ++i) {
    const double angle = M_PI / 6 + i * M_PI / 3;
    v.rotors.push_back({{0.3 * std::cos(angle), 0.3 * std::sin(angle), -0.02}, i % 2 == 0 ? 1 : -1});
  }
  return v;
}

// MODEL.md's written-out D, typed in independently of BodyRegressor.
Eigen::Matrix<double, 6, 9> WrittenOutRegressor(const Eigen::Vector3d& w, const Eigen::Vector3d& wd,
                                                const Eigen::Vector3d& s) {
  const double wx = w.x(), wy = w.y(), wz = w.z(), ax = wd.x(), ay = wd.y(), az = wd.z();
  Eigen::Matrix<double, 6, 9> d = Eigen::Matrix<double, 6, 9>::Zero();
  d.block<3, 3>(0, 0) << -wy * wy - wz * wz, wx * wy - az, wx * wz + ay,  //
      wx * wy + az, -wx * wx - wz * wz, wy * wz - ax,                     //
      wx * wz - ay, wy * wz + ax, -wx * wx - wy * wy;
  d.block<3, 3>(3, 0) << 0, s.z(), -s.y(), -s.z(), 0, s.x(), s.y(), -s.x(), 0;
  d.block<3, 6>(3, 3) << ax, -wy * wz, wy * wz, ay - wx * wz, az + wx * wy, wy * wy - wz * wz,  //
      wx * wz, ay, -wx * wz, ax + wy * wz, wz * wz - wx * wx, az - wx * wy,                     //
      -wx * wy, wx * wy, az, wx * wx - wy * wy, ax - wy * wz, ay + wx * wz;
  return d;
}

class RegressorTest : public ::testing::TestWithParam<Vehicle> {};

// m D_m + D chi - D_k chi_k equals the Newton-Euler wrench minus the rotor wrench on random states.
TEST_P(RegressorTest, MatchesNewtonEulerOnRandomStates) {
  const Vehicle vehicle = GetParam();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d w(3 * u(rng), 3 * u(rng), 3 * u(rng)), wd(20 * u(rng), 20 * u(rng), 20 * u(rng)),
        s(3 * u(rng), 3 * u(rng), 9.8 + 3 * u(rng));
    Eigen::VectorXd omega(vehicle.num_rotors());
    for (int i = 0; i < omega.size(); ++i) omega[i] = 900 + 200 * u(rng);
    BodyParameters body;
    body.first_moment = Eigen::Vector3d(0.01 * u(rng), 0.01 * u(rng), 0.02 * u(rng));
    Eigen::Matrix3d a = Eigen::Matrix3d::Random() * 0.05;
    body.inertia = a * a.transpose() + 0.01 * Eigen::Matrix3d::Identity();
    const double kt = 3.6e-6 * (1 + 0.1 * u(rng)), kd = 5.1e-8 * (1 + 0.1 * u(rng));
    Eigen::Matrix<double, kNumIdimColumns, 1> chi_t;
    chi_t << kt, kd, body.ToVector(), 1.0;

    const Wrench<double> lhs = IdimRows<double>(w, wd, s, omega, vehicle) * chi_t;
    const Wrench<double> rigid = RigidBodyWrench<double>(w, wd, s, vehicle.mass_kg, body.first_moment, body.inertia);
    const Wrench<double> rotor = RotorWrench<double>(omega, kt, kd, vehicle);
    const double scale = rotor.norm();
    EXPECT_LT((lhs - (rigid - rotor)).norm(), 1e-12 * scale) << "trial " << trial;
    EXPECT_LT((BodyRegressor<double>(w, wd, s) - WrittenOutRegressor(w, wd, s)).norm(), 1e-12);
  }
}

// The rotor wrench from the regressor equals the sum of the per-rotor forces and torques.
TEST_P(RegressorTest, RotorWrenchIsSumOfRotorForces) {
  const Vehicle vehicle = GetParam();
  Eigen::VectorXd omega = Eigen::VectorXd::LinSpaced(vehicle.num_rotors(), 800, 1100);
  const double kt = 3.6e-6, kd = 5.1e-8;
  Wrench<double> expected = Wrench<double>::Zero();
  for (int i = 0; i < vehicle.num_rotors(); ++i) {
    const Eigen::Vector3d force(0, 0, kt * omega[i] * omega[i]);
    expected.head<3>() += force;
    expected.tail<3>() += vehicle.rotors[i].position_m.cross(force);
    expected[5] += -vehicle.rotors[i].spin * kd * omega[i] * omega[i];
  }
  EXPECT_LT((RotorWrench<double>(omega, kt, kd, vehicle) - expected).norm(), 1e-12 * expected.norm());
}

// Forward dynamics inverts the Newton-Euler wrench.
TEST_P(RegressorTest, ForwardDynamicsInvertsWrench) {
  const Vehicle vehicle = GetParam();
  BodyParameters body;
  body.first_moment << 0.04, -0.02, -0.01;
  body.inertia << 0.024, 0.0002, 0.0019, 0.0002, 0.036, -0.0007, 0.0019, -0.0007, 0.054;
  const Eigen::Vector3d w(0.3, -1.2, 0.7);
  Wrench<double> wrench;
  wrench << 0.1, -0.2, 14.0, 0.3, -0.1, 0.05;
  Eigen::Vector3d s, wd;
  ForwardDynamics<double>(w, wrench, vehicle.mass_kg, body.first_moment, body.inertia, &s, &wd);
  const Wrench<double> back = RigidBodyWrench<double>(w, wd, s, vehicle.mass_kg, body.first_moment, body.inertia);
  EXPECT_LT((back - wrench).norm(), 1e-12 * wrench.norm());
}

INSTANTIATE_TEST_SUITE_P(Layouts, RegressorTest, ::testing::Values(PlusQuad(), XQuad(), Hexa()),
                         [](const auto& test_info) { return test_info.param.name; });

TEST(RotationTest, BryantRateMatrixMatchesNumericDerivative) {
  const Eigen::Vector3d eta(0.3, -0.2, 1.1), eta_dot(0.5, -0.7, 0.9);
  const double h = 1e-6;
  const Eigen::Matrix3d r0 = BryantToRotation(eta - h * eta_dot), r1 = BryantToRotation(eta + h * eta_dot);
  const Eigen::Matrix3d r_dot = (r1 - r0) / (2 * h);
  const Eigen::Matrix3d w_skew = BryantToRotation(eta).transpose() * r_dot;  // [w x] in the body frame
  const Eigen::Vector3d w(w_skew(2, 1), w_skew(0, 2), w_skew(1, 0));
  EXPECT_LT((w - BryantRateMatrix(eta) * eta_dot).norm(), 1e-8);
  const Eigen::Matrix3d t_dot = (BryantRateMatrix(eta + h * eta_dot) - BryantRateMatrix(eta - h * eta_dot)) / (2 * h);
  EXPECT_LT((t_dot - BryantRateMatrixDerivative(eta, eta_dot)).norm(), 1e-8);
}

TEST(RotationTest, ExpLogRoundTripAndBryant) {
  const Eigen::Vector3d r(0.02, -0.05, 0.03);
  EXPECT_LT((LogSO3(ExpSO3<double>(r)) - r).norm(), 1e-14);
  EXPECT_LT((ExpSO3<double>(Eigen::Vector3d::Zero()) - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  const Eigen::Vector3d eta(0.4, -0.3, 2.5);
  EXPECT_LT((RotationToBryant(BryantToRotation(eta)) - eta).norm(), 1e-12);
}

}  // namespace
}  // namespace rotorid

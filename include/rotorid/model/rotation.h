#pragma once

// Rotations: Bryant angles (R = Rz(yaw) Ry(pitch) Rx(roll), body to world) and rotation vectors.

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rotorid {

Eigen::Matrix3d BryantToRotation(const Eigen::Vector3d& roll_pitch_yaw);
// Roll, pitch, yaw of R (pitch in [-pi/2, pi/2]).
Eigen::Vector3d RotationToBryant(const Eigen::Matrix3d& r);
// T(eta) with w_body = T(eta) eta' for eta = [roll pitch yaw] (MODEL.md section 3).
Eigen::Matrix3d BryantRateMatrix(const Eigen::Vector3d& roll_pitch_yaw);
// d/dt T(eta) for the rates eta'.
Eigen::Matrix3d BryantRateMatrixDerivative(const Eigen::Vector3d& roll_pitch_yaw, const Eigen::Vector3d& rates);

// Exp of a rotation vector (Rodrigues), templated for Jets; exact near zero.
template <typename T>
Eigen::Matrix<T, 3, 3> ExpSO3(const Eigen::Matrix<T, 3, 1>& r) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta_sq = r.squaredNorm();
  Eigen::Matrix<T, 3, 3> k;
  k << T(0), -r.z(), r.y(), r.z(), T(0), -r.x(), -r.y(), r.x(), T(0);
  T a, b;  // sin(theta)/theta, (1 - cos theta)/theta^2
  if (theta_sq < T(1e-12)) {
    a = T(1) - theta_sq / T(6);
    b = T(0.5) - theta_sq / T(24);
  } else {
    const T theta = sqrt(theta_sq);
    a = sin(theta) / theta;
    b = (T(1) - cos(theta)) / theta_sq;
  }
  return Eigen::Matrix<T, 3, 3>::Identity() + a * k + b * k * k;
}

Eigen::Vector3d LogSO3(const Eigen::Matrix3d& r);

}  // namespace rotorid

#include "rotorid/model/rotation.h"

#include <algorithm>

namespace rotorid {

Eigen::Matrix3d BryantToRotation(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d RotationToBryant(const Eigen::Matrix3d& r) {
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return {roll, pitch, yaw};
}

// w_body = Rx^T (e_x roll' + Ry^T e_y pitch' + Ry^T Rz^T e_z yaw'), written out.
Eigen::Matrix3d BryantRateMatrix(const Eigen::Vector3d& rpy) {
  const double sr = std::sin(rpy.x()), cr = std::cos(rpy.x());
  const double sp = std::sin(rpy.y()), cp = std::cos(rpy.y());
  Eigen::Matrix3d t;
  t << 1, 0, -sp,  //
      0, cr, sr * cp, //
      0, -sr, cr * cp;
  return t;
}

Eigen::Matrix3d BryantRateMatrixDerivative(const Eigen::Vector3d& rpy, const Eigen::Vector3d& rates) {
  const double sr = std::sin(rpy.x()), cr = std::cos(rpy.x());
  const double sp = std::sin(rpy.y()), cp = std::cos(rpy.y());
  const double dr = rates.x(), dp = rates.y();
  Eigen::Matrix3d t;
  t << 0, 0, -cp * dp,                             //
      0, -sr * dr, cr * cp * dr - sr * sp * dp,    //
      0, -cr * dr, -sr * cp * dr - cr * sp * dp;
  return t;
}

Eigen::Vector3d LogSO3(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

}  // namespace rotorid

#include "rotorid/model/physical_consistency.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "rotorid/core/text.h"

namespace rotorid {

namespace {

// (tr(A)/2) 1 - A: the second-moment matrix int p p^T dm of a body whose inertia is A.
Eigen::Matrix3d SecondMoments(const Eigen::Matrix3d& inertia) {
  return 0.5 * inertia.trace() * Eigen::Matrix3d::Identity() - inertia;
}

std::string AxisText(const Eigen::Vector3d& axis) {
  // An axis has no sign: show it with its largest entry positive.
  Eigen::Index largest = 0;
  axis.cwiseAbs().maxCoeff(&largest);
  const Eigen::Vector3d a = axis[largest] < 0 ? Eigen::Vector3d(-axis) : axis;
  return "(" + FormatValue("%.2f", a.x()) + ", " + FormatValue("%.2f", a.y()) + ", " + FormatValue("%.2f", a.z()) + ")";
}

}  // namespace

Eigen::Matrix4d PseudoInertia(double mass_kg, const BodyParameters& body) {
  Eigen::Matrix4d j;
  j.topLeftCorner<3, 3>() = SecondMoments(body.inertia);
  j.topRightCorner<3, 1>() = body.first_moment;
  j.bottomLeftCorner<1, 3>() = body.first_moment.transpose();
  j(3, 3) = mass_kg;
  return j;
}

PhysicalConsistency CheckPhysicalConsistency(double mass_kg, const BodyParameters& body, double relative_tolerance) {
  PhysicalConsistency result;
  if (!std::isfinite(mass_kg) || mass_kg <= 0.0) {
    result.problem = "the mass " + ShortNumber(mass_kg) + " kg is not positive";
    return result;
  }
  if (!body.first_moment.allFinite() || !body.inertia.allFinite()) {
    result.problem = "a first moment or inertia is not finite";
    return result;
  }
  const Eigen::Vector3d c = body.first_moment / mass_kg;
  result.centre_of_mass_m = c;
  const Eigen::Matrix3d symmetric = 0.5 * (body.inertia + body.inertia.transpose());
  result.inertia_at_com = symmetric - mass_kg * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> second(SecondMoments(result.inertia_at_com));
  result.second_moments_at_com = second.eigenvalues();
  result.principal_axes = second.eigenvectors();
  // I_c = tr(Sigma_c) 1 - Sigma_c shares Sigma_c's axes: its moments are the sums of the other two.
  const Eigen::Vector3d sigma = result.second_moments_at_com;
  result.principal_moments_at_com = Eigen::Vector3d(sigma[1] + sigma[2], sigma[0] + sigma[2], sigma[0] + sigma[1]);
  std::sort(result.principal_moments_at_com.data(), result.principal_moments_at_com.data() + 3);
  for (int k = 0; k < 3; ++k) result.rms_extent_m[k] = std::copysign(std::sqrt(std::abs(sigma[k]) / mass_kg), sigma[k]);
  const double largest = std::max(sigma.cwiseAbs().maxCoeff(), 0.0);
  result.consistent = sigma[0] > relative_tolerance * largest && largest > 0.0;
  if (!result.consistent) {
    result.problem = "the mass would have an RMS extent of " + ShortNumber(1e3 * result.rms_extent_m[0]) +
                     " mm along " + AxisText(result.principal_axes.col(0)) + " about the centre of mass (" +
                     ShortNumber(1e3 * c.x()) + ", " + ShortNumber(1e3 * c.y()) + ", " + ShortNumber(1e3 * c.z()) +
                     ") mm; inertia about it " + ShortNumber(result.principal_moments_at_com[0]) + ", " +
                     ShortNumber(result.principal_moments_at_com[1]) + ", " +
                     ShortNumber(result.principal_moments_at_com[2]) + " kg m^2";
  }
  return result;
}

}  // namespace rotorid

#pragma once

// Physical consistency of a configuration's inertial parameters (MODEL.md 10, INTERFACE.md 6): ten
// numbers (m, ms, I at O_d) describe a rigid body only if the pseudo-inertia matrix
//
//     J = [[ (tr(I)/2) 1 - I ,  ms ],
//          [ ms^T            ,  m  ]]
//
// is positive definite (Wensing, Kim, Slotine, RA-L 2017). J is the body's second-moment matrix
// int [p; 1][p; 1]^T dm, so with m > 0 it is positive definite exactly when the second moments about
// the centre of mass, Sigma_c = J's Schur complement = (tr(I_c)/2) 1 - I_c, are: every direction of
// the body has a positive extent. That form is the one reported: its eigenvalues are m times the
// squared RMS extents of the mass along the principal axes, so a violation reads in millimetres.

#include <Eigen/Core>
#include <string>

#include "rotorid/model/parameters.h"

namespace rotorid {

// J of a body of mass m with first moment ms and inertia I at O_d (kg, kg m, kg m^2).
Eigen::Matrix4d PseudoInertia(double mass_kg, const BodyParameters& body);

struct PhysicalConsistency {
  bool consistent = false;
  Eigen::Vector3d centre_of_mass_m = Eigen::Vector3d::Zero();  // c = ms / m, in F_d
  Eigen::Matrix3d inertia_at_com = Eigen::Matrix3d::Zero();    // I_c = I - m (|c|^2 1 - c c^T)
  // Eigenvalues of I_c and of Sigma_c, ascending (kg m^2).
  Eigen::Vector3d principal_moments_at_com = Eigen::Vector3d::Zero();
  Eigen::Vector3d second_moments_at_com = Eigen::Vector3d::Zero();
  // Columns: the principal axes of Sigma_c (and of I_c), in the order of second_moments_at_com.
  Eigen::Matrix3d principal_axes = Eigen::Matrix3d::Identity();
  // Signed RMS extent of the mass along each principal axis (m): sqrt(|sigma_k| / m), negative where
  // sigma_k < 0 (no body has it).
  Eigen::Vector3d rms_extent_m = Eigen::Vector3d::Zero();
  // Why not, in words ("the mass has an extent of -4.1 mm along (0.00, 0.99, 0.12): ..."); empty when
  // consistent.
  std::string problem;
};

// Consistent when m > 0, every value is finite and Sigma_c is positive definite. A body whose smallest
// second moment is below `relative_tolerance` times the largest counts as flat, not consistent (J
// singular: a planar body is a limit no real airframe reaches).
PhysicalConsistency CheckPhysicalConsistency(double mass_kg, const BodyParameters& body,
                                             double relative_tolerance = 1e-9);

}  // namespace rotorid

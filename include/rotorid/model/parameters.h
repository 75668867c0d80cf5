#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rotorid {

// chi of one configuration, in MODEL.md's order. Products of inertia are entries of the inertia
// matrix at O_d (I_xy = -sum m x y).
inline constexpr int kNumBodyParameters = 9;
inline constexpr std::array<const char*, kNumBodyParameters> kBodyParameterNames = {
    "ms_x", "ms_y", "ms_z", "I_xx", "I_yy", "I_zz", "I_xy", "I_xz", "I_yz"};
inline constexpr int kNumRotorCoefficients = 2;
inline constexpr std::array<const char*, kNumRotorCoefficients> kRotorCoefficientNames = {"kt", "kd"};

inline constexpr int kNumWrenchComponents = 6;
inline constexpr std::array<const char*, kNumWrenchComponents> kWrenchComponentNames = {"Fx", "Fy", "Fz",
                                                                                        "Mx", "My", "Mz"};

// Rigid-body parameters of one configuration: first moment ms = m * c (kg m) and the inertia
// matrix at O_d in F_d (kg m^2).
struct BodyParameters {
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();

  // [ms_x ms_y ms_z I_xx I_yy I_zz I_xy I_xz I_yz]
  Eigen::Matrix<double, kNumBodyParameters, 1> ToVector() const;
  static BodyParameters FromVector(const Eigen::Ref<const Eigen::VectorXd>& chi);
};

// Propeller coefficients: thrust kt (N s^2) and drag torque kd (N m s^2), shared by all rotors.
struct RotorCoefficients {
  double kt = 0.0;
  double kd = 0.0;
};

// Full parameter set of one configuration with its mass.
struct VehicleParameters {
  double mass_kg = 0.0;
  BodyParameters body;
  RotorCoefficients rotor;
};

// kt, kd and the inertia's diagonal (a system parameter name, "kd" or "<config>.I_xx"): parameters
// whose physics fixes their sign (positive) and excludes zero.
bool PositiveByPhysics(const std::string& name);

// Adds a point mass (kg) at position p (m, in F_d) to the body parameters: exact for ms and the
// inertia at O_d (I += m (|p|^2 1 - p p^T)).
BodyParameters AddPointMass(const BodyParameters& body, double mass_kg, const Eigen::Vector3d& p_m);

}  // namespace rotorid

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
#include <array>
#include <cmath>
#include <string>
#include <vector>

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

// The values of the diagonal inertia entry I(axis, axis) (kg m^2) with which the body is consistent,
// the other parameters held: an interval, since the consistent set is convex (I_zz between
// |I_xx - I_yy| and I_xx + I_yy for a body centred at O_d). {NaN, NaN} when no value makes it a body.
struct InertiaRange {
  double low = 0.0;
  double high = 0.0;
  bool empty() const { return !(high > low); }
};
InertiaRange AllowedDiagonalInertia(double mass_kg, const BodyParameters& body, int axis);
// The values t >= 0 with which the body with inertia I + t `direction` is consistent (an interval).
InertiaRange AllowedInertiaShift(double mass_kg, const BodyParameters& body, const Eigen::Matrix3d& direction);

// The log-Cholesky parameterisation of J (Rucker and Wensing, "Smooth parameterization of rigid-body
// inertia", RA-L 2022): J = U U^T with U upper triangular,
//
//     U = e^alpha [[e^d1, s12, s13, t1],
//                  [0,    e^d2, s23, t2],
//                  [0,    0,    e^d3, t3],
//                  [0,    0,    0,    1 ]],
//
// theta = [alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3]. Every theta is a consistent body (m = e^(2 alpha),
// ms = m t, Sigma = J's upper-left block), every consistent body has exactly one theta: an estimator
// working on theta with alpha held at the known mass cannot leave the consistent set.
inline constexpr int kNumLogCholesky = 10;

// The body parameters [ms_x ms_y ms_z I_xx I_yy I_zz I_xy I_xz I_yz] (BodyParameters::ToVector's order)
// and the mass of `theta`. Templated on the scalar for Ceres' Jets (the projection below, refinements).
template <typename T>
void BodyFromLogCholesky(const T* theta, T* chi, T* mass) {
  using std::exp;
  const T scale = exp(theta[0]);
  // Rows of U / e^alpha (U's last row is e^alpha [0 0 0 1]).
  const T u[3][4] = {{exp(theta[1]), theta[4], theta[6], theta[7]},
                     {T(0.0), exp(theta[2]), theta[5], theta[8]},
                     {T(0.0), T(0.0), exp(theta[3]), theta[9]}};
  const T scale_sq = scale * scale;
  T sigma[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      T sum(0.0);
      for (int k = 0; k < 4; ++k) sum += u[i][k] * u[j][k];
      sigma[i][j] = scale_sq * sum;
    }
  *mass = scale_sq;
  for (int i = 0; i < 3; ++i) chi[i] = scale_sq * u[i][3];  // J_i3 = U_i3 U_33
  // I = tr(Sigma) 1 - Sigma; the products are I's entries (I_xy = -Sigma_xy).
  chi[3] = sigma[1][1] + sigma[2][2];
  chi[4] = sigma[0][0] + sigma[2][2];
  chi[5] = sigma[0][0] + sigma[1][1];
  chi[6] = -sigma[0][1];
  chi[7] = -sigma[0][2];
  chi[8] = -sigma[1][2];
}

// theta of a consistent body (the inverse of BodyFromLogCholesky); throws rotorid::Error naming the
// problem (CheckPhysicalConsistency) when the body is not consistent.
Eigen::Matrix<double, kNumLogCholesky, 1> LogCholeskyOf(double mass_kg, const BodyParameters& body);

// The consistent bodies of a known mass with some of the nine body parameters held at given values (a
// refinement holds the parameters the essential selection discarded at 0): a smooth chart by theta's
// entries with alpha held at the mass, where a held first moment fixes its t_i (ms = m t) and a held
// product of inertia fixes its s_ij (J's off-diagonal entries are m (U U^T)_ij, linear in s_ij given the
// rest: s23 and s13 first, then s12). Every coordinate vector is a body with the held values, every
// such body has one coordinate vector. The diagonal inertia cannot be held (no body has 0 there).
// Coordinates: theta's d1 d2 d3 s12 s23 s13 t1 t2 t3 that are not fixed by a held parameter, in that order.
class ConsistentBodyChart {
 public:
  using Vector9 = Eigen::Matrix<double, kNumBodyParameters, 1>;
  // held[k]: body parameter k (BodyParameters::ToVector's order) held at held_value[k]. Throws
  // rotorid::Error for a held diagonal inertia or a mass that is not positive.
  ConsistentBodyChart(double mass_kg, const std::array<bool, kNumBodyParameters>& held, const Vector9& held_value);

  int dimension() const { return static_cast<int>(free_theta_.size()); }
  double mass() const { return mass_; }

  // The body (ToVector's order) at `coordinates` (dimension() of them).
  template <typename T>
  void Body(const T* coordinates, T* chi) const;
  // The coordinates of a consistent body; false when it is none (J not positive definite). A body off
  // the held values maps to the one with its free coordinates and the held values.
  bool Coordinates(const Vector9& chi, Eigen::VectorXd* coordinates) const;

 private:
  double mass_, alpha_;
  std::array<bool, kNumBodyParameters> held_;
  Vector9 held_value_;
  std::vector<int> free_theta_;  // theta's entries (1..9) that are coordinates
};

template <typename T>
void ConsistentBodyChart::Body(const T* coordinates, T* chi) const {
  using std::exp;
  T theta[kNumLogCholesky];
  for (T& t : theta) t = T(0.0);
  theta[0] = T(alpha_);
  for (size_t k = 0; k < free_theta_.size(); ++k) theta[free_theta_[k]] = coordinates[k];
  // theta = [alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3]; ms_i = m t_i; J_ij = -I_ij = m (U U^T)_ij / e^2alpha.
  for (int i = 0; i < 3; ++i)
    if (held_[i]) theta[7 + i] = T(held_value_[i] / mass_);
  const T& t1 = theta[7];
  const T& t2 = theta[8];
  const T& t3 = theta[9];
  if (held_[8]) theta[5] = (T(-held_value_[8] / mass_) - t2 * t3) / exp(theta[3]);                        // I_yz: s23
  if (held_[7]) theta[6] = (T(-held_value_[7] / mass_) - t1 * t3) / exp(theta[3]);                        // I_xz: s13
  if (held_[6]) theta[4] = (T(-held_value_[6] / mass_) - theta[6] * theta[5] - t1 * t2) / exp(theta[2]);  // I_xy
  T mass;
  BodyFromLogCholesky(theta, chi, &mass);
  for (int k = 0; k < kNumBodyParameters; ++k)
    if (held_[k]) chi[k] = T(held_value_[k]);  // exact, not up to round-off
}

// The consistent body nearest to an estimate in the estimate's own metric: minimises
// (chi - chi0)^T Cov^-1 (chi - chi0) over the nine body parameters with the mass held, through the
// log-Cholesky parameterisation (Ceres). `sqrt_information` is a factor L^T of Cov^-1 (rows: residuals,
// one per independent direction the estimate knows; a parameter it does not know has a zero column
// and is free). An estimate that is consistent already is its own projection (distance 0).
struct ConsistentProjection {
  BodyParameters body;
  double distance_std = 0.0;  // sqrt of the minimum: the Mahalanobis distance, in std
  // The largest single-parameter move, in that parameter's std, and its index in ToVector's order.
  double largest_move_std = 0.0;
  int largest_move_parameter = -1;
  bool converged = true;
};
// `start`: a consistent body to start from (the one the model predicts with), else the estimate with
// its negative second moments raised. `held`: parameters that keep the estimate's values (a refinement's
// discarded ones, held at 0; ConsistentBodyChart); not the diagonal inertia.
ConsistentProjection ProjectOntoConsistentBodies(double mass_kg, const BodyParameters& estimate,
                                                 const Eigen::MatrixXd& sqrt_information,
                                                 const Eigen::Matrix<double, kNumBodyParameters, 1>& std_dev,
                                                 const BodyParameters* start = nullptr,
                                                 const std::array<bool, kNumBodyParameters>& held = {});

}  // namespace rotorid

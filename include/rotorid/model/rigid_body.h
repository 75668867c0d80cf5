#pragma once

// The one model of rotorid: Newton-Euler at O_d in F_d (MODEL.md section 1) and the paper's rotor
// model, templated on the scalar so that the simulator and the TLS (double) and the Ceres
// refinement (ceres::Jet) use the same equations.
//
//   m s + [w'x] ms + [wx]^2 ms   = f        s  = a - R^T g_w  (specific force at O_d)
//   I w' + w x (I w) - [s x] ms  = tau      chi = [ms_x ms_y ms_z I_xx I_yy I_zz I_xy I_xz I_yz]
//
// so that m D_m(s) + D(w, w', s) chi = D_k(Omega) chi_k with chi_k = [kt kd].

#include <Eigen/Core>
#include <Eigen/Dense>

#include "rotorid/core/vehicle.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Wrench = Eigen::Matrix<T, 6, 1>;

template <typename T>
Eigen::Matrix<T, 3, 3> Skew(const Vec3<T>& v) {
  Eigen::Matrix<T, 3, 3> m;
  m << T(0), -v.z(), v.y(),  //
      v.z(), T(0), -v.x(),   //
      -v.y(), v.x(), T(0);
  return m;
}

// L(v): I v = L(v) [I_xx I_yy I_zz I_xy I_xz I_yz]^T.
template <typename T>
Eigen::Matrix<T, 3, 6> InertiaProductMatrix(const Vec3<T>& v) {
  Eigen::Matrix<T, 3, 6> l;
  l << v.x(), T(0), T(0), v.y(), v.z(), T(0),  //
      T(0), v.y(), T(0), v.x(), T(0), v.z(),   //
      T(0), T(0), v.z(), T(0), v.x(), v.y();
  return l;
}

// D (6x9): columns in chi's order.
//   D = [ [w' x] + [w x]^2     0                   ]
//       [ -[s x]               L(w') + [w x] L(w)  ]
// [w x]^2 and [w x] L(w) are written out: each entry is one product or the sum of two (the matrix
// products' other terms are zero), so the values are those of the products to the last bit, at a
// fraction of their cost (this runs per row sample, and with ceres::Jet in the refinement).
template <typename T>
Eigen::Matrix<T, 6, kNumBodyParameters> BodyRegressor(const Vec3<T>& w, const Vec3<T>& w_dot, const Vec3<T>& s) {
  const T xx = w.x() * w.x(), yy = w.y() * w.y(), zz = w.z() * w.z();
  const T xy = w.x() * w.y(), xz = w.x() * w.z(), yz = w.y() * w.z();
  Eigen::Matrix<T, 3, 3> w_skew_squared;
  w_skew_squared << -zz - yy, xy, xz,  //
      xy, -zz - xx, yz,                //
      xz, yz, -yy - xx;
  Eigen::Matrix<T, 3, 6> w_skew_l;  // [w x] L(w)
  w_skew_l << T(0), -yz, yz, -xz, xy, yy - zz,  //
      xz, T(0), -xz, yz, zz - xx, -xy,          //
      -xy, xy, T(0), xx - yy, -yz, xz;
  Eigen::Matrix<T, 6, kNumBodyParameters> d;
  d.template block<3, 3>(0, 0) = Skew<T>(w_dot) + w_skew_squared;
  d.template block<3, 6>(0, 3).setZero();
  d.template block<3, 3>(3, 0) = -Skew<T>(s);
  d.template block<3, 6>(3, 3) = InertiaProductMatrix<T>(w_dot) + w_skew_l;
  return d;
}

// D_m (6x1) = [s; 0].
template <typename T>
Wrench<T> MassRegressor(const Vec3<T>& s) {
  Wrench<T> d;
  d << s, T(0), T(0), T(0);
  return d;
}

// The paper's rotor model: every factor 1.
struct UnitRotorFactors {
  double operator[](int /*rotor*/) const { return 1.0; }
};

// D_k with the per-rotor factors of the rotor-wrench effects (rotorid/model/effects.h): rotor i's
// Omega_i^2 counts f_i times in the thrust column and g_i times in the drag-torque column.
template <typename T, typename Derived, typename Factors>
Eigen::Matrix<T, 6, kNumRotorCoefficients> RotorRegressor(const Eigen::MatrixBase<Derived>& omega,
                                                          const Vehicle& vehicle, const Factors& thrust_factor,
                                                          const Factors& torque_factor) {
  Eigen::Matrix<T, 6, kNumRotorCoefficients> d = Eigen::Matrix<T, 6, kNumRotorCoefficients>::Zero();
  for (int i = 0; i < vehicle.num_rotors(); ++i) {
    const T omega_sq = T(omega[i]) * T(omega[i]);
    const T thrust = thrust_factor[i] * omega_sq;
    const Eigen::Vector3d& p = vehicle.rotors[i].position_m;
    d(2, 0) += thrust;
    d(3, 0) += p.y() * thrust;
    d(4, 0) -= p.x() * thrust;
    d(5, 1) -= double(vehicle.rotors[i].spin) * torque_factor[i] * omega_sq;
  }
  return d;
}

// D_k (6x2) from the rotor speeds |Omega_i| (rad/s): columns for kt and kd.
template <typename T, typename Derived>
Eigen::Matrix<T, 6, kNumRotorCoefficients> RotorRegressor(const Eigen::MatrixBase<Derived>& omega,
                                                          const Vehicle& vehicle) {
  return RotorRegressor<T>(omega, vehicle, UnitRotorFactors{}, UnitRotorFactors{});
}

// Number of columns of one configuration's IDIM row block: [-D_k | D | m D_m].
inline constexpr int kNumIdimColumns = kNumRotorCoefficients + kNumBodyParameters + 1;

// The IDIM rows of one sample (6 x 12), W_t's layout [W_k W m W_m] with W_k = -D_k, so that
// rows * [kt kd chi 1]^T is the equation error e (MODEL.md section 1).
template <typename T, typename Derived>
Eigen::Matrix<T, 6, kNumIdimColumns> IdimRows(const Vec3<T>& w, const Vec3<T>& w_dot, const Vec3<T>& s,
                                             const Eigen::MatrixBase<Derived>& omega, const Vehicle& vehicle) {
  Eigen::Matrix<T, 6, kNumIdimColumns> rows;
  rows.template leftCols<kNumRotorCoefficients>() = -RotorRegressor<T>(omega, vehicle);
  rows.template block<6, kNumBodyParameters>(0, kNumRotorCoefficients) = BodyRegressor<T>(w, w_dot, s);
  rows.template rightCols<1>() = T(vehicle.mass_kg) * MassRegressor<T>(s);
  return rows;
}

// The rows with the rotor-wrench effects' terms: the rotor columns with their per-rotor factors, and
// the extra wrench in the known column (e = rigid-body wrench - rotor wrench - extra).
template <typename T, typename Derived>
void ApplyRotorWrenchTerms(const Eigen::MatrixBase<Derived>& omega, const Vehicle& vehicle,
                           const RotorWrenchTerms<T>& terms, Eigen::Matrix<T, 6, kNumIdimColumns>* rows) {
  rows->template leftCols<kNumRotorCoefficients>() =
      -RotorRegressor<T>(omega, vehicle, terms.thrust_factor, terms.torque_factor);
  rows->template rightCols<1>() -= terms.extra;
}

// Newton-Euler wrench needed at O_d for the motion (s, w, w') of a body with these parameters.
template <typename T>
Wrench<T> RigidBodyWrench(const Vec3<T>& w, const Vec3<T>& w_dot, const Vec3<T>& s, T mass, const Vec3<T>& ms,
                          const Eigen::Matrix<T, 3, 3>& inertia) {
  Wrench<T> wrench;
  wrench.template head<3>() = mass * s + w_dot.cross(ms) + w.cross(w.cross(ms));
  wrench.template tail<3>() = inertia * w_dot + w.cross(inertia * w) - s.cross(ms);
  return wrench;
}

// Forward dynamics: (s, w') of the body under the wrench (f, tau) at O_d, from the 6x6 spatial
// inertia system [m 1, -[ms x]; [ms x], I] [s; w'] = [f - w x (w x ms); tau - w x I w].
template <typename T>
void ForwardDynamics(const Vec3<T>& w, const Wrench<T>& wrench, T mass, const Vec3<T>& ms,
                     const Eigen::Matrix<T, 3, 3>& inertia, Vec3<T>* s, Vec3<T>* w_dot) {
  Eigen::Matrix<T, 6, 6> spatial;
  const Eigen::Matrix<T, 3, 3> ms_skew = Skew<T>(ms);
  spatial << mass * Eigen::Matrix<T, 3, 3>::Identity(), -ms_skew, ms_skew, inertia;
  Wrench<T> rhs;
  rhs.template head<3>() = wrench.template head<3>() - w.cross(w.cross(ms));
  rhs.template tail<3>() = wrench.template tail<3>() - w.cross(inertia * w);
  const Wrench<T> acc = spatial.ldlt().solve(rhs);
  *s = acc.template head<3>();
  *w_dot = acc.template tail<3>();
}

// Rotor wrench D_k [kt kd]^T at O_d for the rotor speeds omega (rad/s).
template <typename T, typename Derived>
Wrench<T> RotorWrench(const Eigen::MatrixBase<Derived>& omega, T kt, T kd, const Vehicle& vehicle) {
  const Eigen::Matrix<T, 6, kNumRotorCoefficients> d = RotorRegressor<T>(omega, vehicle);
  return d.col(0) * kt + d.col(1) * kd;
}

// The rotors' wrench with the rotor-wrench effects' terms (the simulator's forward physics).
template <typename T, typename Derived>
Wrench<T> RotorWrench(const Eigen::MatrixBase<Derived>& omega, T kt, T kd, const Vehicle& vehicle,
                      const RotorWrenchTerms<T>& terms) {
  const Eigen::Matrix<T, 6, kNumRotorCoefficients> d =
      RotorRegressor<T>(omega, vehicle, terms.thrust_factor, terms.torque_factor);
  return d.col(0) * kt + d.col(1) * kd + terms.extra;
}

}  // namespace rotorid

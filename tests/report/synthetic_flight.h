#pragma once

// A synthetic flight whose log satisfies the IDIM exactly (before noise): smooth angular motion
// and thrust variations are chosen, the specific force and the rotor speeds are solved from the
// rigid-body and rotor model of MODEL.md. Used by the report tests and the report benchmark; it
// needs nothing from the simulator.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <random>
#include <string>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"
#include "rotorid/model/parameters.h"

namespace rotorid::testing {

// The paper's configuration A as a plus quad (MODEL.md section 6).
inline Vehicle PaperVehicleA() {
  Vehicle v;
  v.name = "A";
  v.mass_kg = 1.285;
  const double d = 0.225;
  v.rotors = {{Eigen::Vector3d(0, -d, 0), +1},
              {Eigen::Vector3d(0, d, 0), +1},
              {Eigen::Vector3d(d, 0, 0), -1},
              {Eigen::Vector3d(-d, 0, 0), -1}};
  return v;
}

inline VehicleParameters PaperParametersA() {
  VehicleParameters p;
  p.mass_kg = 1.285;
  p.body.first_moment = Eigen::Vector3d(-4e-3, -2e-3, -6e-3);
  p.body.inertia = Eigen::Vector3d(1.8e-2, 1.9e-2, 2.9e-2).asDiagonal();
  p.rotor.kt = 3.6e-6;
  p.rotor.kd = 5.1e-8;
  return p;
}

struct SyntheticFlightOptions {
  double duration_s = 30.0;
  double rate_hz = 200.0;
  double gyro_noise_radps = 0.005;
  double acc_noise_mps2 = 0.05;
  // The logged rotor signal leads the true one by this much (INTERFACE.md's delay effect).
  double delay_s = 0.0;
  unsigned seed = 1;
};

inline FlightLog SyntheticFlight(const Vehicle& vehicle, const VehicleParameters& truth,
                                 const SyntheticFlightOptions& options, const std::string& source) {
  const int n = static_cast<int>(std::round(options.duration_s * options.rate_hz));
  const double g = kStandardGravity, m = vehicle.mass_kg;
  const Eigen::Vector3d ms = truth.body.first_moment;
  const Eigen::Matrix3d inertia = truth.body.inertia;
  // Sums of sines per axis (rad/s): roll and pitch well excited, yaw gently (kd is small).
  struct Tone {
    double amplitude, hz, phase;
  };
  const Tone tones[3][3] = {{{0.8, 0.35, 0.1}, {0.4, 0.9, 1.0}, {0.15, 1.7, 2.0}},
                            {{0.7, 0.28, 0.5}, {0.35, 1.1, 0.3}, {0.12, 1.9, 1.2}},
                            {{0.08, 0.2, 0.7}, {0.04, 0.55, 0.2}, {0.02, 1.3, 2.5}}};
  auto angular = [&](double t, Eigen::Vector3d* w, Eigen::Vector3d* w_dot) {
    w->setZero();
    w_dot->setZero();
    for (int axis = 0; axis < 3; ++axis)
      for (const Tone& tone : tones[axis]) {
        const double omega = 2.0 * M_PI * tone.hz;
        (*w)[axis] += tone.amplitude * std::sin(omega * t + tone.phase);
        (*w_dot)[axis] += tone.amplitude * omega * std::cos(omega * t + tone.phase);
      }
  };
  auto skew = [](const Eigen::Vector3d& v) {
    Eigen::Matrix3d s;
    s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
    return s;
  };
  // Omega^2 from [kt S, Mx, My, Mz] (MODEL.md: D_k columns).
  Eigen::Matrix4d rotor_map;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d p = vehicle.rotors[i].position_m;
    rotor_map(0, i) = truth.rotor.kt;
    rotor_map(1, i) = truth.rotor.kt * p.y();
    rotor_map(2, i) = -truth.rotor.kt * p.x();
    rotor_map(3, i) = -truth.rotor.kd * vehicle.rotors[i].spin;
  }
  const Eigen::Matrix4d wrench_to_omega_sq = rotor_map.inverse();

  FlightLog log;
  log.source = source;
  log.gravity_mps2 = g;
  log.t_s.resize(n);
  log.gyro_radps.resize(n, 3);
  log.acc_mps2.resize(n, 3);
  log.rotor_radps.resize(n, 4);
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  auto true_rotor_speed = [&](double t, Eigen::Vector3d* w_out, Eigen::Vector3d* s_out) {
    Eigen::Vector3d w, w_dot;
    angular(t, &w, &w_dot);
    const Eigen::Vector3d body_terms = (skew(w_dot) + skew(w) * skew(w)) * ms;
    // Thrust only along z: the lateral specific force follows from the force balance.
    Eigen::Vector3d s;
    s.x() = -body_terms.x() / m;
    s.y() = -body_terms.y() / m;
    s.z() = g + 1.2 * std::sin(2.0 * M_PI * 0.4 * t) + 0.6 * std::sin(2.0 * M_PI * 1.3 * t + 0.4);
    const double thrust = m * s.z() + body_terms.z();
    const Eigen::Vector3d moment = inertia * w_dot + w.cross(inertia * w) - s.cross(ms);
    const Eigen::Vector4d omega_sq = wrench_to_omega_sq * Eigen::Vector4d(thrust, moment.x(), moment.y(), moment.z());
    if (w_out) *w_out = w;
    if (s_out) *s_out = s;
    return omega_sq.cwiseMax(0.0).cwiseSqrt().eval();
  };
  for (int k = 0; k < n; ++k) {
    const double t = k / options.rate_hz;
    Eigen::Vector3d w, s;
    true_rotor_speed(t, &w, &s);
    log.t_s[k] = t;
    for (int axis = 0; axis < 3; ++axis) {
      log.gyro_radps(k, axis) = w[axis] + options.gyro_noise_radps * unit(rng);
      log.acc_mps2(k, axis) = s[axis] + options.acc_noise_mps2 * unit(rng);
    }
    // Omega_true(t) = Omega_log(t - delay)  <=>  Omega_log(t) = Omega_true(t + delay).
    log.rotor_radps.row(k) = true_rotor_speed(t + options.delay_s, nullptr, nullptr).transpose();
  }
  return log;
}

}  // namespace rotorid::testing

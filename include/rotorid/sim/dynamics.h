#pragma once

// Equations of motion of the simulated multirotor: a 6-DoF rigid body (first moment ms and full
// inertia at O_d, so the centre of mass need not be at O_d) driven by the paper's rotor model,
// plus first-order motor dynamics. Accelerations come from the model of
// rotorid/model/rigid_body.h (ForwardDynamics of RotorWrench), the same equations the
// identification inverts.
//
//   p' = v                 (O_d in the world frame, z up)
//   v' = R s + g_w         (s: specific force at O_d, body frame)
//   q' = q (0, w) / 2      (attitude, body to world)
//   w' from [m 1, -[ms x]; [ms x], I] [s; w'] = wrench - velocity terms
//   tau Omega' = Omega_cmd(t) - Omega     (Omega = Omega_cmd(t) when tau = 0)
//   S' = rate (Omega^2 - S), Omega_acting^2 = (1 - a) Omega^2 + a S   (a slow actuation component, a != 0)

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>

#include "rotorid/core/vehicle.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

struct SimState {
  Eigen::Vector3d position_w_m = Eigen::Vector3d::Zero();           // O_d in the world frame
  Eigen::Vector3d velocity_w_mps = Eigen::Vector3d::Zero();         // velocity of O_d, world frame
  Eigen::Quaterniond attitude_wb = Eigen::Quaterniond::Identity();  // body to world
  Eigen::Vector3d angular_velocity_b_radps = Eigen::Vector3d::Zero();
  Eigen::VectorXd rotor_speed_radps;  // actual |Omega_i|: the motor-lag state (unused when tau = 0)
  // S_i, the low-passed Omega_i^2 of a slow actuation component (empty: in steady state at Omega_i^2)
  Eigen::VectorXd slow_square_radps2;
};

// A force on the vehicle that rotorid's model does not have (a tether, a payload's pull, wind),
// acting at O_d, in the world frame: its horizontal part turns about z with `turn_period_s`
// (0: constant), like a wind whose direction drifts. It reaches the accelerometer like any force.
// `body_torque_nm`: a torque about O_d in the body frame (the torque bias `rotorid predict` observes).
struct ExternalForce {
  Eigen::Vector3d world_n = Eigen::Vector3d::Zero();
  double turn_period_s = 0.0;
  Eigen::Vector3d body_torque_nm = Eigen::Vector3d::Zero();

  bool active() const { return !world_n.isZero() || !body_torque_nm.isZero(); }
  Eigen::Vector3d At(double t_s) const;
};

struct BodyAcceleration {
  Eigen::Vector3d specific_force_b_mps2 = Eigen::Vector3d::Zero();          // s = R^T (a - g_w) at O_d
  Eigen::Vector3d angular_acceleration_b_radps2 = Eigen::Vector3d::Zero();  // w'
};

class MultirotorDynamics {
 public:
  // The rotor speed command (rad/s, one entry per rotor) the motors follow at time t.
  using RotorCommand = std::function<Eigen::VectorXd(double t_s)>;

  // gravity_mps2 >= 0 is g in g_w = [0, 0, -g]; motor_time_constant_s >= 0. A vehicle without rotors is
  // allowed (a free body). Throws rotorid::Error when the spatial inertia is not positive definite.
  // `rotor_wrench`: the rotor-wrench effects acting (rotorid/model/effects.h), the same models the
  // identification corrects for.
  MultirotorDynamics(const Vehicle& vehicle, const VehicleParameters& parameters, double gravity_mps2,
                     double motor_time_constant_s, EffectChain rotor_wrench = {}, ExternalForce external_force = {},
                     SlowActuation slow_actuation = {});

  // The rotor speeds acting at time t: the lag state, or the command itself when motor_time_constant_s = 0,
  // through the slow actuation component when there is one.
  Eigen::VectorXd ActingRotorSpeeds(double t_s, const SimState& state, const RotorCommand& command) const;
  // Their rates Omega_i': the lag's, or the slope of the (piecewise-linear) command.
  Eigen::VectorXd ActingRotorRates(double t_s, const SimState& state, const RotorCommand& command) const;
  // s and w' of the body in `state` at time t under the rotor wrench of these rotor speeds and rates
  // (rates matter only to rotor-wrench effects; empty: zero) and the external force.
  BodyAcceleration Accelerations(double t_s, const SimState& state, const Eigen::VectorXd& rotor_speed_radps,
                                 const Eigen::VectorXd& rotor_rate_radps2 = {}) const;
  // One classical Runge-Kutta (RK4) step of h seconds from t; the rotor lag is part of the state,
  // the quaternion is renormalised after the step.
  SimState Step(double t_s, const SimState& state, double h_s, const RotorCommand& command) const;

  const Vehicle& vehicle() const { return vehicle_; }
  const VehicleParameters& parameters() const { return parameters_; }
  double motor_time_constant_s() const { return motor_time_constant_s_; }
  Eigen::Vector3d gravity_w_mps2() const { return gravity_w_; }

 private:
  // Flat state [p v q(w,x,y,z) w Omega S] for the integrator (S only with a slow actuation component).
  Eigen::VectorXd Pack(const SimState& state) const;
  SimState Unpack(const Eigen::VectorXd& x) const;
  Eigen::VectorXd Derivative(double t_s, const Eigen::VectorXd& x, const RotorCommand& command) const;
  // Omega_i (the lag state or the command) and its rate, before the slow actuation component.
  Eigen::VectorXd MotorSpeeds(double t_s, const SimState& state, const RotorCommand& command) const;
  Eigen::VectorXd MotorRates(double t_s, const SimState& state, const RotorCommand& command) const;
  // S of the state, or Omega^2 when the state carries none (steady state).
  Eigen::VectorXd SlowSquare(const SimState& state, const Eigen::VectorXd& motor_speed) const;

  Vehicle vehicle_;
  VehicleParameters parameters_;
  Eigen::Vector3d gravity_w_;
  double motor_time_constant_s_;
  EffectChain rotor_wrench_;
  ExternalForce external_force_;
  SlowActuation slow_actuation_;
};

// Torque-free motion (no gravity, no rotors) of a body with mass, first moment and inertia at O_d,
// integrated by RK4 with steps of at most step_s: for conservation checks of the integrator.
SimState IntegrateFreeBody(double mass_kg, const BodyParameters& body, const SimState& initial, double duration_s,
                           double step_s);

// Linear momentum m v_G (world), angular momentum about the world origin (world) and kinetic
// energy of the rigid body in `state`; all conserved in torque-free motion.
Eigen::Vector3d LinearMomentumWorld(double mass_kg, const BodyParameters& body, const SimState& state);
Eigen::Vector3d AngularMomentumWorld(double mass_kg, const BodyParameters& body, const SimState& state);
double KineticEnergy(double mass_kg, const BodyParameters& body, const SimState& state);

}  // namespace rotorid

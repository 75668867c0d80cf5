#include "rotorid/sim/dynamics.h"

#include <cmath>
#include <utility>

#include "rotorid/core/error.h"
#include "rotorid/core/units.h"
#include "rotorid/model/rigid_body.h"

namespace rotorid {
namespace {

constexpr int kPositionIndex = 0;
constexpr int kVelocityIndex = 3;
constexpr int kQuaternionIndex = 6;  // w, x, y, z
constexpr int kAngularVelocityIndex = 10;
constexpr int kRotorIndex = 13;

}  // namespace

Eigen::Vector3d ExternalForce::At(double t_s) const {
  if (turn_period_s <= 0.0) return world_n;
  const double angle = 2.0 * kPi * t_s / turn_period_s;
  return Eigen::Vector3d(std::cos(angle) * world_n.x() - std::sin(angle) * world_n.y(),
                         std::sin(angle) * world_n.x() + std::cos(angle) * world_n.y(), world_n.z());
}

MultirotorDynamics::MultirotorDynamics(const Vehicle& vehicle, const VehicleParameters& parameters, double gravity_mps2,
                                       double motor_time_constant_s, EffectChain rotor_wrench,
                                       ExternalForce external_force, SlowActuation slow_actuation)
    : vehicle_(vehicle),
      parameters_(parameters),
      gravity_w_(0.0, 0.0, -gravity_mps2),
      motor_time_constant_s_(motor_time_constant_s),
      rotor_wrench_(std::move(rotor_wrench)),
      external_force_(external_force),
      slow_actuation_(slow_actuation) {
  if (!(gravity_mps2 >= 0.0) || !std::isfinite(gravity_mps2)) throw Error("gravity must be a finite number >= 0");
  if (!(motor_time_constant_s >= 0.0) || !std::isfinite(motor_time_constant_s))
    throw Error("motor_time_constant_s must be a finite number >= 0");
  if (!(slow_actuation.fraction >= 0.0 && slow_actuation.fraction <= 1.0) || !(slow_actuation.rate_per_s >= 0.0) ||
      !std::isfinite(slow_actuation.rate_per_s))
    throw Error("the slow actuation's fraction must be in [0, 1] and its rate a finite number >= 0");
  // The 6x6 spatial inertia must be positive definite, or ForwardDynamics has no unique answer.
  Eigen::Matrix<double, 6, 6> spatial;
  const Eigen::Matrix3d ms_skew = Skew<double>(parameters.body.first_moment);
  spatial << parameters.mass_kg * Eigen::Matrix3d::Identity(), -ms_skew, ms_skew, parameters.body.inertia;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(spatial);
  if (!(parameters.mass_kg > 0.0) || !(eigen.eigenvalues().minCoeff() > 0.0))
    throw Error(
        "the simulated body's mass, first moment and inertia are not physically consistent "
        "(spatial inertia not positive definite)");
}

Eigen::VectorXd MultirotorDynamics::MotorSpeeds(double t_s, const SimState& state, const RotorCommand& command) const {
  if (vehicle_.rotors.empty()) return Eigen::VectorXd();
  return motor_time_constant_s_ > 0.0 ? state.rotor_speed_radps : command(t_s);
}

Eigen::VectorXd MultirotorDynamics::SlowSquare(const SimState& state, const Eigen::VectorXd& motor_speed) const {
  if (state.slow_square_radps2.size() == motor_speed.size()) return state.slow_square_radps2;
  return motor_speed.array().square();
}

Eigen::VectorXd MultirotorDynamics::ActingRotorSpeeds(double t_s, const SimState& state,
                                                      const RotorCommand& command) const {
  const Eigen::VectorXd motor = MotorSpeeds(t_s, state, command);
  if (!slow_actuation_.active() || motor.size() == 0) return motor;
  const double a = slow_actuation_.fraction;
  return ((1.0 - a) * motor.array().square() + a * SlowSquare(state, motor).array()).max(0.0).sqrt();
}

Eigen::VectorXd MultirotorDynamics::ActingRotorRates(double t_s, const SimState& state,
                                                     const RotorCommand& command) const {
  const Eigen::VectorXd rates = MotorRates(t_s, state, command);
  if (!slow_actuation_.active() || rates.size() == 0) return rates;
  // d/dt sqrt(E), E = (1 - a) Omega^2 + a S.
  const double a = slow_actuation_.fraction;
  const Eigen::ArrayXd motor = MotorSpeeds(t_s, state, command).array(), slow = SlowSquare(state, motor).array();
  const Eigen::ArrayXd acting = ((1.0 - a) * motor.square() + a * slow).max(0.0).sqrt();
  const Eigen::ArrayXd acting_square_rate =
      2.0 * (1.0 - a) * motor * rates.array() + a * slow_actuation_.rate_per_s * (motor.square() - slow);
  return (acting > 0.0).select(acting_square_rate / (2.0 * acting), 0.0).matrix();
}

Eigen::VectorXd MultirotorDynamics::MotorRates(double t_s, const SimState& state, const RotorCommand& command) const {
  if (vehicle_.rotors.empty()) return Eigen::VectorXd();
  if (motor_time_constant_s_ > 0.0) return (command(t_s) - state.rotor_speed_radps) / motor_time_constant_s_;
  // The command is linear between its kinks and the integrator's steps end on them: the forward
  // slope is the step's own, except at a step's last RK4 stage, which sees the next one's.
  constexpr double kProbe = 1e-7;
  return (command(t_s + kProbe) - command(t_s)) / kProbe;
}

BodyAcceleration MultirotorDynamics::Accelerations(double t_s, const SimState& state,
                                                   const Eigen::VectorXd& rotor_speed_radps,
                                                   const Eigen::VectorXd& rotor_rate_radps2) const {
  Wrench<double> wrench = Wrench<double>::Zero();
  if (!vehicle_.rotors.empty()) {
    RotorWrenchTerms<double> terms(vehicle_.num_rotors());
    if (!rotor_wrench_.kinds.empty()) {
      RotorSample<double> sample;
      sample.vehicle = &vehicle_;
      sample.speed = rotor_speed_radps;
      sample.acceleration = rotor_rate_radps2.size() == rotor_speed_radps.size()
                                ? rotor_rate_radps2
                                : Eigen::VectorXd::Zero(rotor_speed_radps.size());
      sample.angular_velocity = state.angular_velocity_b_radps;
      const Eigen::Quaterniond attitude = state.attitude_wb.normalized();
      sample.velocity = attitude.conjugate() * state.velocity_w_mps;
      // The world's z = 0 is the ground.
      sample.height.resize(vehicle_.num_rotors());
      for (int i = 0; i < vehicle_.num_rotors(); ++i)
        sample.height[i] = (state.position_w_m + attitude * vehicle_.rotors[i].position_m).z();
      AddRotorWrench<double>(rotor_wrench_.kinds, rotor_wrench_.Parameters(), sample, &terms);
    }
    wrench = RotorWrench<double>(rotor_speed_radps, parameters_.rotor.kt, parameters_.rotor.kd, vehicle_, terms);
  }
  if (external_force_.active()) {
    wrench.head<3>() += state.attitude_wb.normalized().conjugate() * external_force_.At(t_s);
    wrench.tail<3>() += external_force_.body_torque_nm;
  }
  BodyAcceleration acc;
  ForwardDynamics<double>(state.angular_velocity_b_radps, wrench, parameters_.mass_kg, parameters_.body.first_moment,
                          parameters_.body.inertia, &acc.specific_force_b_mps2, &acc.angular_acceleration_b_radps2);
  return acc;
}

Eigen::VectorXd MultirotorDynamics::Pack(const SimState& state) const {
  const int n = vehicle_.num_rotors();
  Eigen::VectorXd x(kRotorIndex + (slow_actuation_.active() ? 2 * n : n));
  x.segment<3>(kPositionIndex) = state.position_w_m;
  x.segment<3>(kVelocityIndex) = state.velocity_w_mps;
  x.segment<4>(kQuaternionIndex) << state.attitude_wb.w(), state.attitude_wb.x(), state.attitude_wb.y(),
      state.attitude_wb.z();
  x.segment<3>(kAngularVelocityIndex) = state.angular_velocity_b_radps;
  if (state.rotor_speed_radps.size() == n)
    x.segment(kRotorIndex, n) = state.rotor_speed_radps;
  else
    x.segment(kRotorIndex, n).setZero();
  if (slow_actuation_.active()) x.tail(n) = SlowSquare(state, x.segment(kRotorIndex, n));
  return x;
}

SimState MultirotorDynamics::Unpack(const Eigen::VectorXd& x) const {
  SimState state;
  state.position_w_m = x.segment<3>(kPositionIndex);
  state.velocity_w_mps = x.segment<3>(kVelocityIndex);
  state.attitude_wb = Eigen::Quaterniond(x[kQuaternionIndex], x[kQuaternionIndex + 1], x[kQuaternionIndex + 2],
                                         x[kQuaternionIndex + 3]);
  state.angular_velocity_b_radps = x.segment<3>(kAngularVelocityIndex);
  state.rotor_speed_radps = x.segment(kRotorIndex, vehicle_.num_rotors());
  if (slow_actuation_.active()) state.slow_square_radps2 = x.tail(vehicle_.num_rotors());
  return state;
}

Eigen::VectorXd MultirotorDynamics::Derivative(double t_s, const Eigen::VectorXd& x,
                                               const RotorCommand& command) const {
  SimState state = Unpack(x);
  // RK4's intermediate quaternions are not unit; the rotation uses the normalised one, while q'
  // keeps the raw q so that the step stays a plain RK4 step.
  const Eigen::Matrix3d r_wb = state.attitude_wb.normalized().toRotationMatrix();
  const Eigen::VectorXd acting = ActingRotorSpeeds(t_s, state, command);
  // The acting rates only for rotor-wrench effects (else not needed).
  const Eigen::VectorXd rates =
      !rotor_wrench_.kinds.empty() ? ActingRotorRates(t_s, state, command) : Eigen::VectorXd();
  const BodyAcceleration acc = Accelerations(t_s, state, acting, rates);

  Eigen::VectorXd dx(x.size());
  dx.segment<3>(kPositionIndex) = state.velocity_w_mps;
  dx.segment<3>(kVelocityIndex) = r_wb * acc.specific_force_b_mps2 + gravity_w_;
  const Eigen::Vector3d& w = state.angular_velocity_b_radps;
  const Eigen::Quaterniond q_dot = state.attitude_wb * Eigen::Quaterniond(0.0, w.x(), w.y(), w.z());
  dx.segment<4>(kQuaternionIndex) << 0.5 * q_dot.w(), 0.5 * q_dot.x(), 0.5 * q_dot.y(), 0.5 * q_dot.z();
  dx.segment<3>(kAngularVelocityIndex) = acc.angular_acceleration_b_radps2;
  const int n = vehicle_.num_rotors();
  if (motor_time_constant_s_ > 0.0 && n > 0)
    dx.segment(kRotorIndex, n) = MotorRates(t_s, state, command);
  else
    dx.segment(kRotorIndex, n).setZero();
  if (slow_actuation_.active()) {
    const Eigen::VectorXd motor = MotorSpeeds(t_s, state, command);
    dx.tail(n) = slow_actuation_.rate_per_s * (motor.array().square() - state.slow_square_radps2.array()).matrix();
  }
  return dx;
}

SimState MultirotorDynamics::Step(double t_s, const SimState& state, double h_s, const RotorCommand& command) const {
  const Eigen::VectorXd x = Pack(state);
  const Eigen::VectorXd k1 = Derivative(t_s, x, command);
  const Eigen::VectorXd k2 = Derivative(t_s + 0.5 * h_s, x + 0.5 * h_s * k1, command);
  const Eigen::VectorXd k3 = Derivative(t_s + 0.5 * h_s, x + 0.5 * h_s * k2, command);
  const Eigen::VectorXd k4 = Derivative(t_s + h_s, x + h_s * k3, command);
  SimState next = Unpack(x + (h_s / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4));
  next.attitude_wb.normalize();
  // Without a lag the rotor speed is the command itself; keep the state showing what acts.
  if (motor_time_constant_s_ == 0.0 && !vehicle_.rotors.empty()) next.rotor_speed_radps = command(t_s + h_s);
  return next;
}

SimState IntegrateFreeBody(double mass_kg, const BodyParameters& body, const SimState& initial, double duration_s,
                           double step_s) {
  if (!(duration_s >= 0.0) || !(step_s > 0.0)) throw Error("IntegrateFreeBody needs duration >= 0 and step > 0");
  Vehicle free_body;
  free_body.mass_kg = mass_kg;
  VehicleParameters parameters;
  parameters.mass_kg = mass_kg;
  parameters.body = body;
  const MultirotorDynamics dynamics(free_body, parameters, /*gravity_mps2=*/0.0, /*motor_time_constant_s=*/0.0);
  const MultirotorDynamics::RotorCommand no_rotors = [](double) { return Eigen::VectorXd(); };
  const int num_steps = static_cast<int>(std::ceil(duration_s / step_s - 1e-9));
  const double h = num_steps > 0 ? duration_s / num_steps : 0.0;
  SimState state = initial;
  state.rotor_speed_radps.resize(0);
  for (int k = 0; k < num_steps; ++k) state = dynamics.Step(k * h, state, h, no_rotors);
  return state;
}

Eigen::Vector3d LinearMomentumWorld(double mass_kg, const BodyParameters& body, const SimState& state) {
  // P = sum m_i (v + w x rho_i) = m v + R (w x ms)
  const Eigen::Matrix3d r_wb = state.attitude_wb.toRotationMatrix();
  return mass_kg * state.velocity_w_mps + r_wb * state.angular_velocity_b_radps.cross(body.first_moment);
}

Eigen::Vector3d AngularMomentumWorld(double mass_kg, const BodyParameters& body, const SimState& state) {
  // H_origin = p x P + R (I w + ms x v_b), I and ms at O_d.
  const Eigen::Matrix3d r_wb = state.attitude_wb.toRotationMatrix();
  const Eigen::Vector3d v_b = r_wb.transpose() * state.velocity_w_mps;
  const Eigen::Vector3d h_od_b = body.inertia * state.angular_velocity_b_radps + body.first_moment.cross(v_b);
  return state.position_w_m.cross(LinearMomentumWorld(mass_kg, body, state)) + r_wb * h_od_b;
}

double KineticEnergy(double mass_kg, const BodyParameters& body, const SimState& state) {
  // T = m |v|^2 / 2 + v_b . (w x ms) + w^T I w / 2
  const Eigen::Vector3d v_b = state.attitude_wb.toRotationMatrix().transpose() * state.velocity_w_mps;
  const Eigen::Vector3d& w = state.angular_velocity_b_radps;
  return 0.5 * mass_kg * v_b.squaredNorm() + v_b.dot(w.cross(body.first_moment)) + 0.5 * w.dot(body.inertia * w);
}

}  // namespace rotorid

#include "sim/flight_controller.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "rotorid/core/error.h"
#include "rotorid/model/rotation.h"

namespace rotorid::internal {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// Lower rotor speed bound of the mixer, relative to the controller's hover speed.
constexpr double kMinSpeedRatio = 0.3;
// Most tilt the horizontal position loop may add to the pilot's roll and pitch.
constexpr double kMaxPositionCorrectionRad = 0.2;

Eigen::Vector3d Vee(const Eigen::Matrix3d& skew) { return {skew(2, 1), skew(0, 2), skew(1, 0)}; }

// Largest a in [0, 1] such that low <= base + a * delta <= high element-wise (0 when base is
// already outside, since nothing of delta can then be added safely).
double LargestFeasibleFraction(const Eigen::VectorXd& base, const Eigen::VectorXd& delta, double low, double high) {
  double fraction = 1.0;
  for (Eigen::Index i = 0; i < base.size(); ++i) {
    if (delta[i] > 0.0)
      fraction = std::min(fraction, (high - base[i]) / delta[i]);
    else if (delta[i] < 0.0)
      fraction = std::min(fraction, (low - base[i]) / delta[i]);
  }
  return std::clamp(fraction, 0.0, 1.0);
}

// Smooth 0 -> 1 fade-in (raised cosine) and its first two derivatives.
void Envelope(double t_s, double start_s, double ramp_s, double* e, double* de, double* dde) {
  *e = *de = *dde = 0.0;
  if (t_s < start_s) return;
  if (ramp_s <= 0.0 || t_s >= start_s + ramp_s) {
    *e = 1.0;
    return;
  }
  const double w = kTwoPi / (2.0 * ramp_s);
  const double phase = w * (t_s - start_s);
  *e = 0.5 * (1.0 - std::cos(phase));
  *de = 0.5 * w * std::sin(phase);
  *dde = 0.5 * w * w * std::cos(phase);
}

}  // namespace

SinusoidSum::SinusoidSum(RandomStream* random, int num_components, double low_hz, double high_hz, int shaped_derivative,
                         double exponent, double rms) {
  double sum_sq = 0.0;
  std::vector<double> derivative_amplitude;
  for (int i = 0; i < num_components; ++i) {
    const double fraction = (i + random->Uniform()) / num_components;
    const double f_hz = low_hz * std::pow(high_hz / low_hz, fraction);
    omega_radps_.push_back(kTwoPi * f_hz);
    phase_rad_.push_back(kTwoPi * random->Uniform());
    derivative_amplitude.push_back(std::pow(f_hz, exponent));
    sum_sq += 0.5 * derivative_amplitude.back() * derivative_amplitude.back();
  }
  const double scale = sum_sq > 0.0 ? rms / std::sqrt(sum_sq) : 0.0;
  for (int i = 0; i < num_components; ++i)
    amplitude_.push_back(scale * derivative_amplitude[i] / std::pow(omega_radps_[i], shaped_derivative));
}

void SinusoidSum::Evaluate(double t_s, double* value, double* rate, double* acceleration) const {
  *value = *rate = *acceleration = 0.0;
  for (size_t i = 0; i < amplitude_.size(); ++i) {
    const double w = omega_radps_[i];
    const double s = std::sin(w * t_s + phase_rad_[i]), c = std::cos(w * t_s + phase_rad_[i]);
    *value += amplitude_[i] * s;
    *rate += amplitude_[i] * w * c;
    *acceleration -= amplitude_[i] * w * w * s;
  }
}

Pilot::Pilot(const PilotOptions& options, RandomStream* random) : options_(options) {
  // Near the ground the rotors must stay clear of it: small attitude references, no random climbs.
  // On the circle, half the attitude references, so that the tilts they add (and the weak
  // position loop) leave the vehicle near its circle.
  const bool near_ground = options.profile == FlightProfile::kTakeoffLanding;
  const double attitude_scale = near_ground ? 0.3 : options.profile == FlightProfile::kCircle ? 0.5 : 1.0;
  const double vertical_scale = near_ground ? 0.0 : 1.0;
  // Attitude angles: energy spread over 0.15-2.5 Hz, slightly favouring low frequencies as a pilot
  // does; the high end still gives angular accelerations of several rad/s^2.
  roll_ = SinusoidSum(random, 12, 0.15, 2.5, 0, -0.5, attitude_scale * options.excitation * options.roll_rms_rad);
  pitch_ = SinusoidSum(random, 12, 0.15, 2.5, 0, -0.5, attitude_scale * options.excitation * options.pitch_rms_rad);
  // Yaw shaped on its rate, vertical motion on its acceleration (so the altitude stays small).
  yaw_ = SinusoidSum(random, 10, 0.05, 1.0, 1, 0.0, attitude_scale * options.excitation * options.yaw_rate_rms_radps);
  altitude_ =
      SinusoidSum(random, 12, 0.15, 2.5, 2, 0.5, vertical_scale * options.excitation * options.vertical_acc_rms_mps2);
}

Pilot::Signal Pilot::ProfileChannel(int channel, double t_s) const {
  const double t = t_s - options_.start_s;  // the profile starts with the fade-in
  Signal s;
  if (t <= 0.0) return s;
  switch (options_.profile) {
    case FlightProfile::kPaper:
      break;
    case FlightProfile::kYawSpin: {
      if (channel != kYaw) break;
      // Yaw rate S sin(w t): yaw S / w (1 - cos(w t)).
      const double w = kTwoPi / options_.spin_period_s, a = options_.spin_rate_radps;
      s = {a / w * (1.0 - std::cos(w * t)), a * std::sin(w * t), a * w * std::cos(w * t)};
      break;
    }
    case FlightProfile::kCircle: {
      if (channel != kNorth && channel != kEast) break;
      // Centre (0, R): starts at the origin heading along +x. Its angular speed, not its size, fades
      // in (raised cosine over twice the references' ramp): the angle is w times the envelope's integral.
      const double r = options_.circle_radius_m, w = options_.circle_speed_mps / r;
      const double ramp = 2.0 * options_.ramp_s;
      double e, de, dde;
      Envelope(t, 0.0, ramp, &e, &de, &dde);
      const double k = kTwoPi / (2.0 * ramp);
      const double angle = w * (t < ramp ? 0.5 * (t - std::sin(k * t) / k) : t - 0.5 * ramp);
      const double rate = w * e, acceleration = w * de;
      const double c = std::cos(angle), sn = std::sin(angle);
      s = channel == kNorth ? Signal{r * sn, r * rate * c, r * (acceleration * c - rate * rate * sn)}
                            : Signal{r * (1.0 - c), r * rate * sn, r * (acceleration * sn + rate * rate * c)};
      break;
    }
    case FlightProfile::kTakeoffLanding: {
      if (channel != kAltitude) break;
      // 12 s cycles: 3 s low hover, 3 s climb, 3 s high hover, 3 s descent (raised cosines).
      constexpr double kPhaseS = 3.0;
      const double climb = options_.high_altitude_m - options_.hover_altitude_m;
      const double tau = std::fmod(t, 4.0 * kPhaseS);
      const double w = kTwoPi / (2.0 * kPhaseS);
      if (tau < kPhaseS) break;
      if (tau >= 2.0 * kPhaseS && tau < 3.0 * kPhaseS) {
        s.value = climb;
        break;
      }
      // Climbing: (1 - cos) / 2 from 0 to 1; descending: its mirror.
      const double sign = tau < 2.0 * kPhaseS ? 1.0 : -1.0;
      const double phase = w * (tau - (sign > 0.0 ? kPhaseS : 3.0 * kPhaseS));
      s = {climb * (sign > 0.0 ? 0.5 * (1.0 - std::cos(phase)) : 0.5 * (1.0 + std::cos(phase))),
           sign * climb * 0.5 * w * std::sin(phase), sign * climb * 0.5 * w * w * std::cos(phase)};
      break;
    }
  }
  return s;
}

PilotReference Pilot::At(double t_s) const {
  double e, de, dde;
  Envelope(t_s, options_.start_s, options_.ramp_s, &e, &de, &dde);
  PilotReference reference;
  const SinusoidSum* channels[4] = {&roll_, &pitch_, &yaw_, &altitude_};
  double x[kNumChannels], dx[kNumChannels], ddx[kNumChannels];
  for (int c = 0; c < kNumChannels; ++c) {
    double v = 0.0, dv = 0.0, ddv = 0.0;
    if (c < 4) channels[c]->Evaluate(t_s, &v, &dv, &ddv);
    // (e v)' and (e v)'' with the fade-in envelope e.
    x[c] = e * v;
    dx[c] = de * v + e * dv;
    ddx[c] = dde * v + 2.0 * de * dv + e * ddv;
    if (options_.profile == FlightProfile::kPaper) continue;
    const Signal p = ProfileChannel(c, t_s);
    if (options_.profile == FlightProfile::kCircle) {  // faded in by its own speed
      x[c] += p.value;
      dx[c] += p.rate;
      ddx[c] += p.acceleration;
      continue;
    }
    x[c] += e * p.value;
    dx[c] += de * p.value + e * p.rate;
    ddx[c] += dde * p.value + 2.0 * de * p.rate + e * p.acceleration;
  }
  reference.bryant_rad << x[kRoll], x[kPitch], x[kYaw];
  reference.bryant_rate << dx[kRoll], dx[kPitch], dx[kYaw];
  reference.bryant_acceleration << ddx[kRoll], ddx[kPitch], ddx[kYaw];
  reference.altitude_m = options_.hover_altitude_m + x[kAltitude];
  reference.climb_rate_mps = dx[kAltitude];
  reference.vertical_acceleration_mps2 = ddx[kAltitude];
  reference.position_w_m << x[kNorth], x[kEast];
  reference.velocity_w_mps << dx[kNorth], dx[kEast];
  reference.acceleration_w_mps2 << ddx[kNorth], ddx[kEast];
  return reference;
}

FlightController::FlightController(const Vehicle& vehicle, const ControllerModel& model, double gravity_mps2,
                                   double loop_latency_s, double motor_time_constant_s, double max_speed_radps,
                                   double horizontal_omega_radps)
    : model_(model), gravity_mps2_(gravity_mps2), loop_latency_s_(loop_latency_s) {
  const int n = vehicle.num_rotors();
  allocation_.resize(4, n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = vehicle.rotors[i].position_m;
    allocation_.col(i) << model.kt, model.kt * p.y(), -model.kt * p.x(), -vehicle.rotors[i].spin * model.kd;
  }
  // Rank check on rows scaled to unit norm (thrust and yaw rows differ by orders of magnitude).
  Eigen::Matrix<double, 4, Eigen::Dynamic> scaled = allocation_;
  for (int r = 0; r < 4; ++r) scaled.row(r) /= std::max(scaled.row(r).norm(), 1e-300);
  const Eigen::JacobiSVD<Eigen::MatrixXd> scaled_svd(scaled);
  if (n < 4 || scaled_svd.singularValues()[3] < 1e-6 * scaled_svd.singularValues()[0])
    throw Error("vehicle '" + vehicle.name +
                "': its rotor layout cannot produce independent thrust, roll, pitch and yaw torques, so the "
                "simulated controller cannot fly it (needs >= 4 rotors, not all on one line, both spins)");
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(allocation_, Eigen::ComputeThinU | Eigen::ComputeThinV);
  allocation_pinv_ = svd.matrixV() * svd.singularValues().cwiseInverse().asDiagonal() * svd.matrixU().transpose();

  hover_speed_radps_ = std::sqrt(model.mass_kg * gravity_mps2 / (n * model.kt));
  min_speed_sq_ = std::pow(kMinSpeedRatio * hover_speed_radps_, 2);
  const double max_speed = kMaxSpeedRatio * hover_speed_radps_;
  max_speed_sq_ = std::pow(max_speed_radps > 0.0 ? std::min(max_speed, max_speed_radps) : max_speed, 2);

  // The predictor treats the motor lag as part of the delay, which is only accurate for short
  // lags; slower motors get a softer attitude loop. Yaw is slower: the drag torque gives a quad
  // little yaw authority, and a stiff yaw loop would saturate the rotors.
  const double attitude_omega = std::clamp(0.5 / std::max(motor_time_constant_s, 1e-3), 6.25, 10.0);
  const Eigen::Vector3d omega(attitude_omega, attitude_omega, 0.4 * attitude_omega);
  attitude_kp_ = omega.cwiseAbs2();
  attitude_kd_ = 2.0 * 0.8 * omega;
  attitude_ki_ = 0.1 * omega.cwiseAbs2().cwiseProduct(omega);
  const double altitude_omega = 3.0;
  altitude_kp_ = altitude_omega * altitude_omega;
  altitude_kd_ = 2.0 * 0.9 * altitude_omega;
  altitude_ki_ = 0.1 * altitude_omega * altitude_omega * altitude_omega;
  // Weak by default: keeps the vehicle near the origin without fighting the pilot's attitude references.
  horizontal_kp_ = horizontal_omega_radps * horizontal_omega_radps;
  horizontal_kd_ = 2.0 * horizontal_omega_radps;
}

Eigen::VectorXd FlightController::Mix(double thrust_n, const Eigen::Vector3d& torque_nm) const {
  // Priorities as in common autopilot mixers: thrust within bounds, then as much roll/pitch torque
  // as fits, then as much yaw torque as fits; whatever still violates the bounds is clamped.
  const Eigen::VectorXd thrust_part = allocation_pinv_.col(0) * thrust_n;
  const Eigen::VectorXd roll_pitch_part =
      allocation_pinv_.col(1) * torque_nm.x() + allocation_pinv_.col(2) * torque_nm.y();
  const Eigen::VectorXd yaw_part = allocation_pinv_.col(3) * torque_nm.z();
  const Eigen::VectorXd base = thrust_part.cwiseMax(min_speed_sq_).cwiseMin(max_speed_sq_);
  const Eigen::VectorXd with_roll_pitch =
      base + LargestFeasibleFraction(base, roll_pitch_part, min_speed_sq_, max_speed_sq_) * roll_pitch_part;
  const Eigen::VectorXd speed_sq =
      (with_roll_pitch + LargestFeasibleFraction(with_roll_pitch, yaw_part, min_speed_sq_, max_speed_sq_) * yaw_part)
          .cwiseMax(min_speed_sq_)
          .cwiseMin(max_speed_sq_);
  return speed_sq.cwiseSqrt();
}

void FlightController::Trim(const Eigen::VectorXd& rotor_speed_radps, const PilotReference& reference) {
  const Eigen::Vector4d wrench = allocation_ * rotor_speed_radps.cwiseAbs2();
  const Eigen::Matrix3d r_wb = BryantToRotation(reference.bryant_rad);
  altitude_integral_ = (wrench[0] * r_wb(2, 2) / model_.mass_kg - gravity_mps2_) / altitude_ki_;
  attitude_integral_ = -wrench.tail<3>().cwiseQuotient(model_.inertia_diagonal).cwiseQuotient(attitude_ki_);
}

Eigen::VectorXd FlightController::Update(double t_s, double dt_s, const ControllerInput& input,
                                         const PilotReference& reference_ahead) {
  // Smith predictor: the commands issued during the last loop latency have not acted yet; add
  // their (model) effect to the measured state to get the state one latency ahead:
  //   w(t+L) = w(t) + sum a_j dt_j,   theta(t+L) = theta(t) + L w(t) + sum a_j dt_j (t - t_j).
  while (!pending_.empty() && pending_.front().t_s < t_s - loop_latency_s_) pending_.pop_front();
  Eigen::Vector3d pending_rate = Eigen::Vector3d::Zero(), pending_angle = Eigen::Vector3d::Zero();
  double pending_climb_rate = 0.0, pending_climb = 0.0;
  for (const PendingCommand& c : pending_) {
    pending_rate += c.angular_acceleration * c.dt_s;
    pending_angle += c.angular_acceleration * c.dt_s * (t_s - c.t_s);
    pending_climb_rate += c.vertical_acceleration * c.dt_s;
    pending_climb += c.vertical_acceleration * c.dt_s * (t_s - c.t_s);
  }
  const Eigen::Vector3d& gyro = input.gyro_radps;
  const Eigen::Vector3d w = gyro + pending_rate;
  const Eigen::Matrix3d r_wb =
      input.attitude_wb.toRotationMatrix() * ExpSO3<double>(Eigen::Vector3d(loop_latency_s_ * gyro + pending_angle));
  const double altitude = input.position_w_m.z() + loop_latency_s_ * input.velocity_w_mps.z() + pending_climb;
  const double climb_rate = input.velocity_w_mps.z() + pending_climb_rate;

  // Horizontal position loop: a small tilt added to the pilot's, in the heading frame, where
  // pitch accelerates along +x_heading (g * pitch) and roll along -y_heading (-g * roll).
  // The reference's own horizontal acceleration (the circle) is fed forward as a tilt, unclamped.
  const Eigen::Vector2d horizontal_acc =
      -horizontal_kp_ * (input.position_w_m.head<2>() - reference_ahead.position_w_m) -
      horizontal_kd_ * (input.velocity_w_mps.head<2>() - reference_ahead.velocity_w_mps);
  const double yaw = std::atan2(r_wb(1, 0), r_wb(0, 0));
  const double c = std::cos(yaw), s = std::sin(yaw);
  const auto to_heading = [c, s](const Eigen::Vector2d& a) {
    return Eigen::Vector2d(c * a.x() + s * a.y(), -s * a.x() + c * a.y());
  };
  const Eigen::Vector2d heading_acc = to_heading(horizontal_acc);
  const Eigen::Vector2d heading_feedforward = to_heading(reference_ahead.acceleration_w_mps2);
  Eigen::Vector3d bryant_desired = reference_ahead.bryant_rad;
  bryant_desired.x() +=
      std::clamp(-heading_acc.y() / gravity_mps2_, -kMaxPositionCorrectionRad, kMaxPositionCorrectionRad) -
      std::atan(heading_feedforward.y() / gravity_mps2_);
  bryant_desired.y() +=
      std::clamp(heading_acc.x() / gravity_mps2_, -kMaxPositionCorrectionRad, kMaxPositionCorrectionRad) +
      std::atan(heading_feedforward.x() / gravity_mps2_);

  // Attitude: PID on SO(3) (Lee et al. 2010) with the reference's angular acceleration fed forward.
  const Eigen::Matrix3d r_desired = BryantToRotation(bryant_desired);
  const Eigen::Matrix3d rate_matrix = BryantRateMatrix(reference_ahead.bryant_rad);
  const Eigen::Vector3d w_desired = rate_matrix * reference_ahead.bryant_rate;
  const Eigen::Vector3d w_dot_desired =
      rate_matrix * reference_ahead.bryant_acceleration +
      BryantRateMatrixDerivative(reference_ahead.bryant_rad, reference_ahead.bryant_rate) * reference_ahead.bryant_rate;
  const Eigen::Matrix3d r_error = r_desired.transpose() * r_wb;
  const Eigen::Vector3d attitude_error = 0.5 * Vee(r_error - r_error.transpose());
  const Eigen::Vector3d w_desired_body = r_error.transpose() * w_desired;
  const Eigen::Vector3d rate_error = w - w_desired_body;
  attitude_integral_ += attitude_error * dt_s;
  // At most 60 rad/s^2 of integral action (anti-windup).
  const Eigen::Vector3d max_integral = attitude_ki_.cwiseInverse() * 60.0;
  attitude_integral_ = attitude_integral_.cwiseMax(-max_integral).cwiseMin(max_integral);
  const Eigen::Vector3d net_angular_acc = -attitude_kp_.cwiseProduct(attitude_error) -
                                          attitude_kd_.cwiseProduct(rate_error) + r_error.transpose() * w_dot_desired -
                                          w.cross(w_desired_body);
  const Eigen::Vector3d angular_acc_command = net_angular_acc - attitude_ki_.cwiseProduct(attitude_integral_);
  const Eigen::Vector3d inertia_w = model_.inertia_diagonal.cwiseProduct(w);
  const Eigen::Vector3d torque = model_.inertia_diagonal.cwiseProduct(angular_acc_command) + w.cross(inertia_w);

  // Altitude: PID with the reference's vertical acceleration fed forward; thrust tilted by the attitude.
  const double altitude_error = reference_ahead.altitude_m - altitude;
  altitude_integral_ += altitude_error * dt_s;
  const double max_altitude_integral = 4.0 / altitude_ki_;
  altitude_integral_ = std::clamp(altitude_integral_, -max_altitude_integral, max_altitude_integral);
  const double net_vertical_acc = reference_ahead.vertical_acceleration_mps2 + altitude_kp_ * altitude_error +
                                  altitude_kd_ * (reference_ahead.climb_rate_mps - climb_rate);
  const double vertical_acc = std::max(net_vertical_acc + altitude_ki_ * altitude_integral_, -0.7 * gravity_mps2_);
  const double thrust = model_.mass_kg * (gravity_mps2_ + vertical_acc) / std::max(r_wb(2, 2), 0.5);

  pending_.push_back({t_s, dt_s, net_angular_acc, net_vertical_acc});
  return Mix(thrust, torque);
}

}  // namespace rotorid::internal

#include "predict/rollout.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <thread>

#include "core/parallel_for.h"
#include "rotorid/core/error.h"
#include "rotorid/model/physical_consistency.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/model/rotation.h"
#include "rotorid/refine/effect_model.h"
#include "rotorid/signal/differentiate.h"
#include "rotorid/signal/resample.h"
#include "rotorid/sim/dynamics.h"

namespace rotorid::internal {
namespace {

constexpr int kPosition = static_cast<int>(PredictionGroup::kPosition);
constexpr int kVelocity = static_cast<int>(PredictionGroup::kVelocity);
constexpr int kRotation = static_cast<int>(PredictionGroup::kRotation);
constexpr int kAngularVelocity = static_cast<int>(PredictionGroup::kAngularVelocity);

// The geodesic angle of q_a^-1 q_b (rad, in [0, pi]): INTERFACE.md 6's rotation error.
double RotationAngle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const Eigen::Quaterniond d = a.conjugate() * b;
  return 2.0 * std::atan2(d.vec().norm(), std::abs(d.w()));
}

Eigen::Quaterniond RotationVectorToQuaternion(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, r / angle));
}

// The gyro on the grid, corrected from the log to the body by the report's IMU effects (bias,
// misalignment), as the identification corrects it.
Eigen::MatrixX3d CorrectedGyro(const FlightLog& log, const Effects& effects, const Eigen::VectorXd& grid) {
  Eigen::MatrixX3d gyro = InterpolateLinear(log.t_s, log.gyro_radps, grid);
  const EffectChain chain = ActingEffects(effects, EffectStage::kImuSensor);
  if (chain.kinds.empty()) return gyro;
  const std::vector<const double*> parameters = chain.Parameters();
  const Eigen::MatrixX3d acc = InterpolateLinear(log.t_s, log.acc_mps2, grid);
  for (Eigen::Index k = 0; k < gyro.rows(); ++k) {
    ImuSample<double> sample{gyro.row(k).transpose(), Eigen::Vector3d::Zero(), acc.row(k).transpose()};
    CorrectImu(chain.kinds, parameters, &sample);
    gyro.row(k) = sample.angular_velocity.transpose();
  }
  return gyro;
}

// Position, velocity and attitude from the motion capture; the ground-contact rule on the height.
void ReadPose(const FlightLog& log, const ProcessedFlight& processed, const PredictOptions& options,
              LoggedStates* states) {
  const MocapTrack& mocap = *log.mocap;
  states->has_pose = true;
  states->position_w_m = InterpolateLinear(log.t_s, mocap.position_w_m, states->t_s);
  if (mocap.velocity_w_mps) {
    states->velocity_w_mps = InterpolateLinear(log.t_s, *mocap.velocity_w_mps, states->t_s);
    states->description = "position, attitude from motion capture, velocity from the log's velocity columns";
  } else {
    // The position low-passed as the identification does before differentiating it, at the log's rate.
    const Eigen::MatrixXd position = InterpolateLinear(log.t_s, mocap.position_w_m, processed.t_s);
    states->velocity_w_mps = InterpolateLinear(
        processed.t_s, FourthOrderCentralDifference(FiltFiltColumns(processed.filter, position), processed.dt_s),
        states->t_s);
    states->description = "position, attitude from motion capture, velocity its low-passed, differentiated position";
  }
  Eigen::MatrixXd angles = mocap.bryant_rad;
  for (int a = 0; a < 3; ++a) angles.col(a) = UnwrapAngle(angles.col(a));
  angles = InterpolateLinear(log.t_s, angles, states->t_s);
  states->attitude_wb.resize(states->t_s.size());
  for (int k = 0; k < states->size(); ++k)
    states->attitude_wb[k] = Eigen::Quaterniond(BryantToRotation(angles.row(k).transpose()));
  const auto ground = log.metadata.find("ground_z");
  const double ground_z =
      ground != log.metadata.end() ? std::stod(ground->second) : mocap.position_w_m.col(2).minCoeff();
  // A log may start and end in the air (its lowest height is then a hover's): near that height the
  // rotors' thrust decides.
  for (int k = 0; k < states->size(); ++k)
    if (states->position_w_m(k, 2) - ground_z >= options.ground_clearance_m) states->airborne[k] = 1;
}

// Without a pose: the attitude is the integrated gyro (the rotation error of a window needs only the
// relative rotation, and the rotational dynamics do not depend on the attitude).
void IntegrateGyro(LoggedStates* states) {
  states->position_w_m = Eigen::MatrixX3d::Zero(states->size(), 3);
  states->velocity_w_mps = Eigen::MatrixX3d::Zero(states->size(), 3);
  states->attitude_wb.assign(states->size(), Eigen::Quaterniond::Identity());
  for (int k = 1; k < states->size(); ++k) {
    const Eigen::Vector3d mean_rate =
        0.5 * (states->angular_velocity_b_radps.row(k - 1) + states->angular_velocity_b_radps.row(k)).transpose();
    states->attitude_wb[k] =
        (states->attitude_wb[k - 1] * RotationVectorToQuaternion(mean_rate * states->dt_s)).normalized();
  }
  states->description = "no pose in the log: attitude integrated from the gyro (rotation and angular velocity only)";
}

}  // namespace

LoggedStates ReadLoggedStates(const FlightLog& log, const Vehicle& vehicle, const FlownModel& model,
                              const ObservationOptions& observation, const PredictOptions& options) {
  // The rotor signal through the report's rotor-signal effects, at the log's own rate (a motor lag is
  // a filter of that series), as the identification built its rows.
  ObservationOptions whole = observation;
  whole.edge_trim_s = 0.0;
  const ProcessedFlight processed = ProcessFlight(log, vehicle, 1.0, whole);
  LoggedStates states;
  states.dt_s = options.dt_s;
  states.gravity_mps2 = log.gravity_mps2;
  states.t_s = UniformTimeBase(processed.t_s[0], processed.t_s[processed.t_s.size() - 1], 1.0 / options.dt_s);
  states.rotor_speed_radps =
      InterpolateLinear(processed.t_s, RotorSignalWithEffects(processed, model.effects), states.t_s);
  states.angular_velocity_b_radps = CorrectedGyro(log, model.effects, states.t_s);
  // Airborne when the rotors carry the given share of the weight; with a pose, also when well above
  // the ground.
  const double weight_n = vehicle.mass_kg * states.gravity_mps2;
  states.airborne.resize(states.t_s.size());
  for (int k = 0; k < states.size(); ++k)
    states.airborne[k] = model.parameters.rotor.kt * states.rotor_speed_radps.row(k).squaredNorm() >=
                         options.airborne_thrust_share * weight_n;
  if (log.mocap)
    ReadPose(log, processed, options, &states);
  else
    IntegrateGyro(&states);
  if (options.scope == PredictionScope::kWhole) std::fill(states.airborne.begin(), states.airborne.end(), 1);
  return states;
}

ErrorSums::ErrorSums(int horizon_steps, bool with_pose) {
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    const bool verified = with_pose || (g != kPosition && g != kVelocity);
    model[g].assign(verified ? horizon_steps : 0, 0.0);
    naive[g].assign(verified ? horizon_steps : 0, 0.0);
  }
}

void ErrorSums::Add(const ErrorSums& other) {
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    if (other.model[g].empty()) continue;
    if (model[g].empty()) {
      model[g].assign(other.model[g].size(), 0.0);
      naive[g].assign(other.naive[g].size(), 0.0);
    }
    for (size_t h = 0; h < model[g].size(); ++h) {
      model[g][h] += other.model[g][h];
      naive[g][h] += other.naive[g][h];
    }
    windows[g] += other.windows[g];
  }
  torque.Add(other.torque);
}

PredictionCurves ErrorSums::Mean() const {
  PredictionCurves curves;
  curves.windows = windows[kRotation];  // every window scores the rotation
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    if (windows[g] == 0) continue;
    for (double sum : model[g]) curves.mae[g].push_back(sum / static_cast<double>(windows[g]));
    for (double sum : naive[g]) curves.naive_mae[g].push_back(sum / static_cast<double>(windows[g]));
  }
  return curves;
}

namespace {

// The logged state at grid sample k.
SimState LoggedState(const LoggedStates& states, int k) {
  SimState state;
  state.position_w_m = states.position_w_m.row(k).transpose();
  state.velocity_w_mps = states.velocity_w_mps.row(k).transpose();
  state.attitude_wb = states.attitude_wb[k];
  state.angular_velocity_b_radps = states.angular_velocity_b_radps.row(k).transpose();
  return state;
}

}  // namespace

Eigen::Vector3d TorqueOfAngularAcceleration(const VehicleParameters& parameters, const Eigen::Vector3d& b) {
  // [m 1, -[ms x]; [ms x], I] [ds; b] = [0; tau]: ds = [ms x] b / m, tau = (I + [ms x]^2 / m) b.
  const Eigen::Matrix3d ms = Skew<double>(parameters.body.first_moment);
  return (parameters.body.inertia + ms * ms / parameters.mass_kg) * b;
}

namespace {

// One rollout of N steps from grid sample `start`, its errors and the naive predictor's added.
void AddWindow(const LoggedStates& states, const MultirotorDynamics& dynamics,
               const MultirotorDynamics::RotorCommand& command, int start, int horizon, ErrorSums* sums) {
  SimState state = LoggedState(states, start);
  for (int h = 1; h <= horizon; ++h) {
    const int k = start + h;
    state = dynamics.Step(states.t_s[k - 1], state, states.dt_s, command);
    const Eigen::Vector3d w_true = states.angular_velocity_b_radps.row(k).transpose();
    sums->model[kRotation][h - 1] += RotationAngle(states.attitude_wb[k], state.attitude_wb);
    sums->naive[kRotation][h - 1] += RotationAngle(states.attitude_wb[k], states.attitude_wb[start]);
    sums->model[kAngularVelocity][h - 1] += (state.angular_velocity_b_radps - w_true).norm();
    sums->naive[kAngularVelocity][h - 1] += (states.angular_velocity_b_radps.row(start).transpose() - w_true).norm();
    if (!states.has_pose) continue;
    sums->model[kPosition][h - 1] += (state.position_w_m - states.position_w_m.row(k).transpose()).norm();
    sums->naive[kPosition][h - 1] += (states.position_w_m.row(start) - states.position_w_m.row(k)).norm();
    sums->model[kVelocity][h - 1] += (state.velocity_w_mps - states.velocity_w_mps.row(k).transpose()).norm();
    sums->naive[kVelocity][h - 1] += (states.velocity_w_mps.row(start) - states.velocity_w_mps.row(k)).norm();
  }
  for (int g = 0; g < kNumPredictionGroups; ++g)
    if (!sums->model[g].empty()) sums->windows[g] += 1;
}

// The torque bias observer (PredictOptions::torque_bias_window_s). What the model leaves out of the
// angular velocity up to grid sample k: r_k = w_k - integral of the model's w' at the logged states
// (trapezoid). Over a window's past, r grows with the slope of the missing angular acceleration.
class TorqueBiasObserver {
 public:
  TorqueBiasObserver(const LoggedStates& states, const Eigen::MatrixX3d& model_acceleration,
                     const VehicleParameters& parameters)
      : residual_(states.size(), 3), parameters_(parameters) {
    Eigen::Vector3d integral = Eigen::Vector3d::Zero();
    for (int k = 0; k < states.size(); ++k) {
      if (k > 0) integral += 0.5 * (model_acceleration.row(k - 1) + model_acceleration.row(k)).transpose() * states.dt_s;
      residual_.row(k) = states.angular_velocity_b_radps.row(k) - integral.transpose();
    }
  }

  // The body-frame torque about O_d whose angular acceleration is the least-squares slope of r over
  // samples first..last.
  Eigen::Vector3d Torque(int first, int last, double dt_s) const {
    const int n = last - first + 1;
    const double mean_j = 0.5 * (first + last);
    Eigen::Vector3d mean_r = residual_.middleRows(first, n).colwise().mean().transpose();
    Eigen::Vector3d cross = Eigen::Vector3d::Zero();
    double spread = 0.0;
    for (int j = first; j <= last; ++j) {
      cross += (j - mean_j) * (residual_.row(j).transpose() - mean_r);
      spread += (j - mean_j) * (j - mean_j);
    }
    return TorqueOfAngularAcceleration(parameters_, cross / (spread * dt_s));
  }

 private:
  Eigen::MatrixX3d residual_;
  VehicleParameters parameters_;
};

}  // namespace

Eigen::MatrixX3d ModelAngularAccelerations(const LoggedStates& states, const MultirotorDynamics& dynamics,
                                           const MultirotorDynamics::RotorCommand& command) {
  Eigen::MatrixX3d acceleration(states.size(), 3);
  for (int k = 0; k < states.size(); ++k) {
    const SimState state = LoggedState(states, k);
    const double t = states.t_s[k];
    acceleration.row(k) = dynamics
                              .Accelerations(t, state, dynamics.ActingRotorSpeeds(t, state, command),
                                             dynamics.ActingRotorRates(t, state, command))
                              .angular_acceleration_b_radps2.transpose();
  }
  return acceleration;
}

ErrorSums ScoreFlight(const LoggedStates& states, const Vehicle& vehicle, const FlownModel& model,
                      const PredictOptions& options) {
  const int horizon = options.horizon_steps;
  // The rotor-wrench effects act in the physics; the rotor-signal ones (a motor lag among them) are
  // already in the acting rotor speeds, so the dynamics carry no lag state of their own.
  const MultirotorDynamics dynamics = [&] {
    try {
      return MultirotorDynamics(vehicle, model.parameters, states.gravity_mps2, /*motor_time_constant_s=*/0.0,
                                ActingEffects(model.effects, EffectStage::kRotorWrench));
    } catch (const Error& e) {
      throw Error(model.source + ": configuration '" + vehicle.name + "' cannot be flown: " +
                  CheckPhysicalConsistency(model.parameters.mass_kg, model.parameters.body).problem + " (" + e.what() +
                  ")");
    }
  }();
  // Start instants whose whole window k..k+N, and the observer's past k-L..k, is in the scope (no
  // grounded sample in it).
  const int past = static_cast<int>(std::lround(options.torque_bias_window_s / states.dt_s));
  std::vector<int> grounded_before(states.size() + 1, 0);
  for (int k = 0; k < states.size(); ++k) grounded_before[k + 1] = grounded_before[k] + (states.airborne[k] ? 0 : 1);
  std::vector<int> starts;
  for (int k = past; k + horizon < states.size(); k += options.stride)
    if (grounded_before[k + horizon + 1] == grounded_before[k - past]) starts.push_back(k);
  const double t0 = states.t_s.size() > 0 ? states.t_s[0] : 0.0;
  const Eigen::MatrixXd& rotor = states.rotor_speed_radps;
  const int last = states.size() - 1;
  // The acting rotor speeds between grid samples: linear, as INTERFACE.md 1 reads a log.
  const MultirotorDynamics::RotorCommand command = [&rotor, t0, dt = states.dt_s, last](double t_s) {
    const double u = std::clamp((t_s - t0) / dt, 0.0, static_cast<double>(last));
    const int i = std::min(static_cast<int>(u), std::max(last - 1, 0));
    const double f = u - i;
    return Eigen::VectorXd(((1.0 - f) * rotor.row(i) + f * rotor.row(std::min(i + 1, last))).transpose());
  };
  const int threads =
      options.threads > 0 ? options.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int chunks = std::min<int>(static_cast<int>(starts.size()), 8 * threads);
  std::vector<ErrorSums> partial(std::max(chunks, 0), ErrorSums(horizon, states.has_pose));
  const Eigen::MatrixX3d model_acceleration = ModelAngularAccelerations(states, dynamics, command);
  const std::optional<TorqueBiasObserver> observer =
      past > 0 ? std::optional<TorqueBiasObserver>(std::in_place, states, model_acceleration, model.parameters)
               : std::nullopt;
  ParallelFor(chunks, threads, [&](int c) {
    for (size_t s = static_cast<size_t>(c); s < starts.size(); s += static_cast<size_t>(chunks)) {
      if (!observer) {
        AddWindow(states, dynamics, command, starts[s], horizon, &partial[c]);
        continue;
      }
      ExternalForce bias;
      bias.body_torque_nm = observer->Torque(starts[s] - past, starts[s], states.dt_s);
      const MultirotorDynamics biased(vehicle, model.parameters, states.gravity_mps2, 0.0,
                                      ActingEffects(model.effects, EffectStage::kRotorWrench), bias);
      AddWindow(states, biased, command, starts[s], horizon, &partial[c]);
    }
  });
  ErrorSums total(horizon, states.has_pose);
  for (const ErrorSums& p : partial) total.Add(p);
  total.torque = CompareTorque(states, model.parameters, model_acceleration);
  return total;
}

}  // namespace rotorid::internal

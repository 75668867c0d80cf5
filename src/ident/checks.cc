#include "rotorid/ident/checks.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"
#include "rotorid/ident/body_consistency.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/model/parameters.h"
#include "rotorid/model/rotation.h"

namespace rotorid {

const char* CheckStatusName(CheckStatus status) {
  switch (status) {
    case CheckStatus::kOk:
      return "ok";
    case CheckStatus::kWarning:
      return "warning";
    case CheckStatus::kError:
      return "error";
  }
  return "error";
}

bool AnyCheckFailed(const std::vector<Check>& checks) {
  return std::any_of(checks.begin(), checks.end(), [](const Check& c) { return c.status == CheckStatus::kError; });
}

std::string FailedCheckMessages(const std::vector<Check>& checks) {
  std::string out;
  for (const Check& c : checks)
    if (c.status == CheckStatus::kError) out += (out.empty() ? "" : "; ") + c.message;
  return out;
}

namespace {

constexpr double kAirDensityKgpm3 = 1.225;

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

double Correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd ac = a.array() - a.mean(), bc = b.array() - b.mean();
  const double denominator = ac.norm() * bc.norm();
  return denominator > 0.0 ? ac.dot(bc) / denominator : 0.0;
}

std::string VehicleFile(const Vehicle& vehicle) {
  return vehicle.source.empty() ? "the vehicle file of '" + vehicle.name + "'" : vehicle.source;
}

// The smallest distance between two rotors in the rotor plane, coaxial pairs left out (0 when every
// rotor shares one axis): no propeller is wider.
double RotorSpacing(const Vehicle& vehicle) {
  double spacing = 0.0;
  const double coaxial_m = 0.05 * vehicle.MeanArm();
  for (size_t i = 0; i < vehicle.rotors.size(); ++i)
    for (size_t j = i + 1; j < vehicle.rotors.size(); ++j) {
      const double d = (vehicle.rotors[i].position_m - vehicle.rotors[j].position_m).head<2>().norm();
      if (d > coaxial_m && (spacing == 0.0 || d < spacing)) spacing = d;
    }
  return spacing;
}

// What one flight shows, at its IDIM row samples.
struct FlightMetrics {
  double gravity = kStandardGravity;
  double acc_median = 0.0;            // median |specific force|
  double gyro_median = 0.0;           // median |angular velocity|
  double angular_velocity_rms = 0.0;  // of |w|
  double thrust_mean = 0.0;           // of sum Omega_i^2
  double thrust_variation_pct = 0.0;
  double thrust_force_correlation = 0.0;  // of sum Omega_i^2 with s_z
  double arm_m = 0.0;                     // mean rotor distance from the z axis
  double spacing_m = 0.0;                 // smallest distance between two rotors off each other's axis
  bool rotor_is_speed = true;             // a speed (measured, or a command through the vehicle's map)
  bool rotor_is_measured_speed = true;
  // Least-squares angular acceleration per unit Omega_i^2 variation (3 x rotors), with the rotor
  // signal shifted by rotor_lag_s.
  Eigen::MatrixXd moment_pattern;
  double rotor_lag_s = 0.0;
  // The rotation about z (deg) that best turns the roll/pitch moments the rotor positions predict
  // (sum_i (y_i, -x_i) Omega_i^2, up to kt / I) into the measured angular acceleration (MeasureMomentYaw).
  double moment_yaw_deg = 0.0;
  double moment_yaw_correlation = 0.0;  // of the turned moments with the angular acceleration
  // Per rotor, mean and standard deviation of Omega_i^2 over the rows.
  Eigen::VectorXd rotor_square_mean, rotor_square_std;
};

// The rotor-moment pattern: centred regression of the angular acceleration on each rotor's
// Omega^2 taken `lag` samples earlier (the intercept takes gyroscopic and first-moment terms that do
// not vary with a single rotor; a tiny ridge keeps it defined when a rotor never varies). Returns the
// share of the angular acceleration's variance it explains.
double FitMomentPattern(const ProcessedFlight& f, int lag, Eigen::MatrixXd* pattern) {
  const int rotors = f.vehicle.num_rotors();
  std::vector<int> rows;
  for (int i : f.row_samples)
    if (i >= lag) rows.push_back(i);
  Eigen::MatrixXd x(rows.size(), rotors), y(rows.size(), 3);
  for (size_t r = 0; r < rows.size(); ++r) {
    x.row(r) = f.rotor.row(rows[r] - lag).array().square().matrix();
    y.row(r) = f.angular_acceleration.row(rows[r]);
  }
  x.rowwise() -= x.colwise().mean();
  y.rowwise() -= y.colwise().mean();
  Eigen::MatrixXd normal = x.transpose() * x;
  normal.diagonal().array() += 1e-12 * std::max(normal.diagonal().maxCoeff(), 1e-300);
  *pattern = normal.ldlt().solve(x.transpose() * y).transpose();
  const double total = y.squaredNorm();
  return total > 0.0 ? 1.0 - (y - x * pattern->transpose()).squaredNorm() / total : 0.0;
}

// The rotation about z that best turns the roll/pitch moments the rotor positions predict into the
// measured angular acceleration (2-D Procrustes over the samples), at the time shift within 0.1 s
// that fits best: when the tilt direction circles, a delay of the rotor signal alone turns the
// moments by 2 pi f delay (PWM commands of eckart34: -28 deg unshifted, 0.3 deg shifted). With a
// velocity, what it explains linearly is left out of both first: the rotor drag's moment, against
// the velocity, which on circles runs 90 deg from the tilt the rotors command, turned the fit (jana01
// with its motion capture: -29.5 deg, -2.4 deg without it; the correlation 0.88 -> 0.63, but a fit
// of the moments and the velocity together explains 0.885 of the variance against 0.77).
void MeasureMomentYaw(const ProcessedFlight& f, FlightMetrics* m) {
  if (f.row_samples.empty() || !(f.dt_s > 0.0)) return;
  const int first = f.row_samples.front(), n = f.row_samples.back() - first + 1, rotors = f.vehicle.num_rotors();
  Eigen::VectorXd arm_y(rotors), arm_x(rotors);
  for (int i = 0; i < rotors; ++i)
    arm_y[i] = f.vehicle.rotors[i].position_m.y(), arm_x[i] = f.vehicle.rotors[i].position_m.x();
  const Eigen::MatrixXd thrusts = f.rotor.middleRows(first, n).array().square().matrix();
  Eigen::MatrixX2d moment(n, 2), acceleration = f.angular_acceleration.middleRows(first, n).leftCols(2);
  moment << thrusts * arm_y, -(thrusts * arm_x);
  moment.rowwise() -= moment.colwise().mean();
  acceleration.rowwise() -= acceleration.colwise().mean();
  const int max_shift = std::min(static_cast<int>(std::lround(0.1 / f.dt_s)), n / 4);
  Eigen::MatrixX2d velocity;
  if (f.velocity_mps) {
    velocity = f.velocity_mps->middleRows(first, n).leftCols(2);
    velocity.rowwise() -= velocity.colwise().mean();
  }
  for (int shift = -max_shift; shift <= max_shift; ++shift) {
    const int length = n - std::abs(shift);
    Eigen::MatrixX2d a = moment.middleRows(std::max(0, -shift), length);
    Eigen::MatrixX2d b = acceleration.middleRows(std::max(0, shift), length);
    if (velocity.rows() == n) {  // the moments and rates the horizontal velocity explains, left out
      const auto v = velocity.middleRows(std::max(0, shift), length);
      const Eigen::LDLT<Eigen::Matrix2d> normal((v.transpose() * v).eval());
      a -= v * normal.solve(v.transpose() * a);
      b -= v * normal.solve(v.transpose() * b);
    }
    const double dot = a.col(0).dot(b.col(0)) + a.col(1).dot(b.col(1));
    const double cross = a.col(0).dot(b.col(1)) - a.col(1).dot(b.col(0));
    const double norms = std::sqrt(a.squaredNorm() * b.squaredNorm());
    const double correlation = norms > 0.0 ? std::hypot(dot, cross) / norms : 0.0;
    if (dot > 0.0 && correlation > m->moment_yaw_correlation) {
      m->moment_yaw_correlation = correlation;
      m->moment_yaw_deg = std::atan2(cross, dot) * kRadToDeg;
    }
  }
}

// The largest step of the angular velocity between two samples against the typical step around it,
// where the step persists (the means of kPersistSamples before and after differ by at least half of
// it: a spike returns). The body's angular velocity is the integral of finite moments: it ramps, it does
// not step.
struct GyroStep {
  Eigen::Index at = -1;  // the step is between samples at - 1 and at
  double step_radps = 0.0, typical_radps = 0.0;
};
GyroStep LargestGyroStep(const FlightLog& log) {
  constexpr int kNeighbours = 10, kPersistSamples = 5;
  const Eigen::Index n = log.num_samples();
  GyroStep largest;
  if (n < 2 * kNeighbours + 2) return largest;
  const double dt = log.MedianDt();
  std::vector<double> steps(static_cast<size_t>(n));  // steps[i]: from sample i - 1 to i, per median interval
  for (Eigen::Index i = 1; i < n; ++i)
    steps[static_cast<size_t>(i)] =
        (log.gyro_radps.row(i) - log.gyro_radps.row(i - 1)).norm() * dt / std::max(log.t_s[i] - log.t_s[i - 1], dt);
  const double global = Median(std::vector<double>(steps.begin() + 1, steps.end()));
  double best_ratio = 0.0;
  for (Eigen::Index i = kNeighbours + 1; i + kNeighbours < n; ++i) {
    const double step = steps[static_cast<size_t>(i)];
    // The typical step is at least the global median: most samples need no local median.
    if (!(step > 0.0) || step <= best_ratio * global) continue;
    std::vector<double> around;
    for (Eigen::Index j = i - kNeighbours; j <= i + kNeighbours; ++j)
      if (j != i) around.push_back(steps[static_cast<size_t>(j)]);
    const double typical = std::max(Median(std::move(around)), global);
    if (!(typical > 0.0) || step / typical <= best_ratio) continue;
    const Eigen::Index before = std::max<Eigen::Index>(0, i - kPersistSamples),
                       after = std::min(n, i + kPersistSamples);
    const Eigen::Vector3d held = log.gyro_radps.middleRows(i, after - i).colwise().mean() -
                                 log.gyro_radps.middleRows(before, i - before).colwise().mean();
    if (held.norm() < 0.5 * step) continue;
    best_ratio = step / typical;
    largest = {i, step, typical};
  }
  return largest;
}

// The change of the angular velocity over kJoinWindowS centred at `centre_s` that the rotor moments (the
// measured pattern at the rotor lag, FlightMetrics) do not explain, and the median such change over the
// flight's windows. A body turns only as its moments make it: a change no moment made is a jump of the
// state. The filter spreads a jump over its response; the window holds all of it.
constexpr double kJoinWindowS = 0.3;
struct UnexplainedTurn {
  double at_radps = 0.0, typical_radps = 0.0;
};
UnexplainedTurn MeasureUnexplainedTurn(const ProcessedFlight& f, const FlightMetrics& m, double centre_s) {
  UnexplainedTurn turn;
  if (f.row_samples.empty() || !(f.dt_s > 0.0) || m.moment_pattern.rows() != 3) return turn;
  const int lag = static_cast<int>(std::lround(m.rotor_lag_s / f.dt_s));
  const int first = std::max(f.row_samples.front(), lag), last = f.row_samples.back();
  const int half = static_cast<int>(std::lround(0.5 * kJoinWindowS / f.dt_s)), n = last - first + 1;
  if (n < 4 * half + 2) return turn;
  const Eigen::MatrixXd squares = f.rotor.middleRows(first - lag, n).array().square().matrix();
  const Eigen::MatrixXd rates = f.angular_acceleration.middleRows(first, n);
  const Eigen::MatrixXd predicted =
      ((squares.rowwise() - squares.colwise().mean()) * m.moment_pattern.transpose()).rowwise() +
      rates.colwise().mean();
  Eigen::MatrixXd cumulative = Eigen::MatrixXd::Zero(n + 1, 3);  // of the unexplained angular acceleration
  for (int i = 0; i < n; ++i) cumulative.row(i + 1) = cumulative.row(i) + (rates.row(i) - predicted.row(i)) * f.dt_s;
  std::vector<double> changes;
  for (int i = 0; i + 2 * half <= n; ++i) changes.push_back((cumulative.row(i + 2 * half) - cumulative.row(i)).norm());
  turn.typical_radps = Median(changes);
  const int centre = static_cast<int>(std::lround((centre_s - f.t_s[first]) / f.dt_s));
  const int begin = std::clamp(centre - half, 0, n - 2 * half);
  turn.at_radps = (cumulative.row(begin + 2 * half) - cumulative.row(begin)).norm();
  return turn;
}

FlightMetrics Measure(const FlightData& raw, const ProcessedFlight& f, const InputCheckThresholds& t) {
  FlightMetrics m;
  m.gravity = f.gravity_mps2;
  m.rotor_is_speed = !RotorSignalIsCommand(raw.log);
  m.rotor_is_measured_speed = m.rotor_is_speed && !raw.log.metadata.count("command_to_speed");
  const int rows = f.num_rows_samples();
  std::vector<double> acc(rows), gyro(rows);
  Eigen::VectorXd thrust(rows), force_z(rows);
  Eigen::MatrixXd squares(rows, f.vehicle.num_rotors());  // Omega_i^2 per row sample
  for (int r = 0; r < rows; ++r) {
    const int i = f.row_samples[r];
    acc[r] = f.specific_force.row(i).norm();
    gyro[r] = f.angular_velocity.row(i).norm();
    m.angular_velocity_rms += gyro[r] * gyro[r];
    squares.row(r) = f.rotor.row(i).array().square().matrix();
    thrust[r] = squares.row(r).sum();
    force_z[r] = f.specific_force(i, 2);
  }
  m.acc_median = Median(acc);
  m.gyro_median = Median(gyro);
  m.angular_velocity_rms = std::sqrt(m.angular_velocity_rms / std::max(rows, 1));
  m.thrust_mean = thrust.mean();
  m.rotor_square_mean = squares.colwise().mean().transpose();
  m.rotor_square_std = ((squares.rowwise() - squares.colwise().mean()).colwise().squaredNorm() / std::max(rows, 1))
                           .cwiseSqrt()
                           .transpose();
  if (m.thrust_mean > 0.0)
    m.thrust_variation_pct = 100.0 * std::sqrt((thrust.array() - m.thrust_mean).square().mean()) / m.thrust_mean;
  m.thrust_force_correlation = Correlation(thrust, force_z);
  m.arm_m = f.vehicle.MeanArm();
  m.spacing_m = RotorSpacing(f.vehicle);
  MeasureMomentYaw(f, &m);
  // The lag is chosen by how much of the angular acceleration the rotors explain, which does not
  // depend on the vehicle file, so a swapped order still shows as a swap. Steps of about 5 ms.
  const double max_lag_s = m.rotor_is_measured_speed ? t.max_speed_lag_s : t.max_command_lag_s;
  const int max_lag = f.dt_s > 0.0 ? static_cast<int>(std::floor(max_lag_s / f.dt_s)) : 0;
  const int step = std::max(1, static_cast<int>(std::lround(0.005 / std::max(f.dt_s, 1e-9))));
  double best = -1.0;
  for (int lag = 0; lag <= max_lag; lag += step) {
    Eigen::MatrixXd pattern;
    const double explained = FitMomentPattern(f, lag, &pattern);
    if (explained > best) best = explained, m.moment_pattern = pattern, m.rotor_lag_s = lag * f.dt_s;
  }
  return m;
}

// Per axis, the angular acceleration pattern the vehicle file predicts for each rotor (up to a
// positive factor): roll y_i, pitch -x_i, yaw -spin_i.
Eigen::MatrixXd PredictedPattern(const Vehicle& vehicle, const std::vector<int>& order) {
  Eigen::MatrixXd p(3, vehicle.num_rotors());
  for (int i = 0; i < vehicle.num_rotors(); ++i) {
    const Rotor& rotor = vehicle.rotors[order[i]];
    p.col(i) << rotor.position_m.y(), -rotor.position_m.x(), -rotor.spin;
  }
  return p;
}

// Correlation per axis of the measured and the predicted pattern.
Eigen::Vector3d PatternCorrelation(const Eigen::MatrixXd& measured, const Eigen::MatrixXd& predicted) {
  Eigen::Vector3d c;
  for (int a = 0; a < 3; ++a) c[a] = Correlation(measured.row(a).transpose(), predicted.row(a).transpose());
  return c;
}

Check AccelerometerCheck(const FlightMetrics& m, const std::string& source, const InputCheckThresholds& t) {
  const double ratio = m.acc_median / m.gravity;
  const std::string measured = "median |acc| " + ShortNumber(m.acc_median) + " m/s^2, median |gyro| " +
                               ShortNumber(m.gyro_median) + " rad/s, g = " + ShortNumber(m.gravity) + " m/s^2";
  if (ratio >= t.gravity_ratio_low && ratio <= t.gravity_ratio_high)
    return {"accelerometer_units", CheckStatus::kOk, source + ": " + measured};
  std::string cause;
  const double gyro_ratio = m.gyro_median / m.gravity;
  if (gyro_ratio >= t.gravity_ratio_low && gyro_ratio <= t.gravity_ratio_high)
    cause = "the gyro and accelerometer columns appear swapped: exchange gyro_x..z and acc_x..z";
  else if (std::abs(m.acc_median - 1.0) < 0.3)
    cause = "the accelerometer appears to be in g: multiply acc_x..z by " + ShortNumber(m.gravity) +
            " (a column map: unit g)";
  else if (std::abs(m.acc_median / 1000.0 - 1.0) < 0.3)
    cause = "the accelerometer appears to be in mg: multiply acc_x..z by " + ShortNumber(m.gravity / 1000.0);
  else
    cause = "the accelerometer columns are not the specific force in m/s^2 (about g in hover)";
  return {"accelerometer_units", CheckStatus::kError, source + ": " + cause + " (" + measured + ")"};
}

// A sensor at its range limit repeats one value exactly (its extreme) where the motion went further,
// more often than the values just inside it occur (a quantised log, Betaflight's integer deg/s,
// repeats its extremes a few times, like its other values): the regression then reads a smaller
// force or rate than the rotors made (sim A with the accelerometer clipped at 11 m/s^2 on 15 % of
// its samples: kt and I_xx -1.5 %, exit 0 before).
Check SaturationCheck(const FlightLog& log) {
  constexpr double kShare = 0.01;  // of the samples at one extreme, and at least kMinCount
  constexpr int kMinCount = 5;
  const Eigen::Index n = log.num_samples();
  const auto clipped = [&](const Eigen::MatrixX3d& x, const char* prefix) -> std::string {
    for (int a = 0; a < 3; ++a)
      for (const double extreme : {x.col(a).maxCoeff(), x.col(a).minCoeff()}) {
        const auto count = (x.col(a).array() == extreme).count();
        // The values within 5 % of the axis's span inside the extreme.
        const double band = 0.05 * (x.col(a).maxCoeff() - x.col(a).minCoeff());
        const auto inside = ((x.col(a).array() - extreme).abs() <= band && x.col(a).array() != extreme).count();
        if (extreme != 0.0 && count >= kMinCount && static_cast<double>(count) >= kShare * static_cast<double>(n) &&
            count > inside)
          return std::string(prefix) + "xyz"[a] + " sits at " + ShortNumber(extreme) + " on " + std::to_string(count) +
                 " of " + std::to_string(n) + " samples";
      }
    return {};
  };
  std::string found = clipped(log.acc_mps2, "acc_");
  if (found.empty()) found = clipped(log.gyro_radps, "gyro_");
  if (found.empty()) return {"saturation", CheckStatus::kOk, log.source + ": no sensor axis repeats its extreme"};
  return {"saturation", CheckStatus::kError,
          log.source + ": " + found +
              ": the sensor saturates (its range limit) and the force or rate beyond is lost; use a --window "
              "without the saturated stretches, or raise the sensor's range"};
}

Check MotionCheck(const FlightMetrics& m, const std::string& source, const InputCheckThresholds& t) {
  const std::string measured = "RMS angular velocity " + ShortNumber(m.angular_velocity_rms) +
                               " rad/s, thrust variation " + ShortNumber(m.thrust_variation_pct) + " %";
  if (m.thrust_mean <= 0.0)
    return {"motion", CheckStatus::kError, source + ": the rotors never turn (all rotor columns 0): " + measured};
  if (m.angular_velocity_rms < t.motionless_angular_velocity_radps &&
      m.thrust_variation_pct < t.motionless_thrust_variation_pct)
    return {"motion", CheckStatus::kError,
            source + ": the log is motionless (" + measured +
                "): it cannot determine inertia or kt; identify on a flight with roll, pitch, yaw and thrust changes "
                "(docs/tutorial.md)"};
  return {"motion", CheckStatus::kOk, source + ": " + measured};
}

// A rotor column that reads (nearly) nothing, or never changes, while the others fly: a dead rotor
// or an unlogged column, which the regression would absorb silently (rotor 3 of sim A all zeros: kt
// +31 %, kd and I_zz 0, every other check ok).
Check RotorSignalCheck(const FlightMetrics& m, const std::string& source) {
  constexpr double kDeadShare = 0.1, kStuckShare = 0.01;  // of the median rotor's mean, and std
  const auto median = [](const Eigen::VectorXd& v) {
    return Median(std::vector<double>(v.data(), v.data() + v.size()));
  };
  const double typical_mean = median(m.rotor_square_mean), typical_std = median(m.rotor_square_std);
  for (Eigen::Index i = 0; i < m.rotor_square_mean.size(); ++i) {
    const std::string rotor = "rotor_" + std::to_string(i + 1);
    if (m.rotor_square_mean[i] < kDeadShare * typical_mean)
      return {"rotor_signal", CheckStatus::kError,
              source + ": " + rotor + " reads " + ShortNumber(std::sqrt(m.rotor_square_mean[i])) +
                  " RMS while the median rotor reads " + ShortNumber(std::sqrt(typical_mean)) +
                  ": a dead rotor or an empty column; give its speeds, or fly a vehicle file without it"};
    if (m.rotor_square_std[i] < kStuckShare * typical_std)
      return {
          "rotor_signal", CheckStatus::kError,
          source + ": " + rotor + " never changes while the others do: a stuck or constant column; give its speeds"};
  }
  return {"rotor_signal", CheckStatus::kOk, source + ": every rotor column varies with the others"};
}

// A body cannot teleport: a step of the motion-capture position, or of the gyro's angular velocity, far
// beyond the typical one between samples is two flights joined on one time base (or a tracking glitch),
// across which the differentiated velocity, acceleration and angular acceleration are invented.
// Without motion capture (and where its position does not jump), the gyro: a persisting step far beyond
// the typical step around it that the rotor moments do not explain either. Sim A and CF flights joined
// at 5 points: steps 12.6-31.7 times the typical, unexplained 15.8-26 times the median window; single
// flights at most 2.8 and 2.4. Real flights: steps up to 4.9, except NanoBench's onboard gyro, which
// stalls and catches up (steps 9.9-16.9, but the moments explain them: at most 0.83); unexplained
// changes up to 15 where the step is small (ARPL log16).
Check GyroJumpCheck(const FlightLog& log, const ProcessedFlight& f, const FlightMetrics& m) {
  constexpr double kStepRatio = 8.0, kUnexplainedRatio = 8.0;
  const GyroStep step = LargestGyroStep(log);
  if (step.at < 0) return {"state_jump", CheckStatus::kOk, log.source + ": too few samples to judge"};
  const double step_ratio = step.step_radps / step.typical_radps;
  std::string measured = "largest persisting gyro step " + ShortNumber(step.step_radps) +
                         " rad/s at t = " + FormatValue("%.3f", log.t_s[step.at]) + " s, " + ShortNumber(step_ratio) +
                         " times the typical step around it";
  if (step_ratio < kStepRatio) return {"state_jump", CheckStatus::kOk, log.source + ": " + measured};
  const UnexplainedTurn turn = MeasureUnexplainedTurn(f, m, log.t_s[step.at]);
  const double unexplained_ratio = turn.typical_radps > 0.0 ? turn.at_radps / turn.typical_radps : 0.0;
  measured += "; the rotor moments leave " + ShortNumber(turn.at_radps) + " rad/s of it unexplained, " +
              ShortNumber(unexplained_ratio) + " times the median over " + ShortNumber(kJoinWindowS) + " s";
  if (unexplained_ratio < kUnexplainedRatio) return {"state_jump", CheckStatus::kOk, log.source + ": " + measured};
  return {"state_jump", CheckStatus::kError,
          log.source + ": the angular velocity jumps by " + ShortNumber(step.step_radps) + " rad/s between t = " +
              FormatValue("%.3f", log.t_s[step.at - 1]) + " and " + FormatValue("%.3f", log.t_s[step.at]) +
              " s, which no rotor moment made: two flights joined on one time base (or a logging glitch); give "
              "each flight its own log, or --window around the jump (" +
              measured + ")"};
}

// With motion capture, first its position: a step above kJumpM and kTypicalSteps typical steps.
Check StateJumpCheck(const FlightLog& log, const ProcessedFlight& f, const FlightMetrics& m) {
  if (!log.mocap) return GyroJumpCheck(log, f, m);
  constexpr double kJumpM = 0.1, kTypicalSteps = 50.0;
  const Eigen::MatrixX3d& p = log.mocap->position_w_m;
  if (p.rows() < 3) return {"state_jump", CheckStatus::kOk, log.source + ": too few poses"};
  std::vector<double> steps(static_cast<size_t>(p.rows() - 1));
  Eigen::Index at = 0;
  for (Eigen::Index i = 1; i < p.rows(); ++i) {
    steps[static_cast<size_t>(i - 1)] = (p.row(i) - p.row(i - 1)).norm();
    if (steps[static_cast<size_t>(i - 1)] > steps[static_cast<size_t>(at)]) at = i - 1;
  }
  const double largest = steps[static_cast<size_t>(at)], typical = Median(steps);
  const std::string measured =
      "largest position step " + ShortNumber(largest) + " m, typical " + ShortNumber(typical) + " m";
  if (largest <= kJumpM || largest <= kTypicalSteps * typical) return GyroJumpCheck(log, f, m);
  return {"state_jump", CheckStatus::kError,
          log.source + ": the position jumps by " + ShortNumber(largest) +
              " m between t = " + FormatValue("%.3f", log.t_s[at]) + " and " + FormatValue("%.3f", log.t_s[at + 1]) +
              " s: two flights joined on one time base, or a tracking glitch; give each flight its own log, or "
              "--window around the jump (" +
              measured + ")"};
}

// The motion-capture attitude against the gyro: the body rotation between poses 20 ms apart over
// their interval, against the mean gyro there. Euler angles in degrees read 57x fast; a quaternion
// in the wrong order or another Euler convention turns the rates (rotor drag then fits to 0).
constexpr double kAttitudeCheckMinRateRadps = 0.3;

Check AttitudeCheck(const FlightLog& log) {
  const std::string& source = log.source;
  const Eigen::Index n = log.num_samples();
  const double span_s = n > 1 ? log.t_s[n - 1] - log.t_s[0] : 0.0;
  const auto step =
      static_cast<Eigen::Index>(std::max(1.0, std::round(0.02 / (span_s / std::max<Eigen::Index>(n - 1, 1)))));
  double mocap_sq = 0.0, gyro_sq = 0.0, dot = 0.0;
  int intervals = 0;
  for (Eigen::Index i = 0; i + step < n; i += step, ++intervals) {
    const Eigen::Matrix3d a = BryantToRotation(log.mocap->bryant_rad.row(i).transpose());
    const Eigen::Matrix3d b = BryantToRotation(log.mocap->bryant_rad.row(i + step).transpose());
    const Eigen::AngleAxisd turn(a.transpose() * b);
    const Eigen::Vector3d rate = turn.angle() * turn.axis() / (log.t_s[i + step] - log.t_s[i]);
    const Eigen::Vector3d gyro = log.gyro_radps.middleRows(i, step + 1).colwise().mean().transpose();
    mocap_sq += rate.squaredNorm(), gyro_sq += gyro.squaredNorm(), dot += rate.dot(gyro);
  }
  if (!(mocap_sq > 0.0 && gyro_sq > 0.0)) return {"attitude", CheckStatus::kOk, source + ": no rotation to compare"};
  const double ratio = std::sqrt(mocap_sq / gyro_sq), correlation = dot / std::sqrt(mocap_sq * gyro_sq);
  const std::string measured = "the attitude turns " + ShortNumber(ratio) +
                               " times as fast as the gyro says, correlation " + ShortNumber(correlation);
  if (ratio >= 0.5 && ratio <= 2.0 && correlation >= 0.5)
    return {"attitude", CheckStatus::kOk, source + ": " + measured};
  const bool degrees = ratio > 0.5 * kRadToDeg && ratio < 2.0 * kRadToDeg;
  // A hover turns the body less than the attitude's noise over 20 ms: the ratio and correlation are
  // then noise (the Crazyflie's onboard estimate on hover_100hz, RMS 0.044 rad/s: 1.9, 0.50). Degrees stay
  // recognisable (57x); the order or convention needs rotation to judge.
  const double rms_gyro_radps = std::sqrt(gyro_sq / std::max(intervals, 1));
  if (!degrees && rms_gyro_radps < kAttitudeCheckMinRateRadps)
    return {"attitude", CheckStatus::kOk,
            source + ": too little rotation to judge the attitude's convention (RMS rate " +
                ShortNumber(rms_gyro_radps) + " rad/s; " + measured + ")"};
  std::string cause =
      "the motion-capture attitude and the gyro disagree: check the quaternion order (qw, qx, qy, qz), "
      "the Euler convention (R = Rz(yaw) Ry(pitch) Rx(roll)) and the frames";
  if (degrees)
    cause = "the attitude angles appear to be in degrees: give roll, pitch, yaw in rad (a column map: euler unit deg)";
  return {"attitude", CheckStatus::kError, source + ": " + cause + " (" + measured + ")"};
}

// Airborne, the vertical specific force follows the thrust; on the ground it stays at g.
Check AirborneCheck(const FlightMetrics& m, const std::string& source) {
  const std::string measured = "correlation of sum Omega^2 with acc_z " + ShortNumber(m.thrust_force_correlation) +
                               ", thrust variation " + ShortNumber(m.thrust_variation_pct) + " %";
  if (m.thrust_variation_pct > 3.0 && m.thrust_force_correlation < 0.2)
    return {"airborne", CheckStatus::kError,
            source + ": the vertical acceleration does not follow the thrust (" + measured +
                "): the log appears to be recorded on the ground (idle motors) or the rotor columns are not the "
                "rotor speeds; use the airborne part (--window) of the log"};
  return {"airborne", CheckStatus::kOk, source + ": " + measured};
}

// Mass, rotor positions and rotor speed units against each other: a real multirotor has a density
// m / r^3 and a thrust coefficient (kt over rho r^4 / (4 pi^2)) in known ranges.
Check ScaleCheck(const FlightMetrics& m, const FlightData& raw, const InputCheckThresholds& t, bool* plausible_kt) {
  const Vehicle& v = raw.vehicle;
  const std::string source = raw.log.source;
  const double r = m.arm_m;
  *plausible_kt = false;
  if (!(r > 0.0)) return {"vehicle_scale", CheckStatus::kWarning, VehicleFile(v) + ": every rotor sits on the z axis"};
  auto density = [&](double mass, double arm) { return mass / (arm * arm * arm); };
  auto coefficient = [&](double mass, double arm, double thrust_mean) {
    return mass * m.gravity / thrust_mean * 4.0 * M_PI * M_PI / (kAirDensityKgpm3 * std::pow(arm, 4));
  };
  // The same over the rotor spacing (positions scale with the arm).
  const double spacing_over_arm = m.spacing_m > 0.0 ? m.spacing_m / r : 0.0;
  auto spacing_coefficient = [&](double mass, double arm, double thrust_mean) {
    return coefficient(mass, arm, thrust_mean) / std::pow(spacing_over_arm, 4);
  };
  auto fits = [&](double mass, double arm, double thrust_mean) {
    const double d = density(mass, arm), c = coefficient(mass, arm, thrust_mean);
    return d >= t.density_low_kgpm3 && d <= t.density_high_kgpm3 &&
           (!m.rotor_is_speed || (c >= t.thrust_coefficient_low && c <= t.thrust_coefficient_high &&
                                  (spacing_over_arm == 0.0 ||
                                   spacing_coefficient(mass, arm, thrust_mean) <= t.spacing_thrust_coefficient_high)));
  };
  const double mass = v.mass_kg, thrust = m.thrust_mean;
  const std::string measured =
      "mass " + ShortNumber(mass) + " kg, arm " + ShortNumber(r) + " m: m/r^3 " + ShortNumber(density(mass, r)) +
      " kg/m^3" +
      (m.rotor_is_speed ? ", kt from hover " + ShortNumber(mass * m.gravity / thrust) +
                              " N s^2 = " + ShortNumber(coefficient(mass, r, thrust)) + " rho r^4 / (4 pi^2)" +
                              (spacing_over_arm > 0.0
                                   ? " = " + ShortNumber(spacing_coefficient(mass, r, thrust)) +
                                         " rho d^4 / (4 pi^2) with d " + ShortNumber(m.spacing_m) + " m between rotors"
                                   : "")
                        : "");
  if (fits(mass, r, thrust)) {
    *plausible_kt = m.rotor_is_speed;
    return {"vehicle_scale", CheckStatus::kOk, source + ": " + measured};
  }
  const double rpm_thrust = thrust * kRpmToRadps * kRpmToRadps;
  std::string cause;
  if (fits(mass / 1000.0, r, thrust))
    cause = "the mass in " + VehicleFile(v) + " appears to be in grams: give it in kg";
  else if (fits(mass, r / 1000.0, thrust))
    cause = "the rotor positions in " + VehicleFile(v) + " appear to be in mm: give them in m";
  else if (m.rotor_is_speed && fits(mass, r, rpm_thrust))
    cause = "the rotor speeds of " + source + " appear to be in rpm: give |Omega| in rad/s (multiply by " +
            ShortNumber(kRpmToRadps) + ")";
  else if (m.rotor_is_speed && fits(mass, r, thrust * 4.0 * M_PI * M_PI))
    cause = "the rotor speeds of " + source +
            " appear to be in rev/s (kt would be 39.5 times what propellers of this size give): give |Omega| in "
            "rad/s (multiply by 2 pi; a column map: unit rev/s)";
  else
    cause = "mass, rotor positions and rotor speeds do not fit a multirotor: check their units (kg, m, rad/s) in " +
            VehicleFile(v) + " and " + source;
  return {"vehicle_scale", CheckStatus::kError, cause + " (" + measured + ")"};
}

// The rotor moments against the angular acceleration, turned about z (MeasureMomentYaw): an IMU
// yawed against the body (board alignment) or an X layout flown as + correlates at cos 45 deg =
// 0.71 per axis, which the pattern check accepts. Fitted on the samples, not on the per-rotor
// pattern, whose regression is ill-conditioned when the rotors move together; differing roll and
// pitch inertia bias it only as far as roll and pitch moments correlate.
Check ImuYawCheck(const FlightMetrics& m, const FlightData& raw, const InputCheckThresholds& t) {
  const double yaw_deg = m.moment_yaw_deg;
  const std::string measured = "the rotor moments turned " + ShortNumber(yaw_deg) +
                               " deg about z from what the rotor positions of " + VehicleFile(raw.vehicle) +
                               " give, correlation " + ShortNumber(m.moment_yaw_correlation);
  if (std::abs(yaw_deg) <= t.imu_yaw_deg) return {"imu_yaw", CheckStatus::kOk, raw.log.source + ": " + measured};
  return {"imu_yaw", m.rotor_is_measured_speed ? CheckStatus::kError : CheckStatus::kWarning,
          raw.log.source + ": the IMU appears yawed against the rotors (" + measured +
              "): rotate the gyro and accelerometer into the body frame (the board's mounting), or fix the layout in " +
              VehicleFile(raw.vehicle) + " (an X vehicle given as +, or the reverse)"};
}

// The exchange of two rotors whose pattern fits the measured one best by `score` (of the per-axis
// correlations roll, pitch, yaw).
struct Transposition {
  int i = -1, j = -1;
  double score = -1.0;
};
template <typename Score>
Transposition BestTransposition(const FlightMetrics& m, const Vehicle& v, Score score) {
  std::vector<int> order(v.num_rotors());
  std::iota(order.begin(), order.end(), 0);
  Transposition best;
  for (int i = 0; i < v.num_rotors(); ++i)
    for (int j = i + 1; j < v.num_rotors(); ++j) {
      std::swap(order[i], order[j]);
      const double fit = score(PatternCorrelation(m.moment_pattern, PredictedPattern(v, order)));
      std::swap(order[i], order[j]);
      if (fit > best.score) best = {i, j, fit};
    }
  return best;
}

// Which rotor makes which moment: the measured pattern against the vehicle file's positions and
// spins; a transposition that fits is named. With a plausible kt the pattern's size gives an
// apparent roll/pitch inertia, whose ratio to m r^2 tells gyro units.
std::vector<Check> RotorChecks(const FlightMetrics& m, const FlightData& raw, bool plausible_kt,
                               const InputCheckThresholds& t) {
  const Vehicle& v = raw.vehicle;
  const std::string& source = raw.log.source;
  const int n = v.num_rotors();
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  const Eigen::MatrixXd predicted = PredictedPattern(v, order);
  const Eigen::Vector3d c = PatternCorrelation(m.moment_pattern, predicted);
  const std::string measured =
      "correlation of the rotor moments with " + VehicleFile(v) + ": roll " + ShortNumber(c[0]) + ", pitch " +
      ShortNumber(c[1]) + ", yaw " + ShortNumber(c[2]) +
      (m.rotor_lag_s > 0.0 ? ", with the rotor signal " + FormatValue("%.0f ms", m.rotor_lag_s * 1e3) +
                                 " earlier (the lag that explains the rotation best)"
                           : "");
  std::vector<Check> checks;
  const double ok = t.pattern_correlation_ok;
  const CheckStatus swap_status = m.rotor_is_measured_speed ? CheckStatus::kError : CheckStatus::kWarning;
  auto swapped = [&](const Transposition& s, const std::string& why) {
    return Check{"rotor_order", swap_status,
                 "rotors " + std::to_string(s.i + 1) + " and " + std::to_string(s.j + 1) + " appear swapped in " +
                     VehicleFile(v) + " (the data of " + source + " fit the swapped order with correlation " +
                     ShortNumber(s.score) + why + "; " + measured + ")"};
  };
  if (std::min(c[0], c[1]) >= ok) {
    // Two rotors of opposite spin exchanged on a + vehicle (or two on one diagonal of an X) keep
    // roll and pitch at a correlation of 0.5 but lose the yaw pattern: judged on all three axes
    // (rotors 1 and 3 exchanged: sim A 0.5 / 0.5 / -0.02, swapped back 1 / 1 / 1; sim B 0.51 / 0.51 /
    // 0.46, swapped back 0.84 at least; on 33 real flights and segments the best transposition reads at
    // most 0.34 where roll and pitch pass).
    const Transposition best = BestTransposition(m, v, [](const Eigen::Vector3d& s) { return s.minCoeff(); });
    if (best.score >= t.swap_correlation && best.score - c.minCoeff() >= 0.3) {
      checks.push_back(
          swapped(best, " on roll, pitch and yaw, against " + ShortNumber(c.minCoeff()) + " for the file's order"));
      return checks;
    }
    if (c[2] < -ok)
      checks.push_back({"rotor_spins", CheckStatus::kError,
                        source + ": the yaw moments have the opposite sign of the spins in " + VehicleFile(v) +
                            ": the spin directions appear reversed (+1 = counter-clockwise seen from above) (" +
                            measured + ")"});
    else
      checks.push_back({"rotor_spins", CheckStatus::kOk, source + ": " + measured});
    checks.push_back({"rotor_order", CheckStatus::kOk, source + ": " + measured});
  } else {
    const Transposition best = BestTransposition(m, v, [](const Eigen::Vector3d& s) { return std::min(s[0], s[1]); });
    // A swap is named only when it fits clearly better; a lagged command signal (no measured speed)
    // blurs the pattern, so there it is a warning.
    if (best.score >= t.swap_correlation && best.score - std::min(c[0], c[1]) >= 0.5)
      checks.push_back(swapped(best, ""));
    else
      checks.push_back({"rotor_order", CheckStatus::kWarning,
                        source + ": the rotor moments do not match the rotor positions of " + VehicleFile(v) +
                            ": check the rotor order and positions (" + measured + ")"});
    return checks;
  }
  checks.push_back(ImuYawCheck(m, raw, t));
  if (!plausible_kt) return checks;
  // Angular acceleration per unit Omega_i^2 is kt y_i / I_xx (roll) and -kt x_i / I_yy (pitch).
  const double kt = v.mass_kg * m.gravity / m.thrust_mean, reference = v.mass_kg * m.arm_m * m.arm_m;
  double log_ratio = 0.0;
  for (int a = 0; a < 2; ++a) {
    const Eigen::VectorXd p = predicted.row(a).transpose().array() - predicted.row(a).mean();
    const Eigen::VectorXd b = m.moment_pattern.row(a).transpose().array() - m.moment_pattern.row(a).mean();
    log_ratio += 0.5 * std::log(kt * p.squaredNorm() / b.dot(p) / reference);
  }
  const double ratio = std::exp(log_ratio);
  const std::string inertia = "apparent roll/pitch inertia from the rotor moments " + ShortNumber(ratio) + " m r^2";
  const double high = m.rotor_is_measured_speed ? t.inertia_ratio_high_measured_speed : t.inertia_ratio_high;
  const auto plausible = [&](double value) { return value >= t.inertia_ratio_low && value <= high; };
  if (plausible(ratio)) {
    checks.push_back({"gyro_units", CheckStatus::kOk, source + ": " + inertia});
  } else {
    std::string cause = "the gyro and the rotor moments disagree by far: check the gyro units (rad/s)";
    if (plausible(ratio * kRadToDeg))
      cause = "the gyro appears to be in deg/s: give rad/s (multiply gyro_x..z by " + ShortNumber(kDegToRad) + ")";
    else if (plausible(ratio * kDegToRad))
      cause =
          "the gyro reads 57 times too little: rad/s data converted as deg/s (a column map's gyro unit: rad/s, "
          "not deg/s)";
    checks.push_back({"gyro_units", CheckStatus::kError, source + ": " + cause + " (" + inertia + ")"});
  }
  return checks;
}

}  // namespace

std::vector<Check> CheckFlights(const std::vector<FlightData>& raw, const std::vector<ProcessedFlight>& processed,
                                const InputCheckThresholds& thresholds) {
  if (raw.size() != processed.size()) throw Error("CheckFlights: raw and processed flights differ in number");
  std::vector<Check> checks;
  for (size_t k = 0; k < raw.size(); ++k) {
    const FlightMetrics m = Measure(raw[k], processed[k], thresholds);
    const std::string& source = raw[k].log.source;
    const Check acc = AccelerometerCheck(m, source, thresholds), motion = MotionCheck(m, source, thresholds);
    checks.push_back(acc);
    checks.push_back(motion);
    const Check gyro_rate = CheckGyroRate(raw[k].log);
    checks.push_back(gyro_rate);
    checks.push_back(SaturationCheck(raw[k].log));
    if (motion.status != CheckStatus::kError) checks.push_back(RotorSignalCheck(m, source));
    if (raw[k].log.mocap && motion.status != CheckStatus::kError) checks.push_back(AttitudeCheck(raw[k].log));
    if (motion.status != CheckStatus::kError) checks.push_back(StateJumpCheck(raw[k].log, processed[k], m));
    // The checks below read the rotor data against the IMU: only once the IMU and motion are sane.
    if (acc.status == CheckStatus::kError || motion.status == CheckStatus::kError ||
        gyro_rate.status == CheckStatus::kError)
      continue;
    const Check airborne = AirborneCheck(m, source);
    checks.push_back(airborne);
    bool plausible_kt = false;
    checks.push_back(ScaleCheck(m, raw[k], thresholds, &plausible_kt));
    if (airborne.status == CheckStatus::kError) continue;
    for (Check& c : RotorChecks(m, raw[k], plausible_kt, thresholds)) checks.push_back(std::move(c));
  }
  return checks;
}

Check CheckGyroRate(const FlightLog& log) {
  constexpr double kHighRadps = 12.0;  // 690 deg/s as the median
  std::vector<double> rates(static_cast<size_t>(log.num_samples()));
  for (Eigen::Index i = 0; i < log.num_samples(); ++i) rates[static_cast<size_t>(i)] = log.gyro_radps.row(i).norm();
  const double median = Median(rates);
  const std::string measured = "median |gyro| " + ShortNumber(median) + " rad/s";
  if (median <= kHighRadps) return {"gyro_rate", CheckStatus::kOk, log.source + ": " + measured};
  const bool degrees = median * kDegToRad <= kHighRadps;
  return {"gyro_rate", CheckStatus::kError,
          log.source + ": " +
              (degrees ? "the gyro appears to be in deg/s: give rad/s (multiply gyro_x..z by " +
                             ShortNumber(kDegToRad) + "; a column map: unit deg/s)"
                       : "the gyro columns turn faster than any multirotor: check their units (rad/s)") +
              " (" + measured + ")"};
}

std::vector<Check> CheckTimeBase(const std::vector<FlightData>& raw, const std::vector<ProcessedFlight>& processed,
                                 double cutoff_hz) {
  if (raw.size() != processed.size()) throw Error("CheckTimeBase: raw and processed flights differ in number");
  // fs / cut-off below these: an error (-11 % on sim A), a warning (-5 %).
  constexpr double kRateRatioError = 8.0, kRateRatioWarning = 12.0;
  // Time-stamp resolution over the sample interval above this: a warning (1.7e9 s at 200 Hz: 4.8e-5).
  constexpr double kResolutionError = 1e-5;
  std::vector<Check> checks;
  for (size_t k = 0; k < raw.size(); ++k) {
    const std::string& source = raw[k].log.source;
    const double dt = processed[k].dt_s, rate_hz = 1.0 / dt, ratio = rate_hz / cutoff_hz;
    const std::string rate = ShortNumber(rate_hz) + " Hz samples, " + ShortNumber(cutoff_hz) + " Hz cut-off (" +
                             ShortNumber(ratio) + " samples per cut-off period)";
    if (ratio < kRateRatioWarning)
      checks.push_back({"sample_rate", ratio < kRateRatioError ? CheckStatus::kError : CheckStatus::kWarning,
                        source + ": the log is sampled too slowly for the low-pass cut-off (" + rate +
                            "): the derivatives lose amplitude and kd and I_zz come out low (sim: -11 % at 5, -5 % "
                            "at 10); give --cutoff-hz " +
                            ShortNumber(rate_hz / 20.0) + " or lower"});
    else
      checks.push_back({"sample_rate", CheckStatus::kOk, source + ": " + rate});
    const Eigen::VectorXd& t = raw[k].log.t_s;
    const double largest = t.size() > 0 ? std::max(std::abs(t[0]), std::abs(t[t.size() - 1])) : 0.0;
    const double resolution = largest * std::numeric_limits<double>::epsilon();
    const auto origin = raw[k].log.metadata.find("time_origin_s");
    const std::string stamps =
        (origin == raw[k].log.metadata.end() ? "" : "wall-clock stamps counted from " + origin->second + " s: ") +
        "time stamps up to " + ShortNumber(largest) + " s resolve " + ShortNumber(resolution) + " s, " +
        ShortNumber(resolution / dt) + " of the sample interval";
    if (resolution / dt > kResolutionError)
      // A warning: the bias is a few % (NanoBench's UNIX-epoch CSVs at 100 Hz read 3.9e-5), not a wrong unit.
      checks.push_back({"time_base", CheckStatus::kWarning,
                        source + ": the " + stamps +
                            " (a UNIX epoch?), which biases kd and I_zz by a few %: subtract the first time stamp "
                            "(t - t[0]) before identifying"});
    else
      checks.push_back({"time_base", CheckStatus::kOk, source + ": " + stamps});
  }
  return checks;
}

CheckedParameters CheckedFromSolution(const IdimSystem& system, const TlsSolution& solution) {
  CheckedParameters p;
  const Eigen::VectorXd predicted = PredictionChi(solution);
  for (int k = 0; k < system.num_parameters(); ++k) {
    const std::string& name = system.parameter_names[k];
    p.value[name] = solution.chi[k];
    p.std[name] = solution.std[k];
    p.essential[name] = solution.essential[k];
    if (solution.Profiled(k)) {
      p.profiled[name] = solution.profiled_chi[k];
      p.profiled_std[name] = solution.profiled_std[k];
    }
    if (solution.PredictsWithinRange(k)) {  // a value a body allows, not an estimate: no std
      p.predicts_with[name] = predicted[k];
      p.predicts_with_std[name] = 0.0;
    } else if (PredictsWithProfiled(solution, k)) {
      p.predicts_with[name] = predicted[k];
      p.predicts_with_std[name] = solution.profiled_std[k];
    }
  }
  p.covariance_names = system.parameter_names;
  p.covariance = solution.covariance;
  return p;
}

CheckedParameters CheckedFromSolution(const IdentificationResult& linear, const TlsSolution& solution) {
  CheckedParameters p = CheckedFromSolution(linear.system, solution);
  p.mass_kg = ConfigurationMasses(linear.flights);
  return p;
}

std::map<std::string, double> ConfigurationMasses(const std::vector<ProcessedFlight>& flights) {
  std::map<std::string, double> mass;
  for (const ProcessedFlight& f : flights) mass.emplace(f.vehicle.name, f.vehicle.mass_kg);
  return mass;
}

namespace {

// Value, std (0 when unknown) and whether it was estimated.
struct Estimate {
  double value = 0.0;
  double std = 0.0;
  bool estimated = false;
};

Estimate Find(const CheckedParameters& p, const std::string& name) {
  Estimate e;
  if (const auto it = p.value.find(name); it != p.value.end()) e.value = it->second;
  if (const auto it = p.std.find(name); it != p.std.end()) e.std = it->second;
  const auto it = p.essential.find(name);
  e.estimated = p.value.count(name) && (it == p.essential.end() || it->second);
  return e;
}

// The cause to name when kd and I_zz are both negative: the yaw equation holds them only as a ratio
// (kd x rotor signal = I_zz x yaw acceleration + ...), and only the weak gyroscopic terms of the roll
// and pitch rows fix their common scale. On a log with little yaw motion that scale can come out
// negative with a small first-order std (simulated Crazyflie take-off and landing: kd -1.3e-11 +-
// 8e-13 and I_zz -3.8e-6 for 1e-10 and 2.9e-5, their ratio right): reversed spins flip kd alone.
const char kYawScaleCause[] =
    "kd and I_zz are both negative: their ratio is what the yaw equation fixes, and this log has too little yaw "
    "motion to fix their scale; fly yaw manoeuvres, or take kd from a thrust stand";

bool YawScaleFlipped(const CheckedParameters& p, const std::vector<std::string>& configs) {
  const Estimate kd = Find(p, "kd");
  if (!kd.estimated || kd.value >= 0.0) return false;
  for (const std::string& config : configs)
    if (const Estimate zz = Find(p, config + ".I_zz"); zz.estimated && zz.value < 0.0) return true;
  return false;
}

// The cause to name when only I_xx + I_yy < I_zz fails with kd estimated and positive: the same
// unfixed yaw scale with both signs right (simulated take-off and low hover of configuration A: kd
// 1.25e-7 and I_zz 0.071, each at a 10 % std, for 5.1e-8 and 0.029; their ratio within 0.1 %).
std::string YawScaleTooLargeCause(const Estimate& kd, const Estimate& zz) {
  return "I_zz alone is too large, with kd: the yaw equation fixes their ratio (kd / I_zz = " +
         ShortNumber(kd.value / zz.value) +
         "), and this log has too little yaw motion to fix their scale; fly yaw manoeuvres, or take kd from a "
         "thrust stand";
}

// `yaw_anchored`: kd is estimated. Without it the yaw equation has no known scale and I_zz comes
// from the gyroscopic terms alone, so it is left out of the tests. `yaw_scale_flipped`: see
// kYawScaleCause, named instead of the inputs.
Check InertiaCheck(const CheckedParameters& p, const std::string& config, const std::string& label, const Estimate& kd,
                   bool yaw_scale_flipped) {
  const bool yaw_anchored = kd.estimated;
  const std::string name = label + " " + config;
  auto get = [&](const char* n) { return Find(p, config + "." + n); };
  const Estimate xx = get("I_xx"), yy = get("I_yy");
  Estimate zz = get("I_zz");
  zz.estimated = zz.estimated && yaw_anchored;
  const Estimate* diagonal[3] = {&xx, &yy, &zz};
  const char* axis[3] = {"I_xx", "I_yy", "I_zz"};
  std::string problems;
  bool only_zz_too_large = true;
  for (int a = 0; a < 3; ++a) {
    const Estimate& e = *diagonal[a];
    if (e.estimated && e.value < -3.0 * e.std) {
      problems += std::string(problems.empty() ? "" : "; ") + axis[a] + " = " + ShortNumber(e.value) + " < 0";
      only_zz_too_large = false;
    }
  }
  // Triangle inequalities I_a + I_b >= I_c between the estimated diagonal entries, beyond 3 std.
  for (int c = 0; c < 3; ++c) {
    const Estimate &a = *diagonal[(c + 1) % 3], &b = *diagonal[(c + 2) % 3], &z = *diagonal[c];
    if (!a.estimated || !b.estimated || !z.estimated) continue;
    const double margin = a.value + b.value - z.value;
    const double std = std::sqrt(a.std * a.std + b.std * b.std + z.std * z.std);
    if (margin < -3.0 * std) {
      problems += std::string(problems.empty() ? "" : "; ") + axis[(c + 1) % 3] + " + " + axis[(c + 2) % 3] + " < " +
                  axis[c] + " by " + ShortNumber(-margin);
      only_zz_too_large = only_zz_too_large && c == 2;
    }
  }
  if (problems.empty() && xx.estimated && yy.estimated && zz.estimated) {
    Eigen::Matrix3d inertia;
    inertia << xx.value, get("I_xy").value, get("I_xz").value, get("I_xy").value, yy.value, get("I_yz").value,
        get("I_xz").value, get("I_yz").value, zz.value;
    const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia).eigenvalues()[0];
    if (!(smallest > 0.0)) {
      problems = "smallest eigenvalue " + ShortNumber(smallest) + " <= 0";
      only_zz_too_large = false;
    }
  }
  if (problems.empty())
    return {"inertia", CheckStatus::kOk,
            name + ": positive definite, triangle inequalities hold" +
                (yaw_anchored ? "" : " (I_zz not tested: kd not estimated, so the yaw equation has no scale)")};
  return {
      "inertia", CheckStatus::kError,
      name + " inertia is not physical (" + problems + "): " +
          (yaw_scale_flipped                              ? std::string(kYawScaleCause)
           : only_zz_too_large && kd.value > 3.0 * kd.std ? YawScaleTooLargeCause(kd, zz)
                                                          : "a wrong rotor order, spin or unit in the inputs (see the "
                                                            "input checks), or a log that does not excite these axes")};
}

}  // namespace

std::vector<Check> CheckParameters(const CheckedParameters& p, const std::vector<std::string>& configs,
                                   const std::string& label) {
  std::vector<Check> checks;
  std::string not_finite, zero_std;
  for (const auto& [name, value] : p.value) {
    const Estimate e = Find(p, name);
    if (!std::isfinite(value) || !std::isfinite(e.std))
      not_finite += (not_finite.empty() ? "" : ", ") + name;
    else if (e.estimated && p.std.count(name) && e.std == 0.0)
      zero_std += (zero_std.empty() ? "" : ", ") + name;
  }
  if (!not_finite.empty())
    checks.push_back(
        {"finite", CheckStatus::kError, label + ": NaN or inf in " + not_finite + ": the data cannot determine them"});
  else
    checks.push_back({"finite", CheckStatus::kOk, label + ": every value and std is finite"});
  if (!zero_std.empty())
    checks.push_back({"parameter_std", CheckStatus::kError,
                      label + ": std exactly 0 for " + zero_std +
                          ": the data do not determine them (a motionless or unexcited log?)"});
  const Estimate kt = Find(p, "kt"), kd = Find(p, "kd");
  const bool yaw_scale_flipped = YawScaleFlipped(p, configs);
  if (kt.estimated && !(kt.value > 0.0))
    checks.push_back({"kt_positive", CheckStatus::kError,
                      label + ": kt = " + ShortNumber(kt.value) +
                          " <= 0: the rotor signal does not push the vehicle up; check the rotor columns and the "
                          "accelerometer's sign (z up, about +g in hover)"});
  else
    checks.push_back({"kt_positive", CheckStatus::kOk, label + ": kt = " + ShortNumber(kt.value)});
  if (kd.estimated && kd.value < -3.0 * kd.std)
    checks.push_back({"kd_positive", CheckStatus::kError,
                      label + ": kd = " + ShortNumber(kd.value) + " < 0 (std " + ShortNumber(kd.std) + "): " +
                          (yaw_scale_flipped ? std::string(kYawScaleCause)
                                             : "the spin directions in the vehicle file appear reversed (+1 = "
                                               "counter-clockwise seen from above)")});
  else
    checks.push_back({"kd_positive", CheckStatus::kOk,
                      label + ": kd = " + ShortNumber(kd.value) + (kd.estimated ? "" : " (not estimated)")});
  for (const std::string& config : configs) checks.push_back(InertiaCheck(p, config, label, kd, yaw_scale_flipped));
  for (Check& c : PhysicalConsistencyChecks(p, label)) checks.push_back(std::move(c));
  return checks;
}

std::string RelativeErrorList(const std::vector<std::optional<double>>& relative_error_pct, double above_pct) {
  std::string list;
  for (size_t j = 0; j < relative_error_pct.size() && j < kWrenchComponentNames.size(); ++j)
    if (relative_error_pct[j] && *relative_error_pct[j] > above_pct)
      list += std::string(list.empty() ? "" : ", ") + kWrenchComponentNames[j] + " " +
              ShortNumber(*relative_error_pct[j]) + " %";
  return list;
}

std::vector<Check> CheckRelativeError(const std::vector<std::optional<double>>& relative_error_pct,
                                      const std::string& label, bool held_out) {
  std::string not_finite;
  for (size_t j = 0; j < relative_error_pct.size() && j < kWrenchComponentNames.size(); ++j)
    if (relative_error_pct[j] && !std::isfinite(*relative_error_pct[j]))
      not_finite += std::string(not_finite.empty() ? "" : ", ") + kWrenchComponentNames[j];
  if (!not_finite.empty())
    return {{"relative_error", CheckStatus::kError, label + ": relative error not finite in " + not_finite}};
  const std::string above = RelativeErrorList(relative_error_pct, 100.0);
  if (!above.empty())
    return {{"relative_error", held_out ? CheckStatus::kWarning : CheckStatus::kError,
             label + ": relative error above 100 % (" + above +
                 "): the model explains less of the wrench than it gets wrong; check the input checks (units, rotor "
                 "order, rotor signal)"}};
  return {{"relative_error", CheckStatus::kOk, label + ": every relative error at most 100 %"}};
}

void ExcuseLinearParameterErrors(const std::vector<Check>& linear, const std::vector<Check>& with_effects,
                                 std::vector<Check>* checks) {
  // The n-th check named `name` in `list`, or null.
  const auto nth = [](const std::vector<Check>& list, const std::string& name, int n) -> const Check* {
    for (const Check& c : list)
      if (c.name == name && n-- == 0) return &c;
    return nullptr;
  };
  std::map<std::string, int> seen;
  for (const Check& failed : linear) {
    const int n = seen[failed.name]++;
    if (failed.status != CheckStatus::kError || (failed.name != "kt_positive" && failed.name != "kd_positive" &&
                                                 failed.name != "inertia" && failed.name != "physical_consistency"))
      continue;
    const Check* passed = nth(with_effects, failed.name, n);
    if (!passed || passed->status != CheckStatus::kOk) continue;
    for (Check& c : *checks)
      if (c.name == failed.name && c.status == CheckStatus::kError && c.message == failed.message)
        c = {c.name, CheckStatus::kWarning,
             c.message + "; the model with effects passes this check (" + passed->message +
                 "): the linear model lacks what they supply"};
  }
}

int IdentifySteps(const std::vector<FlightData>& flights) { return static_cast<int>(flights.size()) + 2; }

IdentificationResult IdentifyWithChecks(std::vector<FlightData> flights, const IdentifyOptions& options,
                                        std::vector<Check>* checks, const StepProgress& progress) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  const int total_steps = IdentifySteps(flights);
  std::vector<ProcessedFlight> processed =
      ProcessFlights(flights, options.observation, OffsetProgress(progress, 0, total_steps));
  *checks = CheckFlights(flights, processed);
  for (Check& c : CheckTimeBase(flights, processed, options.observation.filter.cutoff_hz))
    checks->push_back(std::move(c));
  const int num_flights = static_cast<int>(flights.size());
  flights = {};
  IdentificationResult result;
  try {
    result = IdentifyProcessed(std::move(processed), options, OffsetProgress(progress, num_flights, total_steps));
  } catch (const Error& e) {
    if (!AnyCheckFailed(*checks)) throw;
    throw Error(std::string(e.what()) + "; likely cause: " + FailedCheckMessages(*checks));
  }
  for (Check& c : CheckParameters(CheckedFromSolution(result, result.solution), result.system.config_names, "linear"))
    checks->push_back(std::move(c));
  for (Check& c : CheckRelativeError(result.relative_error_pct, "linear", /*held_out=*/false))
    checks->push_back(std::move(c));
  return result;
}

}  // namespace rotorid

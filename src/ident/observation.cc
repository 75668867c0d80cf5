#include "rotorid/ident/observation.h"

#include <array>
#include <cmath>
#include <limits>

#include "rotorid/core/error.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/parameters.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/model/rotation.h"
#include "rotorid/signal/differentiate.h"
#include "rotorid/signal/resample.h"

namespace rotorid {

const char* DataSourceName(DataSource source) { return source == DataSource::kImu ? "imu" : "mocap"; }

std::string BodyParameterName(const ProcessedFlight& flight, int k) {
  const bool own = k < 3 && !flight.first_moment_label.empty();
  return flight.vehicle.name + "." + (own ? flight.first_moment_label + "." : "") + kBodyParameterNames[k];
}

std::string ObservationOptions::Validate() const {
  if (filter.band != FilterBand::kLowPass) return "the observation filter must be a low-pass";
  if (filter.order < 1 || filter.order > 12) return "filter order must be in 1..12";
  if (!(filter.cutoff_hz > 0.0)) return "filter cut-off must be positive (Hz)";
  if (row_rate_hz < 0.0) return "row rate must be positive (Hz) or 0 for automatic";
  if (!(edge_trim_s >= 0.0)) return "edge trim must not be negative (s)";
  // Samples are counted in int: a trim longer than any flight (or inf) would overflow them.
  if (!(edge_trim_s <= 600.0)) return "edge trim must be at most 600 s (a trim longer than the flight leaves nothing)";
  return {};
}

namespace {

// The ground's z in the motion-capture frame: the log's `# ground_z:` metadata, else the lowest z of
// O_d in the log (a flight that starts or ends on the ground).
double GroundZ(const FlightLog& log, const Eigen::Ref<const Eigen::VectorXd>& z) {
  const auto it = log.metadata.find("ground_z");
  if (it == log.metadata.end()) return z.minCoeff();
  try {
    size_t used = 0;
    const double value = std::stod(it->second, &used);
    if (used == it->second.size() && std::isfinite(value)) return value;
  } catch (const std::exception&) {
  }
  throw Error(log.source + ": metadata 'ground_z' must be a number (m), got '" + it->second + "'");
}

// Variance gain of white noise through filtfilt (|H|^2 applied twice) and, optionally, the
// fourth-order central difference (per application): (2/fs) * integral over [0, fs/2].
double NoiseVarianceGain(const SosFilter& filter, double fs, int differentiations) {
  const int steps = 4000;
  const double nyquist = 0.5 * fs, dt = 1.0 / fs;
  double integral = 0.0;
  for (int k = 0; k <= steps; ++k) {
    const double f = nyquist * k / steps;
    const double h = filter.Gain(f, fs);
    double value = h * h * h * h;
    const double phase = 2.0 * M_PI * f * dt;  // response of FourthOrderCentralDifference
    const double d = (8.0 * std::sin(phase) - std::sin(2.0 * phase)) / (6.0 * dt);
    for (int i = 0; i < differentiations; ++i) value *= d * d;
    integral += (k == 0 || k == steps ? 0.5 : 1.0) * value;
  }
  return integral * (nyquist / steps) / nyquist;
}

Eigen::Vector3d ColumnNoise(const Eigen::MatrixXd& x) {
  Eigen::Vector3d sigma;
  for (int a = 0; a < 3; ++a) sigma[a] = WhiteNoiseStd(x.col(a));
  return sigma;
}

// The sample interval: the median, which dropouts and jitter do not move. Stamps of a wall clock (a
// UNIX epoch) carry a double's rounding (2.4e-7 s at 1.7e9 s): it put the median 2e-5 off at 200 Hz,
// the resampling grid then drifted off the samples (0.3 sample intervals after 60 s), and its
// interpolation's smoothing biased kd and I_zz by -4 % (the bundled B flight). For such stamps (read
// as offsets from a wall clock, metadata 'time_origin_s', or still large) the interval is the mean of
// the intervals within half the median of it (dropouts left out), where it differs from the median by
// what rounding can (1e-9 to 1e-4): off by the rounding over the whole log. Exact stamps and other logs
// keep the median (their results unchanged to the bit).
double SampleInterval(const FlightLog& log) {
  const double median = log.MedianDt();
  const int n = log.num_samples();
  const bool wall_clock = log.metadata.count("time_origin_s") > 0 ||
                          (n > 0 && std::abs(log.t_s[n - 1]) * std::numeric_limits<double>::epsilon() > 1e-9 * median);
  if (!wall_clock) return median;
  double sum = 0.0;
  int count = 0;
  for (int i = 1; i < n; ++i) {
    const double interval = log.t_s[i] - log.t_s[i - 1];
    if (std::abs(interval - median) <= 0.5 * median) sum += interval, ++count;
  }
  const double mean = count > 0 ? sum / count : median;
  const double difference = std::abs(mean - median);
  return difference > 1e-9 * median && difference <= 1e-4 * median ? mean : median;
}

// The samples [begin, end) free of gaps longer than kMaxGapIntervals sample intervals; a gap
// further than `edge_s` from both ends of the log is an error naming it.
std::pair<int, int> GapFreeRange(const FlightLog& log, double dt, double edge_s) {
  const int n = log.num_samples();
  int begin = 0, end = n;
  for (int i = 1; i < n; ++i) {
    const double gap = log.t_s[i] - log.t_s[i - 1];
    if (gap <= kMaxGapIntervals * dt) continue;
    if (log.t_s[i - 1] - log.t_s[0] < edge_s) {
      begin = i;
    } else if (log.t_s[n - 1] - log.t_s[i] < edge_s) {
      end = i;
      break;
    } else {
      throw Error(log.source + ": the time jumps by " + std::to_string(gap) + " s (" +
                  std::to_string(static_cast<long long>(std::llround(std::min(gap / dt, 1e18)))) +
                  " sample intervals) from t = " + std::to_string(log.t_s[i - 1]) +
                  " s to t = " + std::to_string(log.t_s[i]) + " s (data row " + std::to_string(i + 1) +
                  "); rotorid does not interpolate across gaps longer than " +
                  std::to_string(static_cast<int>(kMaxGapIntervals)) +
                  " samples: use the parts before and after it as separate flights (--window)");
    }
  }
  return {begin, end};
}

// The IMU data corrected by the effects the vehicle file gives known values of (a known lever arm),
// with the filtered rates, as the refinement corrects them by its estimated effects.
void CorrectByKnownEffects(const Vehicle& vehicle, ProcessedFlight* flight) {
  const EffectChain chain = ActingEffects(KnownEffects(vehicle), EffectStage::kImuSensor);
  if (chain.kinds.empty()) return;
  const std::vector<const double*> parameters = chain.Parameters();
  for (Eigen::Index i = 0; i < flight->specific_force.rows(); ++i) {
    ImuSample<double> sample{flight->angular_velocity.row(i).transpose(),
                             flight->angular_acceleration.row(i).transpose(),
                             flight->specific_force.row(i).transpose()};
    CorrectImu(chain.kinds, parameters, &sample);
    flight->angular_velocity.row(i) = sample.angular_velocity.transpose();
    flight->angular_acceleration.row(i) = sample.angular_acceleration.transpose();
    flight->specific_force.row(i) = sample.specific_force.transpose();
  }
}

}  // namespace

Eigen::MatrixXd SpeedFromFilteredSquare(const Eigen::Ref<const Eigen::MatrixXd>& filtered_square) {
  return filtered_square.cwiseMax(0.0).cwiseSqrt();
}

Eigen::MatrixXd FilteredRotorSpeed(const SosFilter& filter, const Eigen::Ref<const Eigen::MatrixXd>& omega_squared) {
  return SpeedFromFilteredSquare(FiltFiltColumns(filter, omega_squared));
}

ProcessedFlight ProcessFlight(const FlightLog& log, const Vehicle& vehicle, double weight,
                              const ObservationOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  if (log.num_rotors() != vehicle.num_rotors())
    throw Error(log.source + ": the log has " + std::to_string(log.num_rotors()) + " rotor columns, vehicle '" +
                vehicle.name + "' has " + std::to_string(vehicle.num_rotors()) + " rotors");
  if (options.source == DataSource::kMocap && !log.mocap)
    throw Error(log.source + ": --source mocap needs pos_x,pos_y,pos_z and roll,pitch,yaw (or qw..qz) columns");
  const double dt = SampleInterval(log);
  if (!(dt > 0.0)) throw Error(log.source + ": cannot determine the sample interval");
  const double fs = 1.0 / dt;
  // Interpolation across a gap invents data, and over a long one a grid that memory cannot hold.
  // Interpolation across a gap invents data, and over a long one a grid that memory cannot hold. A
  // gap within the edge that is trimmed anyway (logging start-up) cuts that edge off.
  const auto [begin, end] = GapFreeRange(log, dt, options.edge_trim_s);
  if (begin > 0 || end < log.num_samples()) return ProcessFlight(log.Slice(begin, end), vehicle, weight, options);
  if (const std::string problem = options.filter.Validate(fs); !problem.empty())
    throw Error(log.source + ": " + problem + " (log sampled at " + std::to_string(fs) + " Hz)");

  ProcessedFlight out;
  out.source = log.source;
  out.vehicle = vehicle;
  out.weight = weight;
  out.dt_s = dt;
  out.gravity_mps2 = log.gravity_mps2;
  out.t_s = UniformTimeBase(log.t_s[0], log.t_s[log.num_samples() - 1], fs);
  const int n = static_cast<int>(out.t_s.size());
  const int trim = static_cast<int>(std::ceil(options.edge_trim_s * fs));
  const double row_rate = options.row_rate_hz > 0.0 ? options.row_rate_hz : 5.0 * options.filter.cutoff_hz;
  const int step = std::max(1, static_cast<int>(std::lround(fs / row_rate)));
  if (n - 2 * trim < 10 * step)
    throw Error(log.source + ": too short after leaving out " + std::to_string(options.edge_trim_s) +
                " s at each end (" + std::to_string(log.duration_s()) + " s of data)");

  const SosFilter filter = DesignButterworth(options.filter, fs);
  const double gain0 = std::sqrt(NoiseVarianceGain(filter, fs, 0));
  const double gain1 = std::sqrt(NoiseVarianceGain(filter, fs, 1));
  const double gain2 = std::sqrt(NoiseVarianceGain(filter, fs, 2));

  out.filter = filter;
  out.rotor_raw = InterpolateLinear(log.t_s, log.rotor_radps, out.t_s);
  out.rotor = FilteredRotorSpeed(filter, out.rotor_raw.array().square().matrix());
  if (log.rotor_command)
    out.rotor_command = InterpolateLinear(log.t_s, *log.rotor_command, out.t_s);  // raw, as rotor_raw
  if (log.voltage_v)
    out.voltage_v = FiltFiltColumns(filter, InterpolateLinear(log.t_s, *log.voltage_v, out.t_s)).col(0);
  if (log.mocap) {
    Eigen::MatrixXd angles = log.mocap->bryant_rad;
    for (int a = 0; a < 3; ++a) angles.col(a) = UnwrapAngle(angles.col(a));
    const Eigen::MatrixXd eta = FiltFiltColumns(filter, InterpolateLinear(log.t_s, angles, out.t_s));
    const Eigen::MatrixXd position =
        FiltFiltColumns(filter, InterpolateLinear(log.t_s, log.mocap->position_w_m, out.t_s));
    // The log's own velocity where it has one (an estimator's), else the differentiated position.
    const Eigen::MatrixXd velocity_w =
        log.mocap->velocity_w_mps
            ? FiltFiltColumns(filter, InterpolateLinear(log.t_s, *log.mocap->velocity_w_mps, out.t_s))
            : FourthOrderCentralDifference(position, dt);
    out.velocity_mps = Eigen::MatrixX3d(n, 3);
    for (int i = 0; i < n; ++i)
      out.velocity_mps->row(i) =
          (BryantToRotation(eta.row(i).transpose()).transpose() * velocity_w.row(i).transpose()).transpose();
    const double ground_z = GroundZ(log, position.col(2));
    out.height_m = position.col(2).array() - ground_z;
    out.rotor_height_m = Eigen::MatrixXd(n, vehicle.num_rotors());
    for (int i = 0; i < n; ++i) {
      const Eigen::Matrix3d r_wb = BryantToRotation(eta.row(i).transpose());
      for (int k = 0; k < vehicle.num_rotors(); ++k)
        (*out.rotor_height_m)(i, k) = (*out.height_m)[i] + r_wb.row(2).dot(vehicle.rotors[k].position_m);
    }
  }
  if (options.source == DataSource::kImu) {
    const Eigen::MatrixXd gyro = InterpolateLinear(log.t_s, log.gyro_radps, out.t_s);
    const Eigen::MatrixXd acc = InterpolateLinear(log.t_s, log.acc_mps2, out.t_s);
    out.angular_velocity = FiltFiltColumns(filter, gyro);
    out.angular_acceleration = FourthOrderCentralDifference(out.angular_velocity, dt);
    out.specific_force = FiltFiltColumns(filter, acc);
    CorrectByKnownEffects(vehicle, &out);
    const Eigen::Vector3d gyro_noise = ColumnNoise(gyro), acc_noise = ColumnNoise(acc);
    out.noise.angular_velocity = gyro_noise * gain0;
    out.noise.angular_acceleration = gyro_noise * gain1;
    out.noise.specific_force = acc_noise * gain0;
  } else {
    Eigen::MatrixXd angles = log.mocap->bryant_rad;
    for (int a = 0; a < 3; ++a) angles.col(a) = UnwrapAngle(angles.col(a));
    angles = InterpolateLinear(log.t_s, angles, out.t_s);
    const Eigen::MatrixXd position = InterpolateLinear(log.t_s, log.mocap->position_w_m, out.t_s);
    const Eigen::MatrixXd eta = FiltFiltColumns(filter, angles);
    const Eigen::MatrixXd eta_dot = FourthOrderCentralDifference(eta, dt);
    const Eigen::MatrixXd eta_ddot = FourthOrderCentralDifference(eta_dot, dt);
    const Eigen::MatrixXd accel_w =
        FourthOrderCentralDifference(FourthOrderCentralDifference(FiltFiltColumns(filter, position), dt), dt);
    out.angular_velocity.resize(n, 3);
    out.angular_acceleration.resize(n, 3);
    out.specific_force.resize(n, 3);
    const Eigen::Vector3d gravity_w(0.0, 0.0, -log.gravity_mps2);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d e = eta.row(i), ed = eta_dot.row(i), edd = eta_ddot.row(i);
      const Eigen::Matrix3d t = BryantRateMatrix(e);
      out.angular_velocity.row(i) = (t * ed).transpose();
      out.angular_acceleration.row(i) = (BryantRateMatrixDerivative(e, ed) * ed + t * edd).transpose();
      const Eigen::Vector3d a = accel_w.row(i);
      out.specific_force.row(i) = (BryantToRotation(e).transpose() * (a - gravity_w)).transpose();
    }
    const Eigen::Vector3d position_noise = ColumnNoise(position), angle_noise = ColumnNoise(angles);
    out.noise.specific_force = Eigen::Vector3d::Constant(position_noise.norm() / std::sqrt(3.0) * gain2);
    out.noise.angular_velocity = angle_noise * gain1;
    out.noise.angular_acceleration = angle_noise * gain2;
  }
  for (int i = trim; i < n - trim; i += step) out.row_samples.push_back(i);
  return out;
}

ProcessedFlight LowPassFurther(const ProcessedFlight& flight, const ButterworthOptions& extra, DataSource source) {
  const double fs = 1.0 / flight.dt_s;
  if (const std::string problem = extra.Validate(fs); !problem.empty()) throw Error(flight.source + ": " + problem);
  const SosFilter more = DesignButterworth(extra, fs);
  ProcessedFlight out = flight;
  out.filter.sections.insert(out.filter.sections.end(), more.sections.begin(), more.sections.end());
  // Filtering commutes with the (linear) central differences: filtering w' again is differentiating
  // the twice-filtered w.
  out.angular_velocity = FiltFiltColumns(more, flight.angular_velocity);
  out.angular_acceleration = FiltFiltColumns(more, flight.angular_acceleration);
  out.specific_force = FiltFiltColumns(more, flight.specific_force);
  out.rotor = FilteredRotorSpeed(more, flight.rotor.array().square().matrix());
  if (flight.voltage_v) out.voltage_v = FiltFiltColumns(more, *flight.voltage_v).col(0);
  if (flight.velocity_mps) out.velocity_mps = FiltFiltColumns(more, *flight.velocity_mps);
  if (flight.height_m) out.height_m = FiltFiltColumns(more, *flight.height_m).col(0);
  if (flight.rotor_height_m) out.rotor_height_m = FiltFiltColumns(more, *flight.rotor_height_m);
  // Noise std scales by the ratio of the cascade's gain to the first filter's, per derivative order.
  auto ratio = [&](int differentiations) {
    const double before = NoiseVarianceGain(flight.filter, fs, differentiations);
    return before > 0.0 ? std::sqrt(NoiseVarianceGain(out.filter, fs, differentiations) / before) : 1.0;
  };
  const bool imu = source == DataSource::kImu;
  out.noise.angular_velocity *= ratio(imu ? 0 : 1);
  out.noise.angular_acceleration *= ratio(imu ? 1 : 2);
  out.noise.specific_force *= ratio(imu ? 0 : 2);
  return out;
}

FlightInputs ProcessedFlight::inputs() const {
  FlightInputs available;
  available.velocity = velocity_mps.has_value();
  available.height = height_m.has_value() && rotor_height_m.has_value();
  available.rotor_radius = vehicle.rotor_radius_m.has_value();
  available.voltage = voltage_v.has_value();
  available.rotor_acceleration = rotor.rows() >= 3;  // differentiable at every row sample
  available.specific_force_rates = specific_force.rows() >= 3;
  available.rotor_command = rotor_command.has_value();
  return available;
}

Eigen::Matrix<double, 6, kNumIdimColumns> IdimRowsOfRowSample(const ProcessedFlight& flight, int r) {
  const int i = flight.row_samples[r];
  const Eigen::Vector3d omega = flight.angular_velocity.row(i), omega_dot = flight.angular_acceleration.row(i),
                        s = flight.specific_force.row(i);
  return IdimRows<double>(omega, omega_dot, s, flight.rotor.row(i).transpose(), flight.vehicle);
}

Eigen::MatrixXd BuildIdimMatrix(const ProcessedFlight& flight) {
  const int rows = flight.num_rows_samples();
  Eigen::MatrixXd w(6 * rows, kNumIdimColumns);
  for (int r = 0; r < rows; ++r) w.middleRows<6>(6 * r) = IdimRowsOfRowSample(flight, r);
  return w;
}

Eigen::Matrix<double, 6, kNumIdimColumns> IdimRowsSignalDerivative(const Eigen::Vector3d& w, double mass_kg, int k) {
  constexpr int kMs = kNumRotorCoefficients, kInertia = kMs + 3, kMass = kNumIdimColumns - 1;
  Eigen::Matrix<double, 6, kNumIdimColumns> d = Eigen::Matrix<double, 6, kNumIdimColumns>::Zero();
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(k % 3);
  if (k < 3) {  // [w x]^2 ms and [w x] I w
    const Eigen::Matrix3d w_skew = Skew<double>(w), e_skew = Skew<double>(e);
    d.block<3, 3>(0, kMs) = e_skew * w_skew + w_skew * e_skew;
    d.block<3, 6>(3, kInertia) = e_skew * InertiaProductMatrix<double>(w) + w_skew * InertiaProductMatrix<double>(e);
  } else if (k < 6) {  // [w' x] ms and I w'
    d.block<3, 3>(0, kMs) = Skew<double>(e);
    d.block<3, 6>(3, kInertia) = InertiaProductMatrix<double>(e);
  } else {  // m s and -[s x] ms
    d.block<3, 1>(0, kMass) = mass_kg * e;
    d.block<3, 3>(3, kMs) = -Skew<double>(e);
  }
  return d;
}

std::vector<Eigen::MatrixXd> IdimNoiseCovariance(const ProcessedFlight& flight) {
  Eigen::Matrix<double, 9, 1> variance;
  variance << flight.noise.angular_velocity, flight.noise.angular_acceleration, flight.noise.specific_force;
  variance = variance.cwiseAbs2();
  // Sum over rows of w w^T: the derivatives by w are linear in w, sum_m w_m dW/dx_k(e_m).
  Eigen::Matrix3d w_moment = Eigen::Matrix3d::Zero();
  for (int i : flight.row_samples) {
    const Eigen::Vector3d w = flight.angular_velocity.row(i);
    w_moment.noalias() += w * w.transpose();
  }
  const double rows = flight.num_rows_samples(), mass = flight.vehicle.mass_kg;
  std::vector<Eigen::MatrixXd> cov(kNumWrenchComponents, Eigen::MatrixXd::Zero(kNumIdimColumns, kNumIdimColumns));
  for (int k = 0; k < 9; ++k) {
    if (variance[k] == 0.0) continue;
    if (k >= 3) {
      const Eigen::Matrix<double, 6, kNumIdimColumns> d = IdimRowsSignalDerivative(Eigen::Vector3d::Zero(), mass, k);
      for (int c = 0; c < kNumWrenchComponents; ++c)
        cov[c].noalias() += (rows * variance[k]) * d.row(c).transpose() * d.row(c);
      continue;
    }
    std::array<Eigen::Matrix<double, 6, kNumIdimColumns>, 3> by_w;
    for (int m = 0; m < 3; ++m) by_w[m] = IdimRowsSignalDerivative(Eigen::Vector3d::Unit(m), mass, k);
    for (int c = 0; c < kNumWrenchComponents; ++c) {
      Eigen::Matrix<double, kNumIdimColumns, 3> a;
      for (int m = 0; m < 3; ++m) a.col(m) = by_w[m].row(c).transpose();
      cov[c].noalias() += variance[k] * a * w_moment * a.transpose();
    }
  }
  return cov;
}

}  // namespace rotorid

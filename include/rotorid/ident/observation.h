#pragma once

// From a flight log to the rows of the IDIM (MODEL.md sections 1 and 3): resampling onto a
// uniform time base, the same zero-phase low-pass on every signal, differentiation, the choice
// of the samples that become rows, and the noise levels the default TLS needs.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/signal/butterworth.h"

namespace rotorid {

enum class DataSource { kImu, kMocap };
const char* DataSourceName(DataSource source);

struct ObservationOptions {
  // IMU: gyro and accelerometer. MOCAP: pose differentiated twice (MODEL.md section 3).
  DataSource source = DataSource::kImu;
  // Zero-phase low-pass applied to every signal (gyro, accelerometer, pose, rotor signal) before
  // differentiation and row selection, so that no column of W_t is delayed against another.
  ButterworthOptions filter = {4, FilterBand::kLowPass, 10.0, 0.0};
  // Rate of the rows (Hz): the filtered signals are decimated to about this rate so that
  // neighbouring rows carry nearly independent noise. 0: five times the cut-off.
  double row_rate_hz = 0.0;
  // Seconds left out at both ends, where filter transients and shifted rotor signals live.
  double edge_trim_s = 0.5;

  std::string Validate() const;
};

// White-noise standard deviations of the filtered signals that enter the regressor, per axis.
struct SignalNoise {
  Eigen::Vector3d specific_force = Eigen::Vector3d::Zero();        // m/s^2
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();      // rad/s
  Eigen::Vector3d angular_acceleration = Eigen::Vector3d::Zero();  // rad/s^2
};

// One flight after signal processing, at the uniform base rate. Rows of the IDIM are taken at
// `row_samples`. The refinement re-builds rows from these arrays with effects applied.
struct ProcessedFlight {
  std::string source;
  Vehicle vehicle;
  double weight = 1.0;
  double dt_s = 0.0;
  Eigen::VectorXd t_s;                    // uniform base time
  Eigen::MatrixX3d specific_force;        // s, IMU (or body) frame, filtered
  Eigen::MatrixX3d angular_velocity;      // w, filtered
  Eigen::MatrixX3d angular_acceleration;  // w', derivative of the filtered w
  Eigen::MatrixXd rotor_raw;              // rotor signal |Omega_i| on the base time, unfiltered
  Eigen::MatrixXd rotor;                  // sqrt of the filtered Omega_i^2: the rotor columns are linear in
                                          // Omega^2, so it is Omega^2 that goes through the low-pass
  SosFilter filter;                       // the low-pass applied to every signal
  std::vector<int> row_samples;           // indices of the samples that become rows
  SignalNoise noise;                      // of the filtered signals at the base rate
  double gravity_mps2 = kStandardGravity;
  // Inputs effects may need (EffectDescriptor::Info::inputs), on the base time, where the log has
  // them: the raw command next to the mapped speed; from motion capture the velocity of O_d in F_d
  // and the heights of O_d and of each rotor above the ground (the log's `# ground_z:` metadata,
  // else its lowest z of O_d); the voltage. The derivatives the effects need at the row samples
  // (the rotor acceleration, s' and s'') are taken there (FourthOrderCentralDifferenceAt), not kept
  // for every sample: 58 MB of an hour at 200 Hz.
  std::optional<Eigen::MatrixXd> rotor_command;
  std::optional<Eigen::MatrixX3d> velocity_mps;
  std::optional<Eigen::VectorXd> height_m;
  std::optional<Eigen::MatrixXd> rotor_height_m;  // of each rotor's hub (n x rotors)
  std::optional<Eigen::VectorXd> voltage_v;
  // Which log the flight was cut from (the segments of one log share it; -1: a log of its own).
  int log_index = -1;
  // Per-flight first moments: the label of this flight's own first moment ("flight2" names
  // "<config>.flight2.ms_x"); empty when the flights of its configuration share one.
  std::string first_moment_label;

  int num_rows_samples() const { return static_cast<int>(row_samples.size()); }
  FlightInputs inputs() const;
};

// The name of body parameter k (kBodyParameterNames) of this flight: "<config>.<name>", and
// "<config>.<label>.ms_x" for a first moment of its own.
std::string BodyParameterName(const ProcessedFlight& flight, int k);

// sqrt(filtfilt(Omega^2)) per column: the rotor signal that enters the rows. The second step alone
// (a filtered square can dip below 0 near a stop: read as 0) for callers that filter more columns
// alongside.
Eigen::MatrixXd SpeedFromFilteredSquare(const Eigen::Ref<const Eigen::MatrixXd>& filtered_square);
Eigen::MatrixXd FilteredRotorSpeed(const SosFilter& filter, const Eigen::Ref<const Eigen::MatrixXd>& omega_squared);

// Longest time step (in median sample intervals) that ProcessFlight interpolates across; a longer
// gap is an error naming its place, unless it lies within the edge trim of either end, which is then
// cut off (docs/input_formats.md).
inline constexpr double kMaxGapIntervals = 10.0;

ProcessedFlight ProcessFlight(const FlightLog& log, const Vehicle& vehicle, double weight,
                              const ObservationOptions& options);

// The flight as if processed with `extra` (a low-pass) after the filter it went through: every
// filtered signal (rotor speeds through their squares) filtered again, the cascade kept in `filter`
// for the effects that re-filter the raw rotor signal, the noise levels scaled by the cascade's gain
// (`source`: how the flight was processed, which sets the derivative order of each signal). The row
// samples stay. The diagnosis re-fits timing effects at half the cut-off with it.
ProcessedFlight LowPassFurther(const ProcessedFlight& flight, const ButterworthOptions& extra, DataSource source);

// The IDIM rows of one flight: 6 rows per row sample (sample-major, components Fx Fy Fz Mx My Mz),
// columns [kt kd chi(9) m] as IdimRows.
Eigen::MatrixXd BuildIdimMatrix(const ProcessedFlight& flight);
// Its rows 6 r .. 6 r + 5: those of row sample r.
Eigen::Matrix<double, 6, kNumIdimColumns> IdimRowsOfRowSample(const ProcessedFlight& flight, int r);

// Per wrench component (6), the sum over the flight's rows of the covariance of the errors of the
// row entries (12x12, columns as BuildIdimMatrix) caused by the white noise of the signals, to first
// order: sum over rows and signals k of sigma_k^2 (dW/dx_k)^T (dW/dx_k) per component. The Jacobian
// is IdimRowsSignalDerivative; it is linear in w and otherwise constant, so the sum over rows needs
// only the number of rows and the second moments of w.
std::vector<Eigen::MatrixXd> IdimNoiseCovariance(const ProcessedFlight& flight);

// The derivative of IdimRows (6 x 12) with respect to signal k of x = [w; w'; s] (k = 0..8), in
// closed form. The regressor is at most quadratic in the signals: the derivative with respect to w
// is linear in w and those with respect to w' and s are constant; none depends on w', s or Omega.
Eigen::Matrix<double, 6, kNumIdimColumns> IdimRowsSignalDerivative(const Eigen::Vector3d& w, double mass_kg, int k);

}  // namespace rotorid

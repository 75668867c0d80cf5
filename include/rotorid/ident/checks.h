#pragma once

// Plausibility checks of inputs and results (INTERFACE.md section 5, `checks[]`): the input
// mistakes a user makes (units, rotor order and spins, a log on the ground) and results that
// cannot be physical (an inertia that is not positive definite, kd < 0, NaN). Each check names
// the likely cause and the fix; thresholds and the data they were tuned on: docs/report_format.md.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/ident/identify.h"

namespace rotorid {

enum class CheckStatus { kOk, kWarning, kError };
const char* CheckStatusName(CheckStatus status);

struct Check {
  std::string name;  // accelerometer_units, rotor_order, inertia, ...
  CheckStatus status = CheckStatus::kOk;
  std::string message;
};

bool AnyCheckFailed(const std::vector<Check>& checks);
// The messages of the failed checks, joined by "; ".
std::string FailedCheckMessages(const std::vector<Check>& checks);

// Thresholds of the input checks (docs/report_format.md gives the values measured on the bundled
// simulated flights and the real Crazyflie flights).
struct InputCheckThresholds {
  // Median |specific force| / g outside [low, high] is an error (accelerometer units).
  double gravity_ratio_low = 0.7;
  double gravity_ratio_high = 1.4;
  // mass / r^3 (kg/m^3, r the mean rotor distance from the z axis) of real multirotors.
  double density_low_kgpm3 = 5.0;
  double density_high_kgpm3 = 5000.0;
  // kt from hover (m g / mean sum Omega^2) over rho r^4 / (4 pi^2): a thrust coefficient C_T (D/r)^4.
  double thrust_coefficient_low = 2e-3;
  double thrust_coefficient_high = 3.0;
  // kt from hover over rho d^4 / (4 pi^2), d the smallest distance between two rotors (the largest
  // propeller diameter that fits): the C_T propellers of that size would need. Real propellers
  // stay below 0.2; a rotor speed in rev/s reads 39.5x high (sim A 0.011 -> 0.44, Crazyflie 0.036).
  double spacing_thrust_coefficient_high = 0.25;
  // Apparent roll/pitch inertia (from the rotor moments and the gyro) over m r^2.
  double inertia_ratio_low = 0.01;
  // 50, not 5: jana00 (figure 8, little roll/pitch excitation) reads 4.5 with the RPM deck and 16.7
  // through the PWM map; a gyro in deg/s reads 57x low, which the lower bound catches.
  double inertia_ratio_high = 50.0;
  // With a measured rotor speed (no command map blurring the pattern), real flights read at most
  // 4.5 (jana00); rad/s data declared deg/s read 57x high (sim A 0.28 -> 16).
  double inertia_ratio_high_measured_speed = 8.0;
  // The rotor-moment pattern fits the vehicle file when its correlation exceeds this per axis.
  double pattern_correlation_ok = 0.4;
  // The rotor moments may turn at most this far (deg) about z from the rotor positions' pattern:
  // the mistakes come in steps of 45 deg (a board mounted yawed, an X vehicle given as +); sims
  // read below 1 deg. Real flights with a velocity (motion capture, an estimator) at most 7.5 deg, once
  // the moments the velocity explains (rotor drag) are left out: jana01 read -29.5 deg with them. The
  // Betaflight Gecko log, without velocity, reads 26 deg.
  double imu_yaw_deg = 35.0;
  // A transposition of two rotors is named when it fits with at least this correlation (and by 0.5
  // better than the file's order).
  double swap_correlation = 0.8;
  // The rotor-moment pattern is measured with the rotor signal shifted by the lag in [0, max] (s)
  // that best explains the angular acceleration, whatever the rotor order: a motor command leads
  // the rotor speed by the motor's response (jana01-06 through the PWM map: 41-53 ms), a measured
  // speed trails little (its filter, telemetry: 6-12 ms). Defaults: 0.15 s and 0.03 s.
  double max_command_lag_s = 0.15;
  double max_speed_lag_s = 0.03;
  // Below these the log is motionless: RMS angular velocity (rad/s) and thrust variation (%).
  double motionless_angular_velocity_radps = 0.02;
  double motionless_thrust_variation_pct = 1.0;
};

// The input checks of each flight (`raw[k]` is the flight `processed[k]` came from).
std::vector<Check> CheckFlights(const std::vector<FlightData>& raw, const std::vector<ProcessedFlight>& processed,
                                const InputCheckThresholds& thresholds = {});

// A multirotor's typical turn rate: real flights read a median |gyro| of 0.2-5 rad/s (Crazyflie,
// Betaflight, INDIflight logs); a gyro in deg/s read as rad/s reads 57x that (error above 12 rad/s,
// naming deg/s). Also run on the whole log before segmentation, which would otherwise leave most of
// such a log out as "gyro limit" and the identification blame the excitation.
Check CheckGyroRate(const FlightLog& log);

// The time base of each flight: a sample rate too low for the low-pass cut-off `cutoff_hz` (the
// filtered derivatives then bias kd and I_zz: sim A at 50 Hz with a 10 Hz cut-off -11 %, at 100 Hz
// -5 %), and time stamps so large that a double no longer resolves them (a UNIX epoch: 2.4e-7 s at
// 1.7e9 s, kd and I_zz -2.6 % at 200 Hz; a warning).
std::vector<Check> CheckTimeBase(const std::vector<FlightData>& raw, const std::vector<ProcessedFlight>& processed,
                                 double cutoff_hz);

// Named parameter values with their std (std absent: not known) of one model.
struct CheckedParameters {
  std::map<std::string, double> value;
  std::map<std::string, double> std;
  std::map<std::string, bool> essential;
  // What the model predicts with where that is not `value` (PredictionChi: a discarded inertia's
  // profiled estimate), with its std.
  std::map<std::string, double> predicts_with;
  std::map<std::string, double> predicts_with_std;
  // A discarded parameter's estimate beside the others (TlsSolution::profiled_chi) and its std, where
  // the model predicts with another value (a range a body allows) or none: the estimate's distance to
  // the physical bodies counts it.
  std::map<std::string, double> profiled;
  std::map<std::string, double> profiled_std;
  // The covariance of the values named in covariance_names (empty: only the std is known): the
  // metric of the projection onto the consistent bodies.
  std::vector<std::string> covariance_names;
  Eigen::MatrixXd covariance;
  // Mass of each configuration (kg): physical_consistency is checked for the configurations in it.
  std::map<std::string, double> mass_kg;
};
CheckedParameters CheckedFromSolution(const IdimSystem& system, const TlsSolution& solution);
// The same with the configurations' masses, from `linear`'s flights (solution: linear's or a
// refinement of it).
CheckedParameters CheckedFromSolution(const IdentificationResult& linear, const TlsSolution& solution);
// Mass of each configuration of `flights` (kg).
std::map<std::string, double> ConfigurationMasses(const std::vector<ProcessedFlight>& flights);

// kt > 0, kd > 0, inertia of each configuration positive definite and the triangle inequalities
// (violations beyond 3 std), finite values and std, an essential parameter with std 0, and
// physical_consistency (PhysicalConsistencyChecks, rotorid/ident/body_consistency.h) of each
// configuration in parameters.mass_kg. `label` says which model ("linear", "refined").
std::vector<Check> CheckParameters(const CheckedParameters& parameters, const std::vector<std::string>& configs,
                                   const std::string& label);
// The linear model's parameter checks (`linear`, CheckParameters of it) that fail where the same check
// of a model with effects (`with_effects`, CheckParameters of that model; the n-th check of a name
// against the n-th, so one inertia check per configuration) passes: the linear model lacks what the
// effects supply (an unmodelled ground effect on a take-off flight with little yaw sent I_zz to 0.071
// for 0.029, the refinement with it 0.033). Each such check in `checks` becomes a warning that says so,
// and the other model's checks decide the exit. Input checks and the relative error are left alone.
void ExcuseLinearParameterErrors(const std::vector<Check>& linear, const std::vector<Check>& with_effects,
                                 std::vector<Check>* checks);
// "Mx 763 %, My 988 %": the components of Table III that are present and above `above_pct`.
std::string RelativeErrorList(const std::vector<std::optional<double>>& relative_error_pct, double above_pct);
// Table III above 100 % (error on the identification flights, warning on held-out ones) or not finite.
std::vector<Check> CheckRelativeError(const std::vector<std::optional<double>>& relative_error_pct,
                                      const std::string& label, bool held_out);

// Input checks, the identification, and the checks of its result. When the identification fails
// while an input check has failed, the error names that likely cause. Progress steps
// (IdentifySteps): each flight processed, the system built, the TLS solved. The flights are taken:
// their logs are released once processed and checked, before the system is built (the raw log of
// a 1 h flight is 60 MB beside the processed flight and W_t; pass std::move(flights)).
int IdentifySteps(const std::vector<FlightData>& flights);
IdentificationResult IdentifyWithChecks(std::vector<FlightData> flights, const IdentifyOptions& options,
                                        std::vector<Check>* checks, const StepProgress& progress = {});

}  // namespace rotorid

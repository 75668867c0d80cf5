#pragma once

// The identified model as a simulator (INTERFACE.md 6, MODEL.md 11): from every logged state of a
// flight, the model of a report is flown open loop over N steps with the logged rotor signal passed
// through the report's effects, and its error against the log is scored per step ahead h, beside the
// naive predictor x(t+h) = x(t) on the same windows.
//
//   PredictOptions options;
//   options.params_path = "refine.json";
//   options.vehicle_paths = {"v.yaml"};
//   options.log_paths = {"flight.csv"};
//   PredictResult result = RunPredict(options);
//   WriteJsonFile("predict.json", PredictJson(result));
//
// The physics is the simulator's (MultirotorDynamics: RK4, first moment and full inertia, the
// rotor-wrench effects), the rotor signal the refinement's (RotorSignalWithEffects: delay, motor
// lag, battery, command map), so the prediction flies exactly the model the report identified.

#include <Eigen/Core>
#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rotorid/ident/checks.h"
#include "rotorid/io/flight_selection.h"
#include "rotorid/io/flight_source.h"

namespace rotorid {

// The state groups scored (INTERFACE.md 6), in the order of the JSON keys.
enum class PredictionGroup { kPosition, kVelocity, kRotation, kAngularVelocity };
inline constexpr int kNumPredictionGroups = 4;
inline constexpr std::array<const char*, kNumPredictionGroups> kPredictionGroupNames = {"position", "velocity",
                                                                                        "rotation", "angular_velocity"};

// Which start instants count. kAirborne: a window counts when every grid sample in it is airborne
// (the ground-contact rule of PredictOptions); kWhole: every window inside the flight.
enum class PredictionScope { kAirborne, kWhole };
// "airborne" or "whole"; throws rotorid::Error otherwise.
PredictionScope ParsePredictionScope(const std::string& text);
const char* PredictionScopeName(PredictionScope scope);
// "NAME=VALUE" (a report parameter and a finite number); throws rotorid::Error otherwise.
std::pair<std::string, double> ParseParameterOverride(const std::string& text);

struct PredictOptions {
  // The identify or refine report whose model is flown.
  std::string params_path;
  // "linear", "refined", or "" for refined when the report has it, else linear.
  std::string block;
  // The flights, paired in order (INTERFACE.md 4): vehicle file, log, optional --window.
  std::vector<std::string> vehicle_paths;
  std::vector<std::string> log_paths;
  std::vector<std::optional<TimeWindow>> windows;  // empty, or one per log
  SegmentMode segment = SegmentMode::kAuto;
  FlightSourceOptions source;
  // Parameters replaced by outside values (a thrust stand's kd, a CAD inertia), by report name
  // ("kd", "<config>.I_zz"): for what a flight cannot fix. Written into the report.
  std::map<std::string, double> parameter_overrides;
  // Steps ahead N, start stride K, prediction grid (s).
  int horizon_steps = 50;
  int stride = 1;
  double dt_s = 0.01;
  PredictionScope scope = PredictionScope::kAirborne;
  // Ground-contact rule of the airborne scope: a sample is airborne when the rotors' thrust
  // kt sum Omega_i^2 carries at least this share of the weight, or, with a pose, when O_d is at least
  // this high above the lowest logged height of the whole log (or its `# ground_z:`).
  double ground_clearance_m = 0.05;
  double airborne_thrust_share = 0.5;
  // 0: the model flies open loop, as a simulator would. > 0: each window also carries a constant
  // body-frame torque bias, observed from the log over this many seconds before its start (the slope
  // of the gyro minus the model's integrated angular acceleration there): a state estimated from the
  // past, nothing after the start instant. Windows then need this much airborne past.
  double torque_bias_window_s = 0.0;
  // Threads over start instants (0: the machine's cores).
  int threads = 0;

  // Empty when valid, else what is wrong (a usage error).
  std::string Validate() const;
};

// MAE(h), h = 1..N, of the model and of the naive predictor, per group; a group the flights do not
// verify (position and velocity without a pose) has empty curves.
struct PredictionCurves {
  std::array<std::vector<double>, kNumPredictionGroups> mae, naive_mae;
  long windows = 0;
  bool Verified(PredictionGroup group) const { return !mae[static_cast<int>(group)].empty(); }
};

// The model's angular acceleration at the logged states against the body's (the corrected gyro,
// differentiated on the grid) in one frequency band, per body axis (roll, pitch, yaw). A horizon
// integrates the error: a torque the model lacks below 1 Hz stays through a window and grows the
// angular velocity error linearly with h, which the naive predictor does not.
struct TorqueBand {
  double low_hz = 0.0, high_hz = 0.0;  // [low, high); the last band ends at the grid's Nyquist frequency
  long samples = 0;                    // grid samples in the scope
  Eigen::Vector3d body_rms_radps2 = Eigen::Vector3d::Zero(), model_rms_radps2 = Eigen::Vector3d::Zero(),
                  error_rms_radps2 = Eigen::Vector3d::Zero();
  // Least-squares slope of the body's on the model's (1: the model's torque is the body's; 0: the body
  // does not follow it) and their correlation; not a number for the mean band (one value each).
  Eigen::Vector3d gain = Eigen::Vector3d::Zero(), correlation = Eigen::Vector3d::Zero();
  // The torque about O_d that the error is (N m), and for roll and pitch how far the centre of mass
  // would have to move in the rotor plane for the weight to exert it (mm; yaw: 0).
  Eigen::Vector3d error_torque_rms_nm = Eigen::Vector3d::Zero(), centre_of_mass_equivalent_mm = Eigen::Vector3d::Zero();
};

// "0-1 Hz", "1-3 Hz", "above 10 Hz": a band's name in the reports.
std::string TorqueBandName(const TorqueBand& band);

// The roll and pitch gains as "0.57 / 0.56", or "-" for the mean band.
std::string TorqueBandGainText(const TorqueBand& band);

// The band edges (Hz) of the torque comparison: 0-1, 1-3, 3-10 Hz and above, those below the grid's
// Nyquist frequency.
std::vector<double> TorqueBandEdges(double dt_s);

struct FlightPrediction {
  std::string file;
  PredictionCurves curves;
  std::vector<TorqueBand> torque_bands;
  // How the log's states were taken ("attitude, position from motion capture, velocity from ...").
  std::string states;
};

struct PredictResult {
  PredictOptions options;
  std::string block;  // the report block flown
  PredictionCurves pooled;
  std::vector<TorqueBand> torque_bands;   // over every flight
  std::vector<FlightPrediction> flights;  // one per log, in the order given
  std::vector<FlightInputSummary> inputs;
  std::vector<Check> checks;  // physical_consistency per configuration, windows in scope
};

PredictResult RunPredict(const PredictOptions& options);

// The "predict" report (INTERFACE.md 6): prediction.{horizon_steps, dt_s, scope, windows, mae,
// naive_mae, flights[]}, input, checks. docs/report_format.md lists the keys.
nlohmann::json PredictJson(const PredictResult& result);

// The answer first: how far ahead the model beats the naive predictor per group, and the bands up to
// 10 Hz in which the body does not follow the model's roll and pitch torque (gain outside 0.7-1.3).
std::string PredictAnswer(const PredictResult& result);

// For the console: the answer, what was flown, then per group the MAE of the model / naive at h = 1,
// 10, N, and the torque comparison by band.
std::string PredictBriefReport(const PredictResult& result);

// The HTML report: MAE(h) per group beside the naive curve (inline SVG), the table at h = 1, 10, N,
// per-flight tables and the checks; WritePredictReport writes it as DIR/predict.html and returns
// that path.
std::string PredictHtml(const PredictResult& result);
std::string WritePredictReport(const std::string& dir, const PredictResult& result);

// The steps at which flights[] and the console give the MAE: 1, 10, N (those <= N, no repeats).
std::vector<int> PredictionSummarySteps(int horizon_steps);

}  // namespace rotorid

#pragma once

// Internal: the states a log gives on the prediction grid, and the open-loop rollouts from them.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"
#include "rotorid/ident/observation.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/parameters.h"
#include "rotorid/predict/predict.h"
#include "rotorid/sim/dynamics.h"

namespace rotorid::internal {

// The model a report describes for one configuration: what the simulator's physics takes.
struct FlownModel {
  std::string source;  // the report's file, for messages
  std::string block;   // the report block it came from
  VehicleParameters parameters;
  Effects effects;
};

// The model of `vehicle`'s configuration from named parameter values ("kt", "kd", "<config>.I_xx",
// ...; a missing one is 0) and effects.
FlownModel FlownModelFromValues(const std::map<std::string, double>& values, const Effects& effects,
                                const Vehicle& vehicle);

// One flight's states on the uniform prediction grid t_k = t_s[0] + k dt.
struct LoggedStates {
  Eigen::VectorXd t_s;
  double dt_s = 0.0;
  double gravity_mps2 = 0.0;
  bool has_pose = false;                        // position and velocity verified (motion capture)
  Eigen::MatrixX3d position_w_m;                // O_d, world (zeros without a pose)
  Eigen::MatrixX3d velocity_w_mps;              // the log's velocity columns, else the differentiated position
  std::vector<Eigen::Quaterniond> attitude_wb;  // body to world; without a pose the integrated gyro
  Eigen::MatrixX3d angular_velocity_b_radps;    // the gyro corrected by the report's IMU effects
  Eigen::MatrixXd rotor_speed_radps;            // acting: the logged rotor signal through the rotor-signal effects
  std::vector<char> airborne;                   // the ground-contact rule per sample
  std::string description;                      // where each state came from, for the report

  int size() const { return static_cast<int>(t_s.size()); }
};

// Reads `log` (a segment of a whole log whose `# ground_z:` metadata is set when it has a pose) onto
// the prediction grid. `observation`: the report's signal processing (its low-pass differentiates the
// position, and the rotor-signal effects see the flight as the identification did).
LoggedStates ReadLoggedStates(const FlightLog& log, const Vehicle& vehicle, const FlownModel& model,
                              const ObservationOptions& observation, const PredictOptions& options);

// The body-frame torque about O_d that adds the angular acceleration b to the body of `parameters`
// and leaves the force unchanged (with a first moment it is not I b).
Eigen::Vector3d TorqueOfAngularAcceleration(const VehicleParameters& parameters, const Eigen::Vector3d& b);

// Sums over the grid samples in the scope of the body's (b) and the model's (m) angular
// acceleration in each band of TorqueBandEdges, per body axis; t: the error's torque, c: its
// centre-of-mass equivalent (TorqueBand).
struct TorqueBandSums {
  struct Band {
    long samples = 0;
    Eigen::Vector3d bb = Eigen::Vector3d::Zero(), mm = Eigen::Vector3d::Zero(), ee = Eigen::Vector3d::Zero(),
                    bm = Eigen::Vector3d::Zero(), tt = Eigen::Vector3d::Zero(), cc = Eigen::Vector3d::Zero();
  };
  std::vector<double> edges;  // band i is [edges[i], edges[i + 1]); the last ends at Nyquist
  std::vector<Band> bands;
  void Add(const TorqueBandSums& other);
  std::vector<TorqueBand> Mean() const;
};

// Sums of the errors over windows, per group and step ahead (index h - 1), and the number of
// windows that verify each group; the torque comparison over the samples in the scope.
struct ErrorSums {
  std::array<std::vector<double>, kNumPredictionGroups> model, naive;
  std::array<long, kNumPredictionGroups> windows = {0, 0, 0, 0};
  TorqueBandSums torque;
  explicit ErrorSums(int horizon_steps = 0, bool with_pose = false);
  void Add(const ErrorSums& other);
  PredictionCurves Mean() const;
};

// The model's angular acceleration at each logged state with the logged rotor signal: what the
// simulator's physics gives at the states of the log (one row per grid sample).
Eigen::MatrixX3d ModelAngularAccelerations(const LoggedStates& states, const MultirotorDynamics& dynamics,
                                           const MultirotorDynamics::RotorCommand& command);

// The body's angular acceleration (the gyro differentiated) against the model's, by band, over the
// samples in the scope; `parameters` turn the error into a torque.
TorqueBandSums CompareTorque(const LoggedStates& states, const VehicleParameters& parameters,
                             const Eigen::MatrixX3d& model_acceleration);

// Flies the model from every start k = 0, K, 2K, ... whose window k..k+N lies in the scope and adds
// the errors. Throws rotorid::Error when the model's body cannot be integrated.
ErrorSums ScoreFlight(const LoggedStates& states, const Vehicle& vehicle, const FlownModel& model,
                      const PredictOptions& options);

// ScoreFlight over the segments of a log; `states` (may be null) gets how the last one's states
// were read.
ErrorSums ScoreSegments(const std::vector<FlightLog>& segments, const Vehicle& vehicle, const FlownModel& model,
                        const ObservationOptions& observation, const PredictOptions& options, std::string* states);

}  // namespace rotorid::internal

#pragma once

// The identification pipeline: flights -> processed signals -> IDIM system -> TLS, with the
// checks a user needs (excitation, scale, systematic force errors) and the paper's Table III.

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/step_progress.h"
#include "rotorid/core/vehicle.h"
#include "rotorid/ident/observation.h"
#include "rotorid/ident/tls.h"

namespace rotorid {

// One flight with its vehicle and its weight in a multi-configuration identification.
struct FlightData {
  Vehicle vehicle;
  FlightLog log;
  double weight = 1.0;
  // Which log the flight was cut from: the segments of one log are one flight for per-flight first
  // moments (-1: a log of its own).
  int log_index = -1;
};

// Whether the flights of one configuration share its first moment (the paper) or each flight
// (each log) has its own, `<config>.flight<k>.ms_x` with k from 1 in the order given: the battery
// moves between flights, the rest of the body and the propellers do not.
enum class FirstMoment { kShared, kPerFlight };
const char* FirstMomentName(FirstMoment mode);
FirstMoment ParseFirstMoment(const std::string& name);

struct IdentifyOptions {
  ObservationOptions observation;
  TlsOptions tls;
  FirstMoment first_moment = FirstMoment::kShared;
  // Accept results in which a configuration's I_xx or I_yy is not identifiable.
  bool allow_partial = false;

  std::string Validate() const;
};

// How much a flight excites what the identification needs.
struct Excitation {
  Eigen::Vector3d angular_acceleration_rms = Eigen::Vector3d::Zero();  // rad/s^2, of w'
  Eigen::Vector3d angular_velocity_rms = Eigen::Vector3d::Zero();      // rad/s
  double thrust_variation_pct = 0.0;  // std / mean of sum Omega^2
};

struct FlightFit {
  std::string source;
  std::string config;
  double weight = 1.0;
  int samples = 0;
  int row_samples = 0;
  double duration_s = 0.0;
  Excitation excitation;
  std::vector<std::optional<double>> relative_error_pct;  // per component
  Eigen::Vector3d mean_force_residual_n = Eigen::Vector3d::Zero();  // Fx, Fy, Fz
};

struct IdentificationResult {
  IdentifyOptions options;  // as used
  std::vector<ProcessedFlight> flights;
  IdimSystem system;
  TlsSolution solution;
  std::vector<std::optional<double>> relative_error_pct;  // all flights together
  std::vector<FlightFit> per_flight;
  std::vector<std::string> warnings;

  // chi_t = [chi; 1] of the solution.
  Eigen::VectorXd ChiT() const;
};

// Progress steps: one per flight processed.
std::vector<ProcessedFlight> ProcessFlights(const std::vector<FlightData>& flights, const ObservationOptions& options,
                                            const StepProgress& progress = {});
Excitation MeasureExcitation(const ProcessedFlight& flight);

// Throws rotorid::Error when the result is not usable (scale lost, kt not identifiable, or a
// configuration's roll/pitch inertia not identifiable without allow_partial), with a message that
// names what and where.
IdentificationResult Identify(const std::vector<FlightData>& flights, const IdentifyOptions& options);
// Progress steps of IdentifyProcessed: the system built, then the TLS solved.
IdentificationResult IdentifyProcessed(std::vector<ProcessedFlight> flights, const IdentifyOptions& options,
                                       const StepProgress& progress = {});

// Sets each flight's first_moment_label: none when shared; per flight, "flight<k>" with k counting the
// logs (log_index; a flight without one counts as a log of its own) of its configuration from 1.
void LabelFirstMoments(FirstMoment mode, std::vector<ProcessedFlight>* flights);

// The configurations (vehicle names) of `flights`, in the order the flights first name them.
std::vector<std::string> ConfigurationNames(const std::vector<ProcessedFlight>& flights);

// Per-flight fit (Table III per flight, mean force residuals) of parameters on processed flights.
// `parameters` maps names ("kt", "kd", "<config>.<name>") to values; missing body parameters of a
// flight's configuration are an error.
FlightFit FitFlight(const ProcessedFlight& flight, const std::map<std::string, double>& parameters);

// Table III over several flights together.
std::vector<std::optional<double>> CombinedRelativeErrorPct(const std::vector<ProcessedFlight>& flights,
                                                            const std::map<std::string, double>& parameters);

// The 12-entry chi_t of one flight from named parameters (its configuration's, and its own first
// moment when it has a label).
Eigen::VectorXd FlightChiT(const ProcessedFlight& flight, const std::map<std::string, double>& parameters);

// The owners ("<config>.<label>", e.g. "A.flight2") of a configuration's own first moments
// ("<owner>.ms_x", ms_y, ms_z) among parameter names, in the order of `names`.
std::vector<std::string> OwnFirstMomentOwners(const std::string& config, const std::vector<std::string>& names);

// Parameters identified with per-flight first moments say nothing about the first moment of a flight
// they were not identified on (the battery sits elsewhere). For each flight of such a configuration,
// this labels it "held_out<k>" (k from 1 per configuration, in order) and adds its first moment to
// `parameters`: fitted on its rows (`rows`, default BuildIdimMatrix) by linear least squares with
// every other parameter fixed, each wrench component weighted by the inverse variance of its residual
// (at the mean first moment of the identified flights, then once more at the fit). Flights of
// configurations with a shared first moment are left as they are. Returns the names it added.
std::vector<std::string> FitHeldOutFirstMoments(
    std::vector<ProcessedFlight>* flights, std::map<std::string, double>* parameters,
    const std::function<Eigen::MatrixXd(const ProcessedFlight&)>& rows = BuildIdimMatrix);

}  // namespace rotorid

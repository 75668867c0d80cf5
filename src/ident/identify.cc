#include "rotorid/ident/identify.h"

#include <cmath>
#include <cstdio>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/model/parameters.h"
#include "rotorid/model/rigid_body.h"

namespace rotorid {

std::string IdentifyOptions::Validate() const {
  if (std::string p = observation.Validate(); !p.empty()) return p;
  return tls.Validate();
}

Eigen::VectorXd IdentificationResult::ChiT() const {
  Eigen::VectorXd chi_t(solution.chi.size() + 1);
  chi_t << solution.chi, 1.0;
  return chi_t;
}

std::vector<ProcessedFlight> ProcessFlights(const std::vector<FlightData>& flights, const ObservationOptions& options,
                                            const StepProgress& progress) {
  std::vector<ProcessedFlight> out;
  out.reserve(flights.size());
  for (const FlightData& f : flights) {
    out.push_back(ProcessFlight(f.log, f.vehicle, f.weight, options));
    if (progress) progress(static_cast<int>(out.size()), static_cast<int>(flights.size()));
  }
  return out;
}

Excitation MeasureExcitation(const ProcessedFlight& flight) {
  Excitation e;
  const int n = flight.num_rows_samples();
  if (n == 0) return e;
  Eigen::VectorXd thrust(n);
  for (int r = 0; r < n; ++r) {
    const int i = flight.row_samples[r];
    e.angular_acceleration_rms += flight.angular_acceleration.row(i).transpose().cwiseAbs2();
    e.angular_velocity_rms += flight.angular_velocity.row(i).transpose().cwiseAbs2();
    thrust[r] = flight.rotor.row(i).squaredNorm();
  }
  e.angular_acceleration_rms = (e.angular_acceleration_rms / n).cwiseSqrt();
  e.angular_velocity_rms = (e.angular_velocity_rms / n).cwiseSqrt();
  const double mean = thrust.mean();
  if (mean > 0.0) e.thrust_variation_pct = 100.0 * std::sqrt((thrust.array() - mean).square().mean()) / mean;
  return e;
}

Eigen::VectorXd FlightChiT(const Vehicle& vehicle, const std::map<std::string, double>& parameters) {
  Eigen::VectorXd chi_t(kNumIdimColumns);
  auto get = [&](const std::string& name) {
    const auto it = parameters.find(name);
    if (it == parameters.end()) throw Error("no value for parameter '" + name + "'");
    return it->second;
  };
  chi_t[0] = get("kt");
  chi_t[1] = get("kd");
  for (int k = 0; k < kNumBodyParameters; ++k) chi_t[2 + k] = get(vehicle.name + "." + kBodyParameterNames[k]);
  chi_t[kNumIdimColumns - 1] = 1.0;
  return chi_t;
}

FlightFit FitFlight(const ProcessedFlight& flight, const std::map<std::string, double>& parameters) {
  FlightFit fit;
  fit.source = flight.source;
  fit.config = flight.vehicle.name;
  fit.weight = flight.weight;
  fit.samples = static_cast<int>(flight.t_s.size());
  fit.row_samples = flight.num_rows_samples();
  fit.duration_s = flight.t_s.size() > 1 ? flight.t_s[flight.t_s.size() - 1] - flight.t_s[0] : 0.0;
  fit.excitation = MeasureExcitation(flight);
  const Eigen::MatrixXd w = BuildIdimMatrix(flight);
  const Eigen::VectorXd chi_t = FlightChiT(flight.vehicle, parameters);
  fit.relative_error_pct = RelativeErrorPct(w, chi_t);
  const Eigen::VectorXd rho = w * chi_t;
  for (Eigen::Index i = 0; i < rho.size(); ++i)
    if (i % 6 < 3) fit.mean_force_residual_n[i % 6] += rho[i];
  if (fit.row_samples > 0) fit.mean_force_residual_n /= fit.row_samples;
  return fit;
}

std::vector<std::optional<double>> CombinedRelativeErrorPct(const std::vector<ProcessedFlight>& flights,
                                                            const std::map<std::string, double>& parameters) {
  int rows = 0;
  for (const ProcessedFlight& f : flights) rows += 6 * f.num_rows_samples();
  // Each flight's rows are scaled so that sum over flights of ||rho||^2 and ||W_k chi_k||^2 add up.
  Eigen::MatrixXd stacked(rows, kNumIdimColumns);
  Eigen::VectorXd residual_rows(rows);
  int row = 0;
  for (const ProcessedFlight& f : flights) {
    const Eigen::MatrixXd w = BuildIdimMatrix(f);
    const Eigen::VectorXd chi_t = FlightChiT(f.vehicle, parameters);
    // Store rho in column 11 and the rotor wrench in column 0 with unit coefficients.
    for (Eigen::Index i = 0; i < w.rows(); ++i) {
      stacked.row(row + i).setZero();
      stacked(row + i, 0) = w(i, 0) * chi_t[0] + w(i, 1) * chi_t[1];
      stacked(row + i, kNumIdimColumns - 1) = w.row(i).dot(chi_t) - stacked(row + i, 0);
    }
    row += static_cast<int>(w.rows());
  }
  Eigen::VectorXd unit = Eigen::VectorXd::Zero(kNumIdimColumns);
  unit[0] = 1.0;
  unit[kNumIdimColumns - 1] = 1.0;
  return RelativeErrorPct(stacked, unit);
}

namespace {

std::map<std::string, double> NamedValues(const IdimSystem& system, const Eigen::VectorXd& chi) {
  std::map<std::string, double> values;
  for (int k = 0; k < system.num_parameters(); ++k) values[system.parameter_names[k]] = chi[k];
  return values;
}

}  // namespace

IdentificationResult IdentifyProcessed(std::vector<ProcessedFlight> flights, const IdentifyOptions& options,
                                       const StepProgress& progress) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  IdentificationResult result;
  result.options = options;
  result.flights = std::move(flights);
  result.system = BuildIdimSystem(result.flights);
  if (progress) progress(1, 2);
  result.solution = SolveIdim(result.system, options.tls);
  if (progress) progress(2, 2);
  const TlsSolution& solution = result.solution;
  if (!solution.usable) {
    std::string sources;
    for (const std::string& s : result.system.flight_source) sources += (sources.empty() ? "" : ", ") + s;
    throw Error(sources + ": " + solution.message);
  }
  const std::map<std::string, double> values = NamedValues(result.system, solution.chi);
  result.relative_error_pct = CombinedRelativeErrorPct(result.flights, values);
  for (const ProcessedFlight& f : result.flights) result.per_flight.push_back(FitFlight(f, values));
  result.warnings = solution.warnings;

  for (const FlightFit& fit : result.per_flight) {
    // The model has no rotor force along x or y: a mean Fx/Fy residual above 1 % of the weight is
    // a systematic force error (accelerometer bias or IMU misalignment), not noise.
    const double mass = result.flights[&fit - &result.per_flight[0]].vehicle.mass_kg;
    const double g = result.flights[&fit - &result.per_flight[0]].gravity_mps2;
    for (int a = 0; a < 2; ++a) {
      const double mean = fit.mean_force_residual_n[a];
      if (std::abs(mean) > 0.01 * mass * g) {
        result.warnings.push_back(fit.source + ": systematic force error in " + kWrenchComponentNames[a] +
                                  ": mean residual " + ShortNumber(mean) + " N (" + ShortNumber(mean / mass) +
                                  " m/s^2 times the mass). The model has no rotor force along this axis, so this "
                                  "points to an accelerometer bias or an IMU misalignment; kt is biased by about "
                                  "the same fraction of g. Try `rotorid refine --effects acc_bias,misalignment`.");
      }
    }
  }
  // Parameters the flights leave unidentifiable, named with the excitation that is missing.
  std::string missing;
  for (size_t c = 0; c < result.system.config_names.size(); ++c) {
    const std::string& config = result.system.config_names[c];
    for (int axis = 0; axis < 2; ++axis) {
      const int k = IdimSystem::ConfigColumn(static_cast<int>(c)) + 3 + axis;
      if (solution.essential[k]) continue;
      double rms = 0.0;
      for (const FlightFit& fit : result.per_flight)
        if (fit.config == config) rms = std::max(rms, fit.excitation.angular_acceleration_rms[axis]);
      missing += (missing.empty() ? "" : "; ") + result.system.parameter_names[k] +
                 " (RMS angular acceleration about " + (axis == 0 ? "x" : "y") + " " + ShortNumber(rms) + " rad/s^2)";
    }
  }
  if (!missing.empty()) {
    const std::string message =
        "not identifiable from these flights: " + missing + ". Fly more roll and pitch manoeuvres (docs/tutorial.md)";
    if (!options.allow_partial) throw Error(message + ", or pass --allow-partial to accept a partial result");
    result.warnings.push_back(message);
  }
  return result;
}

IdentificationResult Identify(const std::vector<FlightData>& flights, const IdentifyOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  return IdentifyProcessed(ProcessFlights(flights, options.observation), options);
}

}  // namespace rotorid

#include "rotorid/ident/identify.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/ident/body_consistency.h"
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

const char* FirstMomentName(FirstMoment mode) { return mode == FirstMoment::kShared ? "shared" : "per-flight"; }

FirstMoment ParseFirstMoment(const std::string& name) {
  if (name == "shared") return FirstMoment::kShared;
  if (name == "per-flight") return FirstMoment::kPerFlight;
  throw Error("unknown first-moment mode '" + name + "'; use 'shared' (default) or 'per-flight'");
}

std::vector<ProcessedFlight> ProcessFlights(const std::vector<FlightData>& flights, const ObservationOptions& options,
                                            const StepProgress& progress) {
  std::vector<ProcessedFlight> out;
  out.reserve(flights.size());
  for (const FlightData& f : flights) {
    out.push_back(ProcessFlight(f.log, f.vehicle, f.weight, options));
    out.back().log_index = f.log_index;
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

void LabelFirstMoments(FirstMoment mode, std::vector<ProcessedFlight>* flights) {
  std::map<std::string, std::map<int, int>> number;  // per configuration: log -> k
  std::map<std::string, int> unindexed;              // per configuration: logs without an index
  for (ProcessedFlight& f : *flights) {
    f.first_moment_label.clear();
    if (mode == FirstMoment::kShared) continue;
    std::map<int, int>& logs = number[f.vehicle.name];
    // Flights without a log index get negative keys of their own, after the ones seen so far.
    const int log = f.log_index >= 0 ? f.log_index : -1 - unindexed[f.vehicle.name]++;
    const int k = logs.emplace(log, static_cast<int>(logs.size()) + 1).first->second;
    f.first_moment_label = "flight" + std::to_string(k);
  }
}

std::vector<std::string> ConfigurationNames(const std::vector<ProcessedFlight>& flights) {
  std::vector<std::string> names;
  for (const ProcessedFlight& f : flights)
    if (std::find(names.begin(), names.end(), f.vehicle.name) == names.end()) names.push_back(f.vehicle.name);
  return names;
}

Eigen::VectorXd FlightChiT(const ProcessedFlight& flight, const std::map<std::string, double>& parameters) {
  Eigen::VectorXd chi_t(kNumIdimColumns);
  auto get = [&](const std::string& name) {
    const auto it = parameters.find(name);
    if (it == parameters.end()) throw Error("no value for parameter '" + name + "'");
    return it->second;
  };
  chi_t[0] = get("kt");
  chi_t[1] = get("kd");
  for (int k = 0; k < kNumBodyParameters; ++k) chi_t[2 + k] = get(BodyParameterName(flight, k));
  chi_t[kNumIdimColumns - 1] = 1.0;
  return chi_t;
}

std::vector<std::string> OwnFirstMomentOwners(const std::string& config, const std::vector<std::string>& names) {
  std::vector<std::string> owners;
  const std::string prefix = config + ".", suffix = ".ms_x";
  for (const std::string& name : names)
    if (name.size() > prefix.size() + suffix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
      owners.push_back(name.substr(0, name.size() - suffix.size()));
  return owners;
}

std::vector<std::string> FitHeldOutFirstMoments(std::vector<ProcessedFlight>* flights,
                                                std::map<std::string, double>* parameters,
                                                const std::function<Eigen::MatrixXd(const ProcessedFlight&)>& rows) {
  std::vector<std::string> added;
  const std::map<std::string, double> identified = *parameters;
  std::map<std::string, int> count;
  for (ProcessedFlight& f : *flights) {
    f.first_moment_label.clear();
    const std::string& config = f.vehicle.name;
    if (identified.count(config + ".ms_x")) continue;
    std::vector<std::string> names;
    for (const auto& entry : identified) names.push_back(entry.first);
    const std::vector<std::string> owners = OwnFirstMomentOwners(config, names);
    if (owners.empty()) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const std::string& owner : owners)
      for (int a = 0; a < 3; ++a) mean[a] += identified.at(owner + "." + kBodyParameterNames[a]) / owners.size();
    f.first_moment_label = "held_out" + std::to_string(++count[config]);
    for (int a = 0; a < 3; ++a) {
      added.push_back(BodyParameterName(f, a));
      (*parameters)[added.back()] = mean[a];
    }
    const Eigen::MatrixXd w = rows(f);
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::VectorXd rho = w * FlightChiT(f, *parameters);
      Eigen::Matrix<double, 6, 1> inverse_variance = Eigen::Matrix<double, 6, 1>::Zero();
      for (Eigen::Index i = 0; i < rho.size(); ++i) inverse_variance[i % 6] += rho[i] * rho[i];
      for (int j = 0; j < 6; ++j)
        inverse_variance[j] = inverse_variance[j] > 0.0 ? (rho.size() / 6) / inverse_variance[j] : 0.0;
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
      for (Eigen::Index i = 0; i < rho.size(); ++i) {
        const Eigen::Vector3d column = w.row(i).segment<3>(kNumRotorCoefficients).transpose();
        normal += inverse_variance[i % 6] * column * column.transpose();
        gradient += inverse_variance[i % 6] * column * rho[i];
      }
      const Eigen::Vector3d step = -normal.ldlt().solve(gradient);
      if (!step.allFinite()) throw Error(f.source + ": its first moment cannot be fitted (no excitation)");
      for (int a = 0; a < 3; ++a) (*parameters)[BodyParameterName(f, a)] += step[a];
    }
  }
  return added;
}

namespace {

// The residual sums of one flight, one row sample at a time: W (about 100 MB for an hour at 200 Hz)
// is never held, and the whole system's W is still alive when the flights are scored.
struct FlightResidualSums {
  RelativeErrorSums relative;
  Eigen::Vector3d force_sum = Eigen::Vector3d::Zero();  // sum of the Fx, Fy, Fz residuals
};

FlightResidualSums ResidualSums(const ProcessedFlight& flight, const std::map<std::string, double>& parameters) {
  const Eigen::VectorXd chi_t = FlightChiT(flight, parameters);
  FlightResidualSums sums;
  for (int r = 0; r < flight.num_rows_samples(); ++r) {
    const Eigen::Matrix<double, 6, kNumIdimColumns> w = IdimRowsOfRowSample(flight, r);
    sums.relative.Add(w, chi_t);
    for (int a = 0; a < 3; ++a) sums.force_sum[a] += w.row(a).dot(chi_t);
  }
  return sums;
}

FlightFit FitFlight(const ProcessedFlight& flight, const FlightResidualSums& sums) {
  FlightFit fit;
  fit.source = flight.source;
  fit.config = flight.vehicle.name;
  fit.weight = flight.weight;
  fit.samples = static_cast<int>(flight.t_s.size());
  fit.row_samples = flight.num_rows_samples();
  fit.duration_s = flight.t_s.size() > 1 ? flight.t_s[flight.t_s.size() - 1] - flight.t_s[0] : 0.0;
  fit.excitation = MeasureExcitation(flight);
  fit.relative_error_pct = sums.relative.Pct();
  if (fit.row_samples > 0) fit.mean_force_residual_n = sums.force_sum / fit.row_samples;
  return fit;
}

}  // namespace

FlightFit FitFlight(const ProcessedFlight& flight, const std::map<std::string, double>& parameters) {
  return FitFlight(flight, ResidualSums(flight, parameters));
}

std::vector<std::optional<double>> CombinedRelativeErrorPct(const std::vector<ProcessedFlight>& flights,
                                                            const std::map<std::string, double>& parameters) {
  RelativeErrorSums sums;  // of ||rho||^2 and ||W_k chi_k||^2 over the flights
  for (const ProcessedFlight& f : flights) sums.Add(ResidualSums(f, parameters).relative);
  return sums.Pct();
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
  LabelFirstMoments(options.first_moment, &result.flights);
  result.system = BuildIdimSystem(result.flights);
  if (progress) progress(1, 2);
  result.solution = SolveIdim(result.system, options.tls);
  SetAllowedRanges(result.system, ConfigurationMasses(result.flights), &result.solution);
  if (progress) progress(2, 2);
  const TlsSolution& solution = result.solution;
  if (!solution.usable) {
    std::string sources;
    for (const std::string& s : result.system.flight_source) sources += (sources.empty() ? "" : ", ") + s;
    throw Error(sources + ": " + solution.message);
  }
  const std::map<std::string, double> values = NamedValues(result.system, PredictionChi(solution));
  RelativeErrorSums all_flights;
  for (const ProcessedFlight& f : result.flights) {
    const FlightResidualSums sums = ResidualSums(f, values);
    all_flights.Add(sums.relative);
    result.per_flight.push_back(FitFlight(f, sums));
  }
  result.relative_error_pct = all_flights.Pct();
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
  // Without kd the yaw equation has no rotor term: Mz leaves Table III and the diagnosis's score,
  // and with it every effect that acts on the yaw moment.
  if (const int kd = result.system.Column("kd"); kd >= 0 && !solution.essential[kd] &&
                                                 std::find(options.tls.fixed_zero.begin(), options.tls.fixed_zero.end(),
                                                           "kd") == options.tls.fixed_zero.end()) {
    double yaw_rms = 0.0;
    for (const FlightFit& fit : result.per_flight)
      yaw_rms = std::max(yaw_rms, fit.excitation.angular_acceleration_rms[2]);
    result.warnings.push_back(
        "kd is not identified (" + ShortNumber(solution.rel_std_pct[kd]) +
        " % std; RMS angular acceleration about z " + ShortNumber(yaw_rms) +
        " rad/s^2): Mz has no rotor term, so it is left out of Table III and of the diagnosis's held-out score. "
        "Either the flights' yaw does not fix the yaw equation (fly yaw manoeuvres) or an unmodelled effect blurs "
        "it (a rotor-speed delay or lag, a rotor inertia); `rotorid diagnose` names the candidates it cannot test "
        "there");
  }
  // Parameters the flights leave unidentifiable, named with the excitation that is missing.
  std::string missing;
  for (size_t c = 0; c < result.system.config_names.size(); ++c) {
    const std::string& config = result.system.config_names[c];
    for (int axis = 0; axis < 2; ++axis) {
      const int k = result.system.Column(config + "." + kBodyParameterNames[3 + axis]);
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

// The model's angular acceleration against the body's by frequency band (TorqueBand): where the
// torque the model computes from the rotor signal is the one the body feels.

#include <algorithm>
#include <cmath>

#include "predict/rollout.h"
#include "rotorid/core/text.h"
#include "rotorid/signal/butterworth.h"
#include "rotorid/signal/differentiate.h"

namespace rotorid {

std::vector<double> TorqueBandEdges(double dt_s) {
  // A band edge needs its low-pass below the Nyquist frequency, with room for the band above it.
  // The first band, [0, 0), is the flight's mean: a constant torque error (a centre of mass that
  // moved between flights) apart from what varies below 1 Hz.
  std::vector<double> edges = {0.0, 0.0};
  for (double edge : {1.0, 3.0, 10.0})
    if (edge < 0.4 / dt_s) edges.push_back(edge);
  return edges;
}

std::string TorqueBandName(const TorqueBand& band) {
  if (band.high_hz == 0.0) return "mean";
  if (!std::isfinite(band.high_hz))
    return band.low_hz > 0.0 ? "above " + ShortNumber(band.low_hz) + " Hz" : "all but the mean";  // a coarse grid
  return ShortNumber(band.low_hz) + "-" + ShortNumber(band.high_hz) + " Hz";
}

std::string TorqueBandGainText(const TorqueBand& band) {
  if (!std::isfinite(band.gain[0])) return "-";
  return FormatValue("%.2f", band.gain[0]) + " / " + FormatValue("%.2f", band.gain[1]);
}

namespace internal {

void TorqueBandSums::Add(const TorqueBandSums& other) {
  if (other.bands.empty()) return;
  if (bands.empty()) {
    *this = other;
    return;
  }
  for (size_t i = 0; i < bands.size(); ++i) {
    Band& b = bands[i];
    const Band& o = other.bands[i];
    b.samples += o.samples;
    b.bb += o.bb, b.mm += o.mm, b.ee += o.ee, b.bm += o.bm, b.tt += o.tt, b.cc += o.cc;
  }
}

std::vector<TorqueBand> TorqueBandSums::Mean() const {
  std::vector<TorqueBand> out;
  for (size_t i = 0; i < bands.size(); ++i) {
    const Band& b = bands[i];
    if (b.samples == 0) continue;
    TorqueBand band;
    band.low_hz = edges[i];
    band.high_hz = i + 1 < edges.size() ? edges[i + 1] : HUGE_VAL;
    band.samples = b.samples;
    const double n = static_cast<double>(b.samples);
    band.body_rms_radps2 = (b.bb / n).cwiseSqrt();
    band.model_rms_radps2 = (b.mm / n).cwiseSqrt();
    band.error_rms_radps2 = (b.ee / n).cwiseSqrt();
    for (int a = 0; a < 3; ++a) {
      band.gain[a] = b.mm[a] > 0.0 && band.high_hz > 0.0 ? b.bm[a] / b.mm[a] : NAN;
      band.correlation[a] = std::isfinite(band.gain[a]) && b.bb[a] > 0.0 ? b.bm[a] / std::sqrt(b.mm[a] * b.bb[a]) : NAN;
    }
    band.error_torque_rms_nm = (b.tt / n).cwiseSqrt();
    band.centre_of_mass_equivalent_mm = 1e3 * (b.cc / n).cwiseSqrt();
    out.push_back(band);
  }
  return out;
}

TorqueBandSums CompareTorque(const LoggedStates& states, const VehicleParameters& parameters,
                             const Eigen::MatrixX3d& model_acceleration) {
  TorqueBandSums sums;
  sums.edges = TorqueBandEdges(states.dt_s);
  sums.bands.resize(sums.edges.size());
  if (states.size() < 3) return sums;
  const Eigen::MatrixXd body = FourthOrderCentralDifference(states.angular_velocity_b_radps, states.dt_s);
  const Eigen::MatrixXd model = model_acceleration;
  // The mean over the samples in the scope, then zero-phase low-passes at each edge; band i is the
  // difference of neighbouring ones, so the bands add up to the whole signal.
  const auto mean_in_scope = [&states](const Eigen::MatrixXd& x) {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    long n = 0;
    for (int k = 0; k < states.size(); ++k)
      if (states.airborne[k]) sum += x.row(k), ++n;
    return Eigen::MatrixXd(Eigen::MatrixXd::Ones(x.rows(), 1) * (sum / std::max(n, 1L)));
  };
  std::vector<Eigen::MatrixXd> body_low = {Eigen::MatrixXd::Zero(body.rows(), 3), mean_in_scope(body)};
  std::vector<Eigen::MatrixXd> model_low = {body_low[0], mean_in_scope(model)};
  for (size_t i = 2; i < sums.edges.size(); ++i) {
    const SosFilter filter = DesignButterworth({2, FilterBand::kLowPass, sums.edges[i], 0.0}, 1.0 / states.dt_s);
    body_low.push_back(FiltFiltColumns(filter, body));
    model_low.push_back(FiltFiltColumns(filter, model));
  }
  body_low.push_back(body);
  model_low.push_back(model);
  const double weight_n = parameters.mass_kg * states.gravity_mps2;
  for (size_t i = 0; i < sums.bands.size(); ++i) {
    TorqueBandSums::Band& band = sums.bands[i];
    for (int k = 0; k < states.size(); ++k) {
      if (!states.airborne[k]) continue;
      const Eigen::Vector3d b = (body_low[i + 1].row(k) - body_low[i].row(k)).transpose();
      const Eigen::Vector3d m = (model_low[i + 1].row(k) - model_low[i].row(k)).transpose();
      const Eigen::Vector3d torque = TorqueOfAngularAcceleration(parameters, b - m);
      band.samples += 1;
      band.bb += b.cwiseAbs2(), band.mm += m.cwiseAbs2(), band.ee += (b - m).cwiseAbs2();
      band.bm += b.cwiseProduct(m), band.tt += torque.cwiseAbs2();
      const Eigen::Vector3d shift(torque.x() / weight_n, torque.y() / weight_n, 0.0);
      band.cc += shift.cwiseAbs2();
    }
  }
  return sums;
}

}  // namespace internal
}  // namespace rotorid

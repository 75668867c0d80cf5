#include "rotorid/refine/motor_response.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "rotorid/core/error.h"
#include "rotorid/ident/observation.h"
#include "rotorid/refine/effect_model.h"
#include "rotorid/signal/resample.h"

namespace rotorid {
namespace {

struct Fit {
  double sum_sq = std::numeric_limits<double>::infinity();
  Eigen::Vector3d map = Eigen::Vector3d::Zero();
};

// Least squares of speed on [1, y, y^2] over rows [begin, end) of every rotor.
Fit FitStaticMap(const Eigen::MatrixXd& y, const Eigen::MatrixXd& speed, Eigen::Index begin, Eigen::Index end) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double speed_sq = 0.0;
  for (Eigen::Index r = 0; r < y.cols(); ++r) {
    for (Eigen::Index k = begin; k < end; ++k) {
      const Eigen::Vector3d basis(1.0, y(k, r), y(k, r) * y(k, r));
      normal.noalias() += basis * basis.transpose();
      rhs.noalias() += basis * speed(k, r);
      speed_sq += speed(k, r) * speed(k, r);
    }
  }
  Fit fit;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return fit;
  fit.map = ldlt.solve(rhs);
  fit.sum_sq = std::max(speed_sq - fit.map.dot(rhs), 0.0);
  return fit;
}

}  // namespace

std::string MotorResponseOptions::Validate() const {
  if (!(min_delay_s < max_delay_s)) return "motor response: min_delay_s must be below max_delay_s";
  if (!(max_tau_s > 0.0)) return "motor response: max_tau_s must be positive";
  if (!(edge_s >= 0.0)) return "motor response: edge_s must not be negative";
  return "";
}

MotorResponse EstimateMotorResponse(const Eigen::VectorXd& t_s, const Eigen::MatrixXd& command,
                                    const Eigen::MatrixXd& speed, const MotorResponseOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  const Eigen::Index n = t_s.size();
  if (command.rows() != n || speed.rows() != n || command.cols() != speed.cols() || command.cols() == 0)
    throw Error("motor response: command (" + std::to_string(command.rows()) + " x " + std::to_string(command.cols()) +
                ") and speed (" + std::to_string(speed.rows()) + " x " + std::to_string(speed.cols()) +
                ") must have one row per time and the same rotors");
  if (!command.allFinite() || !speed.allFinite()) throw Error("motor response: command or speed is not finite");
  if (n < 3) throw Error("motor response: too few samples");
  Eigen::VectorXd dts = t_s.tail(n - 1) - t_s.head(n - 1);
  if (!(dts.minCoeff() > 0.0)) throw Error("motor response: time must increase");
  std::nth_element(dts.data(), dts.data() + dts.size() / 2, dts.data() + dts.size());
  const double dt = dts[dts.size() / 2];

  // Both signals on one uniform base; the command carried in a ProcessedFlight so that the delay and
  // lag are applied by exactly the refinement's model.
  ProcessedFlight commanded;
  commanded.dt_s = dt;
  const Eigen::VectorXd base = UniformTimeBase(t_s[0], t_s[n - 1], 1.0 / dt);
  commanded.rotor_raw = InterpolateLinear(t_s, command, base);
  const Eigen::MatrixXd measured = InterpolateLinear(t_s, speed, base);
  const Eigen::Index m = base.size();
  const auto edge = static_cast<Eigen::Index>(
      std::ceil((options.edge_s + std::max(std::abs(options.min_delay_s), std::abs(options.max_delay_s))) / dt));
  if (m <= 2 * edge + 10) throw Error("motor response: the log is too short for the delays searched");

  const EffectKind delay_effect = ParseEffectKind("delay"), lag_effect = ParseEffectKind("motor_lag");
  auto evaluate = [&](double delay, double tau) {
    Effects effects;
    effects.Set(delay_effect, delay);
    effects.Set(lag_effect, tau);
    const Eigen::MatrixXd y = RotorSignalWithEffects(commanded, effects).array().square().sqrt().matrix();
    return FitStaticMap(y, measured, edge, m - edge);
  };
  // Coarse grid over the whole range, then finer grids around the best point.
  double best_delay = 0.0, best_tau = 0.0;
  Fit best;
  double delay_step = std::max(dt, (options.max_delay_s - options.min_delay_s) / 50.0);
  double tau_step = options.max_tau_s / 40.0;
  double delay_lo = options.min_delay_s, delay_hi = options.max_delay_s, tau_lo = 0.0, tau_hi = options.max_tau_s;
  for (int level = 0; level < 4; ++level) {
    for (double delay = delay_lo; delay <= delay_hi + 1e-12; delay += delay_step) {
      for (double tau = tau_lo; tau <= tau_hi + 1e-12; tau += tau_step) {
        const Fit fit = evaluate(delay, tau);
        if (fit.sum_sq < best.sum_sq) {
          best = fit;
          best_delay = delay;
          best_tau = tau;
        }
      }
    }
    delay_lo = std::max(options.min_delay_s, best_delay - 2 * delay_step);
    delay_hi = std::min(options.max_delay_s, best_delay + 2 * delay_step);
    tau_lo = std::max(0.0, best_tau - 2 * tau_step);
    tau_hi = std::min(options.max_tau_s, best_tau + 2 * tau_step);
    delay_step /= 5.0;
    tau_step /= 5.0;
  }

  MotorResponse out;
  out.delay_s = best_delay;
  out.motor_tau_s = best_tau;
  out.static_map = best.map;
  out.samples = static_cast<int>((m - 2 * edge) * speed.cols());
  out.residual_rms = std::sqrt(best.sum_sq / out.samples);
  const Eigen::MatrixXd used = measured.middleRows(edge, m - 2 * edge);
  const double mean = used.mean();
  const double variance = (used.array() - mean).square().mean();
  out.explained_pct = variance > 0.0 ? 100.0 * (1.0 - out.residual_rms * out.residual_rms / variance) : 0.0;
  return out;
}

}  // namespace rotorid

#pragma once

// Where the model's residual lies (MODEL.md section 5, question 1), on the identification data:
// per frequency band (residual amplitude spectrum against the rotor-model wrench's), per stretch of
// the flight (windowed error, the worst windows named with their times and what the vehicle was
// doing), and the residual's correlation with the signature of each candidate effect, i.e. the
// derivative of the residual rho = W(effects) chi_t with respect to the effect's parameters (for
// delay and lag the derivative of the rotor wrench, for acc bias and misalignment mostly the
// gravity direction), with the parameters chi projected out.

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/model/effects.h"

namespace rotorid {

using ComponentVector = Eigen::Matrix<double, 6, 1>;  // Fx Fy Fz Mx My Mz

struct GapLocationOptions {
  // Frequency bands (Hz, [low, high)) of the residual spectrum; a high edge <= 0 means "to the
  // Nyquist frequency of the rows" (everything above the low-pass cut-off is attenuated by it).
  std::vector<std::pair<double, double>> bands = {{0.0, 1.0}, {1.0, 3.0}, {3.0, 6.0}, {6.0, 0.0}};
  // Stretches: windows of this length, this far apart.
  double window_s = 5.0;
  double window_step_s = 2.5;
  // Number of worst (non-overlapping) stretches named.
  int worst_stretches = 3;

  std::string Validate() const;
};

struct BandGap {
  double low_hz = 0.0;
  double high_hz = 0.0;
  ComponentVector residual_rms = ComponentVector::Zero();        // linear model's residual in the band
  ComponentVector final_residual_rms = ComponentVector::Zero();  // with the final effects
  ComponentVector model_rms = ComponentVector::Zero();           // rotor-model wrench in the band
  ComponentVector share_pct = ComponentVector::Zero();           // of the component's residual energy
  // 100 residual_rms / model_rms; null where the model wrench is 0 (Fx, Fy).
  std::vector<std::optional<double>> residual_to_model_pct;
};

struct FlightStretch {
  std::string flight;
  double start_s = 0.0;
  double end_s = 0.0;
  // Mean square of the scaled residual in the window over that of the whole flight (1: average).
  double mean_square_ratio = 0.0;
  int dominant_component = 0;                                      // largest scaled mean square in the window
  std::vector<std::optional<double>> relative_error_pct;           // Table III in the window
  Eigen::Vector3d angular_velocity_rms = Eigen::Vector3d::Zero();  // rad/s
  double mean_vertical_acceleration_mps2 = 0.0;                    // mean specific force along z_d minus g
  // "climbing" / "descending" (net thrust above / below the weight), "rolling", "pitching",
  // "yawing" (rates well above the flight's typical); else "hovering" (rates well below it) or
  // "typical manoeuvring".
  std::vector<std::string> activities;
};

struct EffectSignature {
  EffectKind kind = nullptr;
  std::vector<std::string> labels;  // delay_s, acc_bias_x, ...
  // Cosine between the scaled residual and each parameter's signature (chi projected out): its
  // square is the share of the residual a fit of that parameter alone removes (to first order).
  Eigen::VectorXd residual_correlation;
  Eigen::VectorXd linearized_estimate;  // one Gauss-Newton step from zero, all its parameters jointly
  Eigen::VectorXd linearized_std;
  double linearized_shrink_pct = 0.0;                             // in-sample residual removed by that step
  ComponentVector component_share_pct = ComponentVector::Zero();  // where the signature's energy lies
};

struct GapLocation {
  std::vector<std::optional<double>> relative_error_pct;  // linear model, in-sample (Table III)
  std::vector<BandGap> bands;
  std::vector<FlightStretch> worst_stretches;
  std::vector<EffectSignature> signatures;
};

// The where-analysis of a linear identification, with the residual of the final model (named
// parameters and effects, e.g. the diagnosis' selected effects) for the per-band comparison.
GapLocation LocateGap(const IdentificationResult& linear, const std::map<std::string, double>& final_parameters,
                      const Effects& final_effects, const std::vector<EffectKind>& candidates,
                      const GapLocationOptions& options);

}  // namespace rotorid

#pragma once

// Command-to-IMU delay of a log: a global search of the TLS criterion over a wide range of delays
// (so that the estimate cannot lock onto a wrong local minimum), then the joint refinement from
// the best grid point, whose covariance gives the std.

#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/refine/refine.h"

namespace rotorid {

struct DelayOptions {
  DelaySearch search;
  // Estimate the motor time constant jointly (delay and lag are partly confounded).
  bool with_motor_lag = false;
  int num_threads = 2;

  std::string Validate() const;
};

struct DelayEstimate {
  double delay_s = 0.0;
  double delay_std_s = 0.0;
  double motor_tau_s = 0.0;
  double motor_tau_std_s = 0.0;
  double grid_best_s = 0.0;
  std::vector<double> grid_s;
  std::vector<double> criterion;  // TLS criterion at each grid delay
  RefineResult refined;
  std::vector<std::string> warnings;
};

// The effect this estimates (the registry's `delay`).
EffectKind DelayEffect();

// Progress steps of EstimateDelay: the global search, then the refinement's (RefineSteps).
int DelaySteps(const DelayOptions& options);
DelayEstimate EstimateDelay(const IdentificationResult& linear, const DelayOptions& options,
                            const StepProgress& progress = {});

// The TLS criterion at each delay (threads split the grid).
std::vector<double> DelayCriterionCurve(const IdentificationResult& linear, const std::vector<double>& delays_s,
                                        int num_threads);

}  // namespace rotorid

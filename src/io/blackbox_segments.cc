#include "rotorid/io/blackbox_segments.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/units.h"

namespace rotorid {
namespace {

// Centred moving average over about `window_s` of a per-sample signal (prefix sums).
std::vector<double> CentredMean(const Eigen::VectorXd& t, const std::vector<double>& x, double window_s) {
  const int n = static_cast<int>(x.size());
  std::vector<double> prefix(n + 1, 0.0), out(n);
  for (int i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + x[i];
  int lo = 0, hi = 0;
  for (int i = 0; i < n; ++i) {
    while (t[lo] < t[i] - window_s / 2) ++lo;
    while (hi < n && t[hi] <= t[i] + window_s / 2) ++hi;
    out[i] = (prefix[hi] - prefix[lo]) / (hi - lo);
  }
  return out;
}

double MedianOfPositive(const Eigen::MatrixXd& rotor) {
  std::vector<double> values;
  for (Eigen::Index i = 0; i < rotor.size(); ++i)
    if (rotor.data()[i] > 0) values.push_back(rotor.data()[i]);
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace

const char* ToString(FlightPhase phase) {
  switch (phase) {
    case FlightPhase::kMotorsStopped:
      return "motors stopped";
    case FlightPhase::kArmedIdle:
      return "armed idle";
    case FlightPhase::kFreeFall:
      return "free fall";
    case FlightPhase::kPowered:
      return "powered";
  }
  return "unknown";
}

std::string FlightPhaseOptions::Validate() const {
  if (!(stopped_fraction >= 0 && stopped_fraction < 1)) return "stopped_fraction must be in [0, 1)";
  if (!(free_fall_g > 0 && free_fall_g < 1)) return "free_fall_g must be in (0, 1)";
  if (!(free_fall_window_s >= 0) || !(min_phase_s >= 0)) return "phase windows must be >= 0 s";
  return {};
}

std::vector<FlightPhaseSpan> FlightPhases(const FlightLog& log, const FlightPhaseOptions& options,
                                          const SegmentationOptions& segmentation) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  if (const std::string problem = segmentation.Validate(); !problem.empty()) throw Error(problem);
  const int n = log.num_samples();
  if (n == 0) return {};
  const double median = MedianOfPositive(log.rotor_radps);
  std::vector<double> acc_norm(n), gyro_norm(n), thrust(n);
  for (int i = 0; i < n; ++i) {
    acc_norm[i] = log.acc_mps2.row(i).norm();
    gyro_norm[i] = log.gyro_radps.row(i).norm();
    thrust[i] = log.rotor_radps.row(i).squaredNorm() / std::max(1, log.num_rotors());
  }
  const std::vector<double> acc_fast = CentredMean(log.t_s, acc_norm, options.free_fall_window_s);
  const std::vector<double> acc_rest = CentredMean(log.t_s, acc_norm, segmentation.rest_window_s);
  const std::vector<double> gyro_rest = CentredMean(log.t_s, gyro_norm, segmentation.rest_window_s);
  std::vector<FlightPhase> phase(n, FlightPhase::kPowered);
  for (int i = 0; i < n; ++i) {
    const bool stopped = log.rotor_radps.row(i).maxCoeff() <= options.stopped_fraction * median;
    const bool at_rest = gyro_rest[i] < segmentation.rest_gyro_radps &&
                         std::abs(acc_rest[i] - log.gravity_mps2) < segmentation.rest_acc_tolerance_mps2;
    const bool low_thrust = thrust[i] < segmentation.ground_thrust_fraction * median * median;
    if (acc_fast[i] < options.free_fall_g * log.gravity_mps2)
      phase[i] = FlightPhase::kFreeFall;
    else if (stopped)
      phase[i] = FlightPhase::kMotorsStopped;
    else if (at_rest && low_thrust)
      phase[i] = FlightPhase::kArmedIdle;
  }
  std::vector<FlightPhaseSpan> spans;
  for (int i = 0; i < n;) {
    int j = i + 1;
    while (j < n && phase[j] == phase[i]) ++j;
    const bool too_short = log.t_s[j - 1] - log.t_s[i] < options.min_phase_s;
    if (!spans.empty() && (too_short || spans.back().phase == phase[i])) {
      spans.back().end = j;
    } else {
      spans.push_back({phase[i], i, j, 0.0, 0.0});
    }
    i = j;
  }
  for (FlightPhaseSpan& s : spans) {
    s.t_begin_s = log.t_s[s.begin];
    s.t_end_s = log.t_s[s.end - 1];
  }
  return spans;
}

std::string PhaseReport(const std::vector<FlightPhaseSpan>& phases) {
  std::string out;
  char line[160];
  for (const FlightPhaseSpan& s : phases) {
    std::snprintf(line, sizeof(line), "  %8.3f - %8.3f s  %s\n", s.t_begin_s, s.t_end_s, ToString(s.phase));
    out += line;
  }
  return out;
}

SegmentationOptions ThrownQuadSegmentationOptions() {
  SegmentationOptions options;
  options.takeoff_margin_s = 0.1;
  options.landing_margin_s = 0.3;
  options.max_specific_force_mps2 = 10.0 * kStandardGravity;
  options.max_angular_acc_radps2 = 20000.0;
  options.gyro_limit_radps = 34.0;
  options.min_segment_s = 0.3;
  return options;
}

Segmentation SegmentThrownFlight(const FlightLog& log, const SegmentationOptions& options) {
  // Without the pose: a hand-launched vehicle rests in a hand or on a table, so "near the resting
  // height" is no ground (LOG00230 hovers at its hand's height for its last 4 s).
  FlightLog without_pose = log;
  without_pose.mocap.reset();
  Segmentation segmentation = SegmentFlight(without_pose, options);
  std::vector<FlightPhaseSpan> stopped;
  for (const FlightPhaseSpan& s : FlightPhases(log, {}, options))
    if (s.phase == FlightPhase::kMotorsStopped) stopped.push_back(s);
  std::vector<SampleRange> kept;
  for (const SampleRange& range : segmentation.kept) {
    int begin = range.begin;
    const auto keep_until = [&](int end) {
      if (end > begin && log.t_s[end - 1] - log.t_s[begin] >= options.min_segment_s) kept.push_back({begin, end});
    };
    for (const FlightPhaseSpan& s : stopped) {
      if (s.end <= begin || s.begin >= range.end) continue;
      keep_until(std::max(begin, s.begin));
      ExcludedSpan span;
      span.begin = std::max(begin, s.begin);
      span.end = std::min(range.end, s.end);
      span.t_begin_s = log.t_s[span.begin];
      span.t_end_s = log.t_s[span.end - 1];
      span.reason = ExclusionReason::kOnGround;
      span.detail = "motors stopped (carried by hand or resting)";
      segmentation.excluded.push_back(span);
      begin = std::min(range.end, s.end);
    }
    keep_until(range.end);
  }
  segmentation.kept = kept;
  std::sort(segmentation.excluded.begin(), segmentation.excluded.end(),
            [](const ExcludedSpan& a, const ExcludedSpan& b) { return a.begin < b.begin; });
  return segmentation;
}

}  // namespace rotorid

#include "rotorid/io/segmentation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"

namespace rotorid {
namespace {

constexpr int kKept = -1;

// Higher wins where reasons overlap: the most specific explanation of a sample is reported.
int Priority(ExclusionReason reason) {
  switch (reason) {
    case ExclusionReason::kImpact:
      return 7;
    case ExclusionReason::kGyroLimit:
      return 6;
    case ExclusionReason::kMotorSaturation:
      return 5;
    case ExclusionReason::kOnGround:
      return 4;
    case ExclusionReason::kLanding:
      return 3;
    case ExclusionReason::kTakeoff:
      return 2;
    case ExclusionReason::kShortSegment:
      return 1;
    case ExclusionReason::kLoggingGap:
      return 0;
  }
  return 0;
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Per-sample reasons, each sample keeping the highest-priority one.
class ReasonMap {
 public:
  explicit ReasonMap(int n) : reason_(static_cast<size_t>(n), kKept) {}
  void Mark(int begin, int end, ExclusionReason reason) {
    for (int i = std::max(begin, 0); i < std::min(end, size()); ++i) {
      if (reason_[i] == kKept || Priority(reason) > Priority(static_cast<ExclusionReason>(reason_[i]))) {
        reason_[i] = static_cast<int>(reason);
      }
    }
  }
  int size() const { return static_cast<int>(reason_.size()); }
  int at(int i) const { return reason_[i]; }

 private:
  std::vector<int> reason_;
};

// Marks every sample within `margin_s` of a flagged one. Flags are merged as time intervals
// first, so that dense flags cost O(n) overall.
void MarkAround(const Eigen::VectorXd& t, const std::vector<int>& flagged, double margin_s, ExclusionReason reason,
                ReasonMap* reasons) {
  const double* begin = t.data();
  const double* end = t.data() + t.size();
  size_t k = 0;
  while (k < flagged.size()) {
    const double lo = t[flagged[k]] - margin_s;
    double hi = t[flagged[k]] + margin_s;
    while (k + 1 < flagged.size() && t[flagged[k + 1]] - margin_s <= hi) hi = t[flagged[++k]] + margin_s;
    ++k;
    const int first = static_cast<int>(std::lower_bound(begin, end, lo) - begin);
    const int last = static_cast<int>(std::upper_bound(begin, end, hi) - begin);
    reasons->Mark(first, last, reason);
  }
}

// Calls f(begin, end) for each run [begin, end) of equal flags, in order. f may change the
// flags of its own run.
template <typename F>
void ForEachRun(const std::vector<char>& flags, F f) {
  const int n = static_cast<int>(flags.size());
  for (int a = 0; a < n;) {
    int b = a;
    while (b < n && flags[b] == flags[a]) ++b;
    f(a, b);
    a = b;
  }
}

// The metadata says so, or else every rotor value lies in [0, 1].
bool RotorSignalLooksLikeCommand(const FlightLog& log) {
  if (const auto it = log.metadata.find("rotor_signal"); it != log.metadata.end()) return it->second == "command";
  return log.num_rotors() > 0 && log.rotor_radps.minCoeff() >= 0.0 && log.rotor_radps.maxCoeff() <= 1.0;
}

// Samples where the rotors carry less than `fraction` of hover thrust. The rotor "thrust
// level" is the mean of the squared signals, hover its median while the rotors run.
std::vector<char> LowThrust(const FlightLog& log, double fraction) {
  const int n = log.num_samples();
  const int num_rotors = log.num_rotors();
  Eigen::VectorXd level = Eigen::VectorXd::Zero(n);
  if (num_rotors > 0) level = log.rotor_radps.rowwise().squaredNorm() / num_rotors;
  const double max_level = level.maxCoeff();
  std::vector<double> running;
  for (int i = 0; i < n; ++i) {
    if (level[i] > 0.01 * max_level) running.push_back(level[i]);
  }
  const double hover_level = Median(running);
  std::vector<char> low(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i) low[i] = !(hover_level > 0.0) || level[i] < fraction * hover_level;
  return low;
}

// At rest: the centred moving averages over the rest window (two pointers over prefix sums) of
// the gyro near zero and of the specific force near g.
std::vector<char> AtRest(const FlightLog& log, const SegmentationOptions& o) {
  const int n = log.num_samples();
  const Eigen::VectorXd& t = log.t_s;
  Eigen::MatrixXd prefix = Eigen::MatrixXd::Zero(n + 1, 6);
  for (int i = 0; i < n; ++i) {
    prefix.row(i + 1).head(3) = prefix.row(i).head(3) + log.gyro_radps.row(i);
    prefix.row(i + 1).tail(3) = prefix.row(i).tail(3) + log.acc_mps2.row(i);
  }
  std::vector<char> rest(static_cast<size_t>(n), 0);
  int lo = 0, hi = 0;  // window [lo, hi)
  const double half_window = 0.5 * o.rest_window_s;
  for (int i = 0; i < n; ++i) {
    while (t[lo] < t[i] - half_window) ++lo;
    while (hi < n && t[hi] <= t[i] + half_window) ++hi;
    const Eigen::Matrix<double, 1, 6> mean = (prefix.row(hi) - prefix.row(lo)) / (hi - lo);
    rest[i] = mean.head(3).norm() < o.rest_gyro_radps &&
              std::abs(mean.tail(3).norm() - log.gravity_mps2) < o.rest_acc_tolerance_mps2;
  }
  return rest;
}

// With motion capture, samples near the resting height (the median height on ground) count as
// ground too: contact, ground effect. Returns the samples within that clearance.
std::vector<char> MarkNearFloor(const FlightLog& log, double clearance_m, std::vector<char>* ground) {
  const int n = log.num_samples();
  std::vector<char> below_clearance(static_cast<size_t>(n), 0);
  if (!log.mocap || log.mocap->position_w_m.rows() != n) return below_clearance;
  std::vector<double> resting_z;
  for (int i = 0; i < n; ++i) {
    if ((*ground)[i]) resting_z.push_back(log.mocap->position_w_m(i, 2));
  }
  if (resting_z.empty()) return below_clearance;
  const double floor_z = Median(resting_z);
  for (int i = 0; i < n; ++i) {
    if (log.mocap->position_w_m(i, 2) < floor_z + clearance_m) {
      below_clearance[i] = 1;
      (*ground)[i] = 1;
    }
  }
  return below_clearance;
}

// Ground runs, and the take-off and landing transients where an airborne run meets the ground
// (not where the log starts or ends).
void MarkGroundAndTransients(const Eigen::VectorXd& t, const std::vector<char>& ground, const SegmentationOptions& o,
                             ReasonMap* reasons) {
  const int n = static_cast<int>(ground.size());
  ForEachRun(ground, [&](int a, int b) {
    if (ground[a]) {
      reasons->Mark(a, b, ExclusionReason::kOnGround);
      return;
    }
    if (a > 0) {
      const int last =
          static_cast<int>(std::upper_bound(t.data() + a, t.data() + b, t[a] + o.takeoff_margin_s) - t.data());
      reasons->Mark(a, last, ExclusionReason::kTakeoff);
    }
    if (b < n) {
      const int first =
          static_cast<int>(std::lower_bound(t.data() + a, t.data() + b, t[b] - o.landing_margin_s) - t.data());
      reasons->Mark(first, b, ExclusionReason::kLanding);
    }
  });
}

// What the spans' details quote besides the log itself.
struct SampleEvidence {
  bool is_command = false;
  std::vector<char> below_clearance;  // ground by motion-capture height
  Eigen::VectorXd alpha;              // largest per-axis angular acceleration
  std::vector<char> gap_before;       // a logging gap before the sample
};

// The angular acceleration between samples, zero across a logging gap (which it marks).
void FindGapsAndAngularAcceleration(const FlightLog& log, double max_gap_s, SampleEvidence* evidence) {
  const int n = log.num_samples();
  const Eigen::VectorXd& t = log.t_s;
  evidence->alpha = Eigen::VectorXd::Zero(n);
  evidence->gap_before.assign(static_cast<size_t>(n), 0);
  for (int i = 1; i < n; ++i) {
    const double dt = t[i] - t[i - 1];
    if (dt > max_gap_s) {
      evidence->gap_before[i] = 1;
      continue;
    }
    if (dt > 0.0) evidence->alpha[i] = (log.gyro_radps.row(i) - log.gyro_radps.row(i - 1)).cwiseAbs().maxCoeff() / dt;
  }
}

// Impacts and spikes, the gyro limit and motor saturation, each with its margin.
void MarkSpikesAndSaturation(const FlightLog& log, const SampleEvidence& evidence, const SegmentationOptions& o,
                             ReasonMap* reasons) {
  std::vector<int> impact, gyro_limit, saturated;
  for (int i = 0; i < log.num_samples(); ++i) {
    if (log.acc_mps2.row(i).norm() > o.max_specific_force_mps2 || evidence.alpha[i] > o.max_angular_acc_radps2) {
      impact.push_back(i);
    }
    if (log.gyro_radps.row(i).cwiseAbs().maxCoeff() > o.gyro_limit_radps) gyro_limit.push_back(i);
    if (log.num_rotors() > 0) {
      const double top = log.rotor_radps.row(i).maxCoeff();
      if ((evidence.is_command && top >= o.command_saturation) ||
          (!evidence.is_command && o.speed_saturation_radps > 0.0 && top >= o.speed_saturation_radps)) {
        saturated.push_back(i);
      }
    }
  }
  MarkAround(log.t_s, impact, o.spike_margin_s, ExclusionReason::kImpact, reasons);
  MarkAround(log.t_s, gyro_limit, o.spike_margin_s, ExclusionReason::kGyroLimit, reasons);
  MarkAround(log.t_s, saturated, o.saturation_margin_s, ExclusionReason::kMotorSaturation, reasons);
}

// Runs of unmarked samples, split at gaps; those shorter than min_segment_s are marked short.
std::vector<SampleRange> KeptRanges(const Eigen::VectorXd& t, const std::vector<char>& gap_before, double min_segment_s,
                                    ReasonMap* reasons) {
  std::vector<SampleRange> kept;
  const int n = reasons->size();
  for (int a = 0; a < n;) {
    if (reasons->at(a) != kKept) {
      ++a;
      continue;
    }
    int b = a + 1;
    while (b < n && reasons->at(b) == kKept && !gap_before[b]) ++b;
    if (t[b - 1] - t[a] < min_segment_s) {
      reasons->Mark(a, b, ExclusionReason::kShortSegment);
    } else {
      kept.push_back({a, b});
    }
    a = b;
  }
  return kept;
}

// What caused the span [a, b) left out for `reason`, in numbers.
std::string SpanDetail(ExclusionReason reason, int a, int b, const FlightLog& log, const SampleEvidence& evidence,
                       const SegmentationOptions& o) {
  const Eigen::VectorXd& t = log.t_s;
  switch (reason) {
    case ExclusionReason::kOnGround: {
      const bool by_height = std::any_of(evidence.below_clearance.begin() + a, evidence.below_clearance.begin() + b,
                                         [](char c) { return c != 0; });
      return by_height ? "at rest or within " + FormatValue("%.2f m", o.ground_clearance_m) +
                             " of the resting height (motion capture)"
                       : "at rest with the rotors below " + FormatValue("%.0f%%", 100 * o.ground_thrust_fraction) +
                             " of hover thrust";
    }
    case ExclusionReason::kTakeoff:
      return "first " + FormatValue("%.2f s", o.takeoff_margin_s) + " after leaving the ground";
    case ExclusionReason::kLanding:
      return "last " + FormatValue("%.2f s", o.landing_margin_s) + " before reaching the ground";
    case ExclusionReason::kImpact: {
      double peak_acc = 0.0, peak_alpha = 0.0;
      for (int i = a; i < b; ++i) {
        peak_acc = std::max(peak_acc, log.acc_mps2.row(i).norm());
        peak_alpha = std::max(peak_alpha, evidence.alpha[i]);
      }
      return "peak specific force " + FormatValue("%.1f g", peak_acc / log.gravity_mps2) +
             ", peak angular acceleration " + FormatValue("%.0f rad/s^2", peak_alpha);
    }
    case ExclusionReason::kGyroLimit: {
      double peak = 0.0;
      for (int i = a; i < b; ++i) peak = std::max(peak, log.gyro_radps.row(i).cwiseAbs().maxCoeff());
      return "peak " + FormatValue("%.1f rad/s", peak) + FormatValue(" (%.0f deg/s)", peak * 180.0 / kPi) + " > " +
             FormatValue("%.1f rad/s", o.gyro_limit_radps);
    }
    case ExclusionReason::kMotorSaturation: {
      std::string rotors;
      const double limit = evidence.is_command ? o.command_saturation : o.speed_saturation_radps;
      for (int r = 0; r < log.num_rotors(); ++r) {
        if ((log.rotor_radps.col(r).segment(a, b - a).array() >= limit).any()) {
          rotors += (rotors.empty() ? "" : ", ") + std::to_string(r + 1);
        }
      }
      const std::string at_limit = evidence.is_command ? " at full command" : " at its speed limit";
      return rotors.empty() ? "within " + FormatValue("%.2f s", o.saturation_margin_s) + " of a rotor" + at_limit
                            : "rotor " + rotors + at_limit;
    }
    case ExclusionReason::kShortSegment:
      return "kept stretch of " + FormatValue("%.2f s", t[b - 1] - t[a]) + " < " +
             FormatValue("%.2f s", o.min_segment_s);
    case ExclusionReason::kLoggingGap:
      break;
  }
  return {};
}

// Runs of one reason, then the logging gaps, in time order.
std::vector<ExcludedSpan> ExcludedSpans(const FlightLog& log, const ReasonMap& reasons, const SampleEvidence& evidence,
                                        const SegmentationOptions& o) {
  const Eigen::VectorXd& t = log.t_s;
  const int n = reasons.size();
  std::vector<ExcludedSpan> excluded;
  for (int a = 0; a < n;) {
    if (reasons.at(a) == kKept) {
      ++a;
      continue;
    }
    int b = a + 1;
    while (b < n && reasons.at(b) == reasons.at(a)) ++b;
    ExcludedSpan span;
    span.begin = a;
    span.end = b;
    span.t_begin_s = t[a];
    span.t_end_s = t[b - 1];
    span.reason = static_cast<ExclusionReason>(reasons.at(a));
    span.detail = SpanDetail(span.reason, a, b, log, evidence, o);
    excluded.push_back(std::move(span));
    a = b;
  }
  for (int i = 1; i < n; ++i) {
    if (!evidence.gap_before[i]) continue;
    ExcludedSpan gap;
    gap.begin = gap.end = i;
    gap.t_begin_s = t[i - 1];
    gap.t_end_s = t[i];
    gap.reason = ExclusionReason::kLoggingGap;
    gap.detail = "no samples for " + FormatValue("%.3f s", t[i] - t[i - 1]);
    excluded.push_back(std::move(gap));
  }
  std::stable_sort(excluded.begin(), excluded.end(), [](const ExcludedSpan& x, const ExcludedSpan& y) {
    return x.t_begin_s < y.t_begin_s || (x.t_begin_s == y.t_begin_s && x.begin < y.begin);
  });
  return excluded;
}

}  // namespace

const char* ToString(ExclusionReason reason) {
  switch (reason) {
    case ExclusionReason::kOnGround:
      return "on ground";
    case ExclusionReason::kTakeoff:
      return "take-off";
    case ExclusionReason::kLanding:
      return "landing";
    case ExclusionReason::kImpact:
      return "impact or spike";
    case ExclusionReason::kGyroLimit:
      return "gyro limit";
    case ExclusionReason::kMotorSaturation:
      return "motor saturation";
    case ExclusionReason::kLoggingGap:
      return "logging gap";
    case ExclusionReason::kShortSegment:
      return "short segment";
  }
  return "?";
}

std::string SegmentationOptions::Validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!positive(rest_window_s)) return "rest_window_s must be positive";
  if (!positive(rest_gyro_radps)) return "rest_gyro_radps must be positive";
  if (!positive(rest_acc_tolerance_mps2)) return "rest_acc_tolerance_mps2 must be positive";
  if (!(non_negative(ground_thrust_fraction) && ground_thrust_fraction <= 1.0))
    return "ground_thrust_fraction must lie in [0, 1]";
  if (!non_negative(ground_clearance_m)) return "ground_clearance_m must be >= 0";
  if (!non_negative(min_ground_s)) return "min_ground_s must be >= 0";
  if (!non_negative(takeoff_margin_s) || !non_negative(landing_margin_s))
    return "take-off and landing margins must be >= 0";
  if (!positive(max_specific_force_mps2)) return "max_specific_force_mps2 must be positive";
  if (!positive(max_angular_acc_radps2)) return "max_angular_acc_radps2 must be positive";
  if (!positive(gyro_limit_radps)) return "gyro_limit_radps must be positive";
  if (!non_negative(spike_margin_s) || !non_negative(saturation_margin_s)) return "margins must be >= 0";
  if (!positive(command_saturation)) return "command_saturation must be positive";
  if (!non_negative(speed_saturation_radps)) return "speed_saturation_radps must be >= 0 (0: not checked)";
  if (!positive(max_gap_s)) return "max_gap_s must be positive";
  if (!non_negative(min_segment_s)) return "min_segment_s must be >= 0";
  return {};
}

int Segmentation::kept_samples() const {
  int total = 0;
  for (const SampleRange& r : kept) total += r.size();
  return total;
}

double Segmentation::kept_duration_s(const FlightLog& log) const {
  double total = 0.0;
  for (const SampleRange& r : kept) total += log.t_s[r.end - 1] - log.t_s[r.begin];
  return total;
}

std::string Segmentation::Report(const FlightLog& log) const {
  std::string out;
  const double duration = log.duration_s();
  out += "kept " + std::to_string(kept.size()) + " segment" + (kept.size() == 1 ? "" : "s") + ", " +
         FormatValue("%.2f s", kept_duration_s(log)) + " of " + FormatValue("%.2f s", duration) + " (" +
         std::to_string(kept_samples()) + " of " + std::to_string(num_samples) + " samples)";
  for (const SampleRange& r : kept) {
    out +=
        "\n  kept      " + FormatValue("%9.3f", log.t_s[r.begin]) + " - " + FormatValue("%9.3f s", log.t_s[r.end - 1]);
  }
  for (const ExcludedSpan& span : excluded) {
    out += "\n  left out  " + FormatValue("%9.3f", span.t_begin_s) + " - " + FormatValue("%9.3f s", span.t_end_s) +
           "  " + ToString(span.reason) + (span.detail.empty() ? "" : ": " + span.detail);
  }
  return out;
}

Segmentation SegmentFlight(const FlightLog& log, const SegmentationOptions& o) {
  if (const std::string problem = o.Validate(); !problem.empty()) throw Error("segmentation: " + problem);
  Segmentation result;
  const int n = log.num_samples();
  result.num_samples = n;
  if (n == 0) return result;

  SampleEvidence evidence;
  evidence.is_command = RotorSignalLooksLikeCommand(log);
  std::vector<char> ground = AtRest(log, o);
  const std::vector<char> low_thrust = LowThrust(log, o.ground_thrust_fraction);
  for (int i = 0; i < n; ++i) ground[i] = ground[i] && low_thrust[i];
  evidence.below_clearance = MarkNearFloor(log, o.ground_clearance_m, &ground);
  // Brief still moments in flight are not ground.
  ForEachRun(ground, [&](int a, int b) {
    if (ground[a] && log.t_s[b - 1] - log.t_s[a] < o.min_ground_s) std::fill(ground.begin() + a, ground.begin() + b, 0);
  });

  ReasonMap reasons(n);
  MarkGroundAndTransients(log.t_s, ground, o, &reasons);
  FindGapsAndAngularAcceleration(log, o.max_gap_s, &evidence);
  MarkSpikesAndSaturation(log, evidence, o, &reasons);
  result.kept = KeptRanges(log.t_s, evidence.gap_before, o.min_segment_s, &reasons);
  result.excluded = ExcludedSpans(log, reasons, evidence, o);
  return result;
}

std::vector<FlightLog> KeptSegments(FlightLog log, const Segmentation& segmentation) {
  std::vector<FlightLog> out;
  if (segmentation.kept.size() == 1 && segmentation.kept[0].begin == 0 &&
      segmentation.kept[0].end == log.num_samples()) {
    out.push_back(std::move(log));
    return out;
  }
  out.reserve(segmentation.kept.size());
  for (const SampleRange& r : segmentation.kept) out.push_back(log.Slice(r.begin, r.end));
  return out;
}

}  // namespace rotorid

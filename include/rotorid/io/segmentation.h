#pragma once

// Flight segmentation: which samples of a log show the vehicle flying freely, so that
// identification sees only those. Left out, each with the time span and the reason:
//
//   on ground      at rest (steady specific force of 1 g, no rotation) while the rotors carry
//                  less than a fraction of the hover thrust; with motion capture also anything
//                  within a clearance of the floor (contact, ground effect)
//   take-off       the first seconds after leaving the ground
//   landing        the last seconds before touching down
//   impact/spike   specific force or angular acceleration beyond what flight produces (a hit,
//                  a crash, or a sensor glitch), with a margin either side
//   gyro limit     a gyro axis beyond a limit (near the sensor's range, where it clips)
//   saturation     a rotor command at full scale: the motor gives less than commanded
//   logging gap    no samples for longer than max_gap_s (the kept ranges never span one)
//   short segment  flying, but a kept stretch shorter than min_segment_s
//
// The rotor signal counts as a command when the metadata says `rotor_signal: command`, or when
// every rotor value lies in [0, 1].

#include <string>
#include <vector>

#include "rotorid/core/flight_log.h"

namespace rotorid {

enum class ExclusionReason {
  kOnGround,
  kTakeoff,
  kLanding,
  kImpact,
  kGyroLimit,
  kMotorSaturation,
  kLoggingGap,
  kShortSegment,
};

// "on ground", "take-off", "landing", "impact or spike", "gyro limit", "motor saturation",
// "logging gap", "short segment".
const char* ToString(ExclusionReason reason);

struct SegmentationOptions {
  // At rest: the centred moving average over rest_window_s of the gyro is below rest_gyro_radps
  // in norm and that of the accelerometer within rest_acc_tolerance_mps2 of g in norm.
  // Defaults: 0.1 s, 0.1 rad/s, 0.5 m/s^2.
  double rest_window_s = 0.1;
  double rest_gyro_radps = 0.1;
  double rest_acc_tolerance_mps2 = 0.5;
  // Rotors "not carrying the vehicle": mean of the squared rotor signals (thrust ~ Omega^2 or
  // u^2) below this fraction of its median while the rotors run. Default: 0.5.
  double ground_thrust_fraction = 0.5;
  // With motion capture: samples below the resting height + this count as ground. The resting
  // height comes from the samples found on ground without mocap; a log that never rests keeps
  // every height. Default: 0.1 m (Crazyflie-sized ground effect; raise it for larger props).
  double ground_clearance_m = 0.1;
  // Ground runs shorter than this are taken as airborne (a brief still moment in flight).
  // Default: 0.2 s.
  double min_ground_s = 0.2;
  // Left out after leaving and before reaching the ground. Defaults: 1.0 s each.
  double takeoff_margin_s = 1.0;
  double landing_margin_s = 1.0;
  // Impacts and sensor spikes: norm of the specific force above max_specific_force_mps2, or a
  // gyro axis changing faster than max_angular_acc_radps2 between samples. Defaults: 4 g and
  // 2000 rad/s^2 (a Crazyflie's motors give at most about 1000 rad/s^2; large vehicles far
  // less, so lower it for them).
  double max_specific_force_mps2 = 4.0 * kStandardGravity;
  double max_angular_acc_radps2 = 2000.0;
  // Any gyro axis beyond this. Default: 30 rad/s (about 0.9 of a +-2000 deg/s range).
  double gyro_limit_radps = 30.0;
  // Left out either side of an impact, spike or gyro-limit sample. Default: 0.1 s.
  double spike_margin_s = 0.1;
  // Saturation: a normalised command at or above command_saturation (default 0.999); for a
  // measured speed, a rotor at or above speed_saturation_radps (default 0: not checked, since a
  // measured speed shows no saturation by itself). Margin either side: 0.05 s.
  double command_saturation = 0.999;
  double speed_saturation_radps = 0.0;
  double saturation_margin_s = 0.05;
  // Gaps in the time stamps longer than this split the kept ranges. Default: 0.05 s.
  double max_gap_s = 0.05;
  // Kept stretches shorter than this are left out. Default: 1.0 s.
  double min_segment_s = 1.0;

  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

// Samples [begin, end) of the log.
struct SampleRange {
  int begin = 0;
  int end = 0;
  int size() const { return end - begin; }
};

// A stretch left out: samples [begin, end) from t_begin_s to t_end_s (the times of its first and
// last sample; for a logging gap, begin == end and the span is the gap itself).
struct ExcludedSpan {
  double t_begin_s = 0.0;
  double t_end_s = 0.0;
  int begin = 0;
  int end = 0;
  ExclusionReason reason = ExclusionReason::kOnGround;
  std::string detail;  // e.g. "peak |acc| 20.1 g, peak angular acceleration 9684 rad/s^2"
};

struct Segmentation {
  std::vector<SampleRange> kept;       // in time order, disjoint
  std::vector<ExcludedSpan> excluded;  // in time order
  int num_samples = 0;

  int kept_samples() const;
  double kept_duration_s(const FlightLog& log) const;
  // Lines for the CLI: a summary, then one line per excluded span.
  std::string Report(const FlightLog& log) const;
};

// Segments a flight. Throws rotorid::Error for invalid options.
Segmentation SegmentFlight(const FlightLog& log, const SegmentationOptions& options = {});

// The kept ranges as separate logs (FlightLog::Slice), in time order; `log` itself, not a copy, when
// the one kept range is all of it.
std::vector<FlightLog> KeptSegments(FlightLog log, const Segmentation& segmentation);

}  // namespace rotorid

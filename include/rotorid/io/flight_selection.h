#pragma once

// Which part of a log the analysis uses (INTERFACE.md 4, v2: --window, --segment) and a record
// of what was read (INTERFACE.md 5, v2: input.flights[]): format, time span, rates, rotor signal
// and where it came from, the stretches kept and those left out with the reason.

#include <optional>
#include <string>
#include <vector>

#include "rotorid/core/flight_log.h"
#include "rotorid/io/segmentation.h"

namespace rotorid {

// Seconds of the log's own time base (a Crazyflie log's time since boot, a CSV's `t`).
struct TimeWindow {
  double start_s = 0.0;
  double end_s = 0.0;
};
// "START,END" with START < END; throws rotorid::Error naming the text.
TimeWindow ParseTimeWindow(const std::string& text);

enum class SegmentMode { kAuto, kNone };
// "auto" or "none"; throws rotorid::Error otherwise.
SegmentMode ParseSegmentMode(const std::string& text);

struct KeptStretch {
  double start_s = 0.0;
  double end_s = 0.0;
};
struct LeftOutStretch {
  double start_s = 0.0;
  double end_s = 0.0;
  std::string reason;  // "outside --window" or a segmentation reason ("on ground", "take-off", ...)
  std::string detail;
};

// What was read from one log file and which of it is used.
struct FlightInputSummary {
  std::string file;
  std::string format;        // "csv", "csv (column map)", "px4_ulog", "crazyflie_usd"
  double log_start_s = 0.0;  // the whole log
  double log_end_s = 0.0;
  std::optional<TimeWindow> window;  // --window, when given
  std::string segment_mode = "auto";
  double used_s = 0.0;               // total length of the kept stretches
  double imu_rate_hz = 0.0;          // median sample rate of the log's time base
  std::string rotor_signal;          // "rpm", "command" or "command+voltage"
  std::string rotor_signal_source;   // topic or columns, and any map applied
  std::vector<std::string> sources;  // columns or topics used, one entry per stream
  std::vector<KeptStretch> kept;
  std::vector<LeftOutStretch> left_out;  // outside the window, and what segmentation dropped
  std::vector<std::string> notes;        // what the user must know (e.g. a fallback to commands)

  // One line for the console: "read: FILE (format, 1000 Hz, rpm from ..., 35.0-65.0 s, 30.0 s used)".
  std::string ConsoleLine() const;
};

// A log cut to its window and segmented.
struct SelectedFlight {
  std::vector<FlightLog> segments;  // in time order; one entry when the whole (window of the) log is kept
  FlightInputSummary summary;
};

// Cuts `log` (read from `path`) to `window`, then keeps its airborne, unsaturated stretches when
// `mode` is kAuto. Without `segmentation` the log's format chooses: blackbox logs (thrown or
// self-launched FPV quads) SegmentThrownFlight with ThrownQuadSegmentationOptions, every other
// format SegmentFlight with the default options. Throws rotorid::Error naming the file when the
// window lies outside the log or nothing usable is left.
SelectedFlight SelectFlight(FlightLog log, const std::string& path, const std::optional<TimeWindow>& window,
                            SegmentMode mode, const std::optional<SegmentationOptions>& segmentation = std::nullopt);

// The summary alone, for a log used whole (e.g. the rotor signal of a log read without selection).
FlightInputSummary DescribeFlightInput(const FlightLog& log, const std::string& path);

}  // namespace rotorid

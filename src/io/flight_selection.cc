#include "rotorid/io/flight_selection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/io/blackbox_segments.h"

namespace rotorid {

namespace {

std::string Meta(const FlightLog& log, const std::string& key) {
  const auto it = log.metadata.find(key);
  return it == log.metadata.end() ? std::string() : it->second;
}

std::string FormatName(const FlightLog& log) {
  if (Meta(log, "format") == "px4_ulog") return "px4_ulog";
  if (Meta(log, "format") == "blackbox") return "blackbox";
  if (Meta(log, "source_format").rfind("crazyflie_usd", 0) == 0) return "crazyflie_usd";
  if (!Meta(log, "column_map").empty()) return "csv (column map)";
  return "csv";
}

bool IsCommandSignal(const FlightLog& log) {
  return Meta(log, "rotor_signal") == "command" || Meta(log, "px4_rotor_signal") == "command" ||
         !Meta(log, "command_to_speed").empty();
}

std::string RotorColumns(const FlightLog& log) {
  return log.num_rotors() > 0 ? "rotor_1..rotor_" + std::to_string(log.num_rotors()) : "none";
}

// The stream each input came from, as the reader recorded it.
void DescribeSources(const FlightLog& log, const std::string& format, FlightInputSummary* s) {
  const auto add = [&](const std::string& what, const std::string& from) {
    if (!from.empty()) s->sources.push_back(what + ": " + from);
  };
  if (format == "px4_ulog") {
    add("imu", Meta(log, "px4_imu"));
    s->rotor_signal_source = Meta(log, "px4_rotor");
    add("pose", Meta(log, "px4_pose"));
    add("voltage", Meta(log, "px4_battery"));
  } else if (format == "crazyflie_usd") {
    add("imu", Meta(log, "imu_event"));
    add("time base", Meta(log, "time_base"));
    s->rotor_signal_source = Meta(log, "rotor_signal_source");
    add("pose", Meta(log, "mocap"));
    add("voltage", Meta(log, "voltage_source"));
  } else if (format == "blackbox") {
    add("imu", Meta(log, "blackbox_gyro") + "; " + Meta(log, "blackbox_acc"));
    s->rotor_signal_source = Meta(log, "blackbox_rotor");
    if (log.mocap) add("pose", Meta(log, "blackbox_pose"));
    if (log.voltage_v) add("voltage", Meta(log, "blackbox_voltage"));
  } else {
    if (format != "csv") add("column map", Meta(log, "column_map"));
    add("imu", "t, gyro_x..gyro_z, acc_x..acc_z");
    s->rotor_signal_source = format == "csv" ? RotorColumns(log) : Meta(log, "rotor_signal_columns");
    if (log.mocap) add("pose", "pos_x..pos_z and attitude columns");
    if (log.voltage_v) add("voltage", "voltage");
  }
  if (s->rotor_signal_source.empty()) s->rotor_signal_source = RotorColumns(log);
  add("rotor", s->rotor_signal_source);
  if (const std::string map = Meta(log, "command_to_speed"); !map.empty()) s->rotor_signal_source += " -> " + map;
}

void AddNotes(const FlightLog& log, const std::string& format, FlightInputSummary* s) {
  const bool command = IsCommandSignal(log);
  if (format == "px4_ulog" && command && Meta(log, "px4_rotor").find("esc") == std::string::npos) {
    s->notes.push_back("the rotor signal is the motor command (" + Meta(log, "px4_rotor") +
                       "), not a measured speed (esc_status.esc_rpm)");
  }
  if (command && Meta(log, "command_to_speed").empty()) {
    s->notes.push_back(
        "the rotor signal is a motor command without a command_to_speed map in the vehicle file: kt "
        "and kd come out per (command unit)^2, not per (rad/s)^2");
  }
  if (const std::string origin = Meta(log, "time_origin_s"); !origin.empty()) {
    s->notes.push_back("the time stamps are a wall clock from " + origin +
                       " s: times are counted from that first stamp (--window takes either)");
  }
  if (const std::string problems = Meta(log, "ulog_warnings"); !problems.empty()) {
    s->notes.push_back("the ULog reader reported " + problems +
                       " problem(s) (e.g. a truncated end): parts of the log may be missing");
  }
}

// A log whose stamps are a wall clock counts its times from the first stamp (metadata
// 'time_origin_s'): a window given on the wall clock (from the origin on) is moved onto those times.
std::optional<TimeWindow> OnTheLogsTimes(const FlightLog& log, const std::optional<TimeWindow>& window) {
  const std::string origin_text = Meta(log, "time_origin_s");
  if (!window || origin_text.empty()) return window;
  const double origin = std::strtod(origin_text.c_str(), nullptr);
  if (!(window->start_s >= origin)) return window;
  return TimeWindow{window->start_s - origin, window->end_s - origin};
}

}  // namespace

TimeWindow ParseTimeWindow(const std::string& text) {
  std::istringstream in(text);
  TimeWindow w;
  char comma = 0;
  std::string rest;
  if (!(in >> w.start_s >> comma >> w.end_s) || comma != ',' || (in >> rest) || !std::isfinite(w.start_s) ||
      !std::isfinite(w.end_s)) {
    throw Error("window must be START,END in seconds, got '" + text + "'");
  }
  if (!(w.start_s < w.end_s)) throw Error("window '" + text + "' must start before it ends");
  return w;
}

SegmentMode ParseSegmentMode(const std::string& text) {
  if (text == "auto") return SegmentMode::kAuto;
  if (text == "none") return SegmentMode::kNone;
  throw Error("segment must be auto or none, got '" + text + "'");
}

std::string FlightInputSummary::ConsoleLine() const {
  std::string line = "read: " + file + " (" + format + ", " + FormatValue("%.0f Hz", imu_rate_hz) + ", " +
                     rotor_signal + " from " + rotor_signal_source + "), ";
  const double start = window ? std::max(window->start_s, log_start_s) : log_start_s;
  const double end = window ? std::min(window->end_s, log_end_s) : log_end_s;
  line += FormatValue("%.2f", start) + "-" + FormatValue("%.2f s", end) + ", " + FormatValue("%.2f s used", used_s) +
          " in " + std::to_string(kept.size()) + " stretch" + (kept.size() == 1 ? "" : "es");
  for (const LeftOutStretch& l : left_out) {
    line += "\n  left out " + FormatValue("%9.3f", l.start_s) + " - " + FormatValue("%9.3f s", l.end_s) + "  " +
            l.reason + (l.detail.empty() ? "" : ": " + l.detail);
  }
  for (const std::string& note : notes) line += "\n  note: " + note;
  return line;
}

FlightInputSummary DescribeFlightInput(const FlightLog& log, const std::string& path) {
  FlightInputSummary s;
  s.file = path;
  s.format = FormatName(log);
  if (log.num_samples() > 0) {
    s.log_start_s = log.t_s[0];
    s.log_end_s = log.t_s[log.num_samples() - 1];
  }
  const double dt = log.num_samples() > 1 ? log.MedianDt() : 0.0;
  s.imu_rate_hz = dt > 0.0 ? 1.0 / dt : 0.0;
  s.rotor_signal = IsCommandSignal(log) ? (log.voltage_v ? "command+voltage" : "command") : "rpm";
  DescribeSources(log, s.format, &s);
  AddNotes(log, s.format, &s);
  s.used_s = log.duration_s();
  s.kept = {{s.log_start_s, s.log_end_s}};
  s.segment_mode = "none";
  return s;
}

SelectedFlight SelectFlight(FlightLog log, const std::string& path, const std::optional<TimeWindow>& asked_window,
                            SegmentMode mode, const std::optional<SegmentationOptions>& segmentation_options) {
  SelectedFlight selected;
  FlightInputSummary& s = selected.summary;
  s = DescribeFlightInput(log, path);
  s.window = OnTheLogsTimes(log, asked_window);
  s.segment_mode = mode == SegmentMode::kAuto ? "auto" : "none";
  s.kept.clear();

  FlightLog cut = std::move(log);
  const std::optional<TimeWindow> window = OnTheLogsTimes(cut, asked_window);
  if (window) {
    const Eigen::VectorXd& t = cut.t_s;
    const int begin = static_cast<int>(std::lower_bound(t.data(), t.data() + t.size(), window->start_s) - t.data());
    const int end = static_cast<int>(std::upper_bound(t.data(), t.data() + t.size(), window->end_s) - t.data());
    if (end - begin < 2) {
      throw Error(path + ": --window " + FormatValue("%g", window->start_s) + "," + FormatValue("%g", window->end_s) +
                  " holds no samples; the log spans " + FormatValue("%.3f", s.log_start_s) + " - " +
                  FormatValue("%.3f s", s.log_end_s) + " (its own time base)");
    }
    if (begin > 0) s.left_out.push_back({t[0], t[begin - 1], "outside --window", ""});
    if (end < t.size()) s.left_out.push_back({t[end], t[t.size() - 1], "outside --window", ""});
    cut = cut.Slice(begin, end);
  }

  if (mode == SegmentMode::kNone) {
    s.kept.push_back({cut.t_s[0], cut.t_s[cut.num_samples() - 1]});
    s.used_s = cut.duration_s();
    selected.segments.push_back(std::move(cut));
    return selected;
  }

  // A blackbox log is an FPV quad, often thrown or self-launched: the general take-off margin
  // would swallow its first, most excited second (docs/blackbox.md 4).
  const bool thrown = !segmentation_options && s.format == "blackbox";
  const SegmentationOptions segmentation = segmentation_options ? *segmentation_options
                                           : thrown             ? ThrownQuadSegmentationOptions()
                                                                : SegmentationOptions{};
  const Segmentation segments = thrown ? SegmentThrownFlight(cut, segmentation) : SegmentFlight(cut, segmentation);
  for (const ExcludedSpan& e : segments.excluded)
    s.left_out.push_back({e.t_begin_s, e.t_end_s, ToString(e.reason), e.detail});
  std::sort(s.left_out.begin(), s.left_out.end(),
            [](const LeftOutStretch& a, const LeftOutStretch& b) { return a.start_s < b.start_s; });
  if (segments.kept.empty()) {
    throw Error(path + ": --segment auto found no airborne, unsaturated stretch of at least " +
                FormatValue("%g s", segmentation.min_segment_s) + " in " + FormatValue("%.3f", cut.t_s[0]) + " - " +
                FormatValue("%.3f s", cut.t_s[cut.num_samples() - 1]) +
                "; choose the flight with --window START,END or use --segment none");
  }
  selected.segments = KeptSegments(std::move(cut), segments);
  s.used_s = 0.0;
  for (FlightLog& segment : selected.segments) {
    s.kept.push_back({segment.t_s[0], segment.t_s[segment.num_samples() - 1]});
    s.used_s += segment.duration_s();
    // Messages about a segment name its stretch of the file.
    if (selected.segments.size() > 1 || !segments.excluded.empty() || window)
      segment.source = path + " [" + FormatValue("%.2f", s.kept.back().start_s) + "-" +
                       FormatValue("%.2f s", s.kept.back().end_s) + "]";
  }
  return selected;
}

}  // namespace rotorid

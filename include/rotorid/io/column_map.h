#pragma once

// CSV exports of other tools, read through a column map: a small YAML file that says which
// columns hold rotorid's quantities and in which units, so a user never rewrites a file.
//
//   time:   {column: t_us, unit: us}                              # s, ms, us, ns
//   gyro:   {columns: [gyro.x, gyro.y, gyro.z], unit: deg/s}      # rad/s, deg/s
//   acc:    {columns: [acc.x, acc.y, acc.z], unit: g}             # m/s^2, g
//   rotors: {columns: [rpm.m1, rpm.m2, rpm.m3, rpm.m4], unit: rpm}
//   frame: flu                                                    # or frd: (x, -y, -z)
//
// The full reference, with optional keys (rotor_commands, position, quaternion, euler, voltage,
// world_frame, delimiter, comment, skip_lines, gravity, metadata), is docs/input_formats.md.

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rotorid/core/flight_log.h"

namespace rotorid {

// Where a value was written in the map file, for messages.
struct MapLocation {
  int line = 0;    // 1-based; 0 = unknown
  int column = 0;  // 1-based
};

// One quantity: which CSV columns hold it and how a raw value v becomes rotorid's unit:
// SI (or normalised command) = (v * scale - range_low) / (range_high - range_low) for commands,
// and v * scale * unit_factor otherwise.
struct MappedQuantity {
  std::vector<std::string> columns;  // CSV header names, in rotorid's order (x, y, z / w, x, y, z / rotor 1..N)
  std::vector<MapLocation> column_locations;
  std::string unit;          // as written in the map ("" where a quantity has no unit)
  double unit_factor = 1.0;  // to SI
  double scale = 1.0;        // user factor applied to raw values first (key `scale`)
  bool is_command = false;   // rotor units pwm, us, normalized, percent
  double range_low = 0.0;    // command range mapped to [0, 1] (key `range`)
  double range_high = 1.0;
  MapLocation location;  // of the quantity's key
};

enum class BodyFrame { kFlu, kFrd };
enum class WorldFrame { kZUp, kNed };

struct ColumnMap {
  std::string source;  // the map file, for messages
  MappedQuantity time, gyro, acc;
  std::optional<MappedQuantity> rotors;          // speeds or commands, by unit
  std::optional<MappedQuantity> rotor_commands;  // a second rotor signal: commands only
  std::optional<MappedQuantity> position, quaternion, euler, voltage;
  BodyFrame frame = BodyFrame::kFlu;
  WorldFrame world_frame = WorldFrame::kZUp;  // default: NED when frame is frd, else z up
  char delimiter = ',';
  bool whitespace_delimited = false;       // delimiter "whitespace": runs of spaces and tabs
  std::string comment = "#";               // lines starting with it are skipped ("" = none)
  int skip_lines = 0;                      // lines skipped before the header
  double gravity_mps2 = kStandardGravity;  // for unit g; also the log's gravity
  std::map<std::string, std::string> metadata;
};

// Reads a column map. Throws rotorid::Error "<map>:<line>:<column>: <what>".
ColumnMap ReadColumnMap(const std::string& path);
ColumnMap ParseColumnMap(const std::string& yaml_text, const std::string& source_name);

// Reads a CSV through a map into one flight. `num_rotors` is the vehicle's rotor count (-1: as
// many as the map lists). `rotor_signal` is FlightSourceOptions::rotor_signal: "auto" (speed
// when the map has one, else the command), "rpm" (speed only) or "command". Commands land in
// the rotor columns normalised to [0, 1], with metadata `rotor_signal: command`. Throws
// rotorid::Error naming "<csv>:<line>:<column>" for the data and "<map>:<line>:<column>" for
// the map entry involved.
FlightLog ReadMappedCsv(const std::string& csv_path, const ColumnMap& map, int num_rotors = -1,
                        const std::string& rotor_signal = "auto");
FlightLog ParseMappedCsv(std::string_view csv_text, const std::string& source_name, const ColumnMap& map,
                         int num_rotors = -1, const std::string& rotor_signal = "auto");

}  // namespace rotorid

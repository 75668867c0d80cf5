#pragma once

// One entry point for every log format rotorid reads: the format is recognised from the file's
// first bytes (PX4 ULog, Crazyflie micro-SD, Betaflight/INAV blackbox) and falls back to the CSV of INTERFACE.md.

#include <string>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"

namespace rotorid {

enum class LogFormat { kCsv, kULog, kCrazyflieUsd, kBlackbox };

struct FlightSourceOptions {
  // Which rotor signal to use where a log has several: "auto" (measured speed when present,
  // else the command), "rpm" (measured speed only) or "command".
  std::string rotor_signal = "auto";
  // A column-map file for CSV exports of other tools (empty: the CSV of INTERFACE.md).
  std::string column_map_path;

  std::string Validate() const;
};

LogFormat DetectLogFormat(const std::string& path);

// Whether the log's rotor columns hold a motor command rather than a measured speed.
bool RotorSignalIsCommand(const FlightLog& log);
// Replaces a command log's rotor columns by map(u) (rad/s) and says so in the metadata.
void ApplyCommandToSpeed(const CommandToSpeed& map, FlightLog* log);
// Reads any supported log into one flight on one time base. When the rotor signal is a command
// and the vehicle has a command_to_speed map, the rotor columns become the mapped speed. Throws
// rotorid::Error naming the file and what is wrong.
FlightLog LoadFlightLog(const std::string& path, const Vehicle& vehicle, const FlightSourceOptions& options = {});
// The same without the command_to_speed map: the rotor columns as the log holds them.
FlightLog LoadFlightLogAsRecorded(const std::string& path, const Vehicle& vehicle,
                                  const FlightSourceOptions& options = {});

}  // namespace rotorid

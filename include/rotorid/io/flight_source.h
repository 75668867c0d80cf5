#pragma once

// One entry point for every log format rotorid reads: the format is recognised from the file's
// first bytes (PX4 ULog, Crazyflie micro-SD) and falls back to the CSV of INTERFACE.md.

#include <string>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"

namespace rotorid {

enum class LogFormat { kCsv, kULog, kCrazyflieUsd };

struct FlightSourceOptions {
  // Which rotor signal to use where a log has several: "auto" (measured speed when present,
  // else the command), "rpm" (measured speed only) or "command".
  std::string rotor_signal = "auto";
  // A column-map file for CSV exports of other tools (empty: the CSV of INTERFACE.md).
  std::string column_map_path;

  std::string Validate() const;
};

LogFormat DetectLogFormat(const std::string& path);
// Reads any supported log into one flight on one time base. Throws rotorid::Error naming the
// file and what is wrong.
FlightLog LoadFlightLog(const std::string& path, const Vehicle& vehicle, const FlightSourceOptions& options = {});

}  // namespace rotorid

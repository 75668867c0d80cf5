#pragma once

#include <string>

#include "rotorid/core/flight_log.h"

namespace rotorid {

// Reads a flight log CSV (INTERFACE.md section 2). `num_rotors` is the vehicle's rotor count;
// rotor_1..rotor_N must all be present (-1: take every rotor_k column found, k = 1, 2, ...).
// Throws rotorid::Error naming file, line and column for anything malformed.
FlightLog ReadFlightCsv(const std::string& path, int num_rotors = -1);
FlightLog ParseFlightCsv(const std::string& text, const std::string& source_name, int num_rotors = -1);

// The CSV text of a log (metadata as '# key: value' lines) and its atomic write.
std::string FlightLogToCsv(const FlightLog& log);
void WriteFlightCsv(const std::string& path, const FlightLog& log);

// The fewest samples a flight log may have.
inline constexpr int kMinFlightSamples = 20;

}  // namespace rotorid

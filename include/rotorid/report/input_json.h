#pragma once

// input.flights[] of every report (INTERFACE.md 5, v2): what each log gave and which part was used.

#include <nlohmann/json.hpp>
#include <vector>

#include "rotorid/io/flight_selection.h"

namespace rotorid {

nlohmann::json FlightInputJson(const FlightInputSummary& summary);
// {"flights": [...], "validate_flights": [...]} (the second only when held-out logs were read).
nlohmann::json InputJson(const std::vector<FlightInputSummary>& flights,
                         const std::vector<FlightInputSummary>& validate_flights = {});

}  // namespace rotorid

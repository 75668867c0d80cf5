#pragma once

// `rotorid delay` (INTERFACE.md 4): the command-to-IMU delay of the flights with its std, a global
// search of the TLS criterion, then the joint refinement.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
#include "rotorid/refine/delay.h"

namespace rotorid {

struct DelayCommandOptions {
  CommandInputOptions input;
  IdentifyOptions identify;
  DelayOptions delay;
};

struct DelayCommandResult {
  DelayCommandOptions options;
  LoadedFlights loaded;
  IdentificationResult linear;
  DelayEstimate estimate;
  std::vector<Check> checks;
};

DelayCommandResult RunDelay(const DelayCommandOptions& options);
// The estimate (DelayJson), settings (the search range as settings.delay_search_s), linear, checks.
nlohmann::json DelayJson(const DelayCommandResult& result);
ReportInput DelayReportInput(const DelayCommandResult& result);
std::string WriteDelayReport(const DelayCommandResult& result);
std::string DelayBrief(const DelayCommandResult& result);

}  // namespace rotorid

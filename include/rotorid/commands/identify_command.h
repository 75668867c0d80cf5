#pragma once

// `rotorid identify` (INTERFACE.md 4, 5): the paper's IDIM-TLS on the given flights, with the checks.
//
//   IdentifyCommandOptions options;
//   options.input.training = {{"A.yaml"}, {"A.csv"}};
//   const IdentifyCommandResult result = RunIdentify(options);
//   WriteJsonFile("identify.json", IdentifyJson(result));

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
#include "rotorid/ident/identify.h"

namespace rotorid {

struct IdentifyCommandOptions {
  CommandInputOptions input;
  IdentifyOptions identify;
};

struct IdentifyCommandResult {
  IdentifyCommandOptions options;
  LoadedFlights loaded;  // what was read (its flights moved into `linear`)
  size_t num_flights = 0;
  IdentificationResult linear;
  std::vector<Check> checks;
};

IdentifyCommandResult RunIdentify(const IdentifyCommandOptions& options);

// The report: settings, linear, checks, input (INTERFACE.md 5).
nlohmann::json IdentifyJson(const IdentifyCommandResult& result);
// The HTML report's input (pointing into `result`), and the report written into
// options.input.report_dir (its path; "" without a folder).
ReportInput IdentifyReportInput(const IdentifyCommandResult& result);
std::string WriteIdentifyReport(const IdentifyCommandResult& result);
// For the console: the method and data, the parameter table and Table III.
std::string IdentifyBrief(const IdentifyCommandResult& result);

}  // namespace rotorid

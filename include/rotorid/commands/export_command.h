#pragma once

// rotorid export as a library call (docs/simulators.md): a report's model resolved (every number
// fixed, the body physically possible) and written in one simulator format.

#include <string>
#include <vector>

#include "rotorid/report/export.h"

namespace rotorid {

struct ExportCommandOptions {
  std::string params_path;             // identify or refine report
  std::string vehicle_path;            // the vehicle file of its configuration
  std::string format;                  // ExportFormatNames()
  std::string out;                     // file, or directory for gz and gazebo-classic
  std::string block;                   // "linear", "refined", or "" for refined when present
  double max_rotor_speed_radps = 0.0;  // 0: the vehicle's command_to_speed at u = 1
  std::vector<std::string> settings;   // NAME=VALUE (ParseExportSetting)
  bool force = false;                  // export a report that failed its checks
};

struct ExportCommandResult {
  ExportFormat format = ExportFormat::kYaml;
  ExportModel model;
};

// Reads the report and vehicle file, resolves the model and writes it; throws rotorid::Error
// naming the file or the parameter at fault.
ExportCommandResult RunExportCommand(const ExportCommandOptions& options);

// "rotorid export: <block> parameters of <params> as <format> -> <out>", then where each value
// came from.
std::string ExportConsoleText(const ExportCommandOptions& options, const ExportCommandResult& result);

}  // namespace rotorid

#include "rotorid/commands/export_command.h"

#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/report/json.h"

namespace rotorid {

ExportCommandResult RunExportCommand(const ExportCommandOptions& options) {
  const IdentifiedModel identified = IdentifiedModelFromReport(ReadJsonFile(options.params_path), options.params_path,
                                                               ReadVehicleYaml(options.vehicle_path), options.block);
  ExportOptions export_options;
  export_options.force = options.force;
  if (options.max_rotor_speed_radps > 0.0) export_options.set["max_rotor_speed"] = options.max_rotor_speed_radps;
  for (const std::string& setting : options.settings) export_options.set.insert(ParseExportSetting(setting));
  ExportCommandResult result;
  result.format = ParseExportFormat(options.format);
  result.model = ResolveExportModel(identified, export_options);
  WriteExportedFiles(ExportFiles(result.model, result.format), options.out, ExportWritesDirectory(result.format));
  return result;
}

std::string ExportConsoleText(const ExportCommandOptions& options, const ExportCommandResult& result) {
  std::string text = "rotorid export: " + result.model.block + " parameters of " + options.params_path + " as " +
                     ExportFormatName(result.format) + " -> " + options.out + "\n";
  for (const std::string& line : result.model.provenance) text += "  " + line + "\n";
  return text;
}

}  // namespace rotorid

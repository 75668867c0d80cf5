#include "rotorid/io/flight_source.h"

#include <fstream>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/io/blackbox.h"
#include "rotorid/io/blackbox_flight.h"
#include "rotorid/io/column_map.h"
#include "rotorid/io/crazyflie_flight.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/io/px4_flight.h"
#include "rotorid/io/rotor_signal.h"

namespace rotorid {

std::string FlightSourceOptions::Validate() const { return RotorSignalProblem(rotor_signal); }

LogFormat DetectLogFormat(const std::string& path) {
  // Before any reader: a device (/dev/zero), a FIFO or an oversized file is refused by its path.
  RequireInputFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  char head[256] = {};
  in.read(head, sizeof(head));
  const std::string magic(head, static_cast<size_t>(in.gcount()));
  if (magic.size() >= 7 && magic.compare(0, 4, "ULog") == 0) return LogFormat::kULog;
  if (!magic.empty() && static_cast<unsigned char>(magic[0]) == 0xBC) return LogFormat::kCrazyflieUsd;
  if (LooksLikeBlackbox(magic)) return LogFormat::kBlackbox;
  return LogFormat::kCsv;
}

bool RotorSignalIsCommand(const FlightLog& log) {
  const auto is = [&](const char* key, const char* value) {
    const auto it = log.metadata.find(key);
    return it != log.metadata.end() && it->second == value;
  };
  return is("rotor_signal", "command") || is("px4_rotor_signal", "command");
}

void ApplyCommandToSpeed(const CommandToSpeed& map, FlightLog* log) {
  log->rotor_command = log->rotor_radps;
  log->rotor_radps = log->rotor_radps.unaryExpr([&](double u) { return map(u); });
  const Eigen::Vector3d& c = map.coefficients;
  log->metadata["rotor_signal"] = "speed";
  log->metadata["command_to_speed"] = "Omega = " + std::to_string(c[0]) + " + " + std::to_string(c[1]) + " u + " +
                                      std::to_string(c[2]) + " u^2 (vehicle file)";
}

FlightLog LoadFlightLog(const std::string& path, const Vehicle& vehicle, const FlightSourceOptions& options) {
  FlightLog log = LoadFlightLogAsRecorded(path, vehicle, options);
  if (vehicle.command_to_speed && RotorSignalIsCommand(log)) ApplyCommandToSpeed(*vehicle.command_to_speed, &log);
  return log;
}

FlightLog LoadFlightLogAsRecorded(const std::string& path, const Vehicle& vehicle, const FlightSourceOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw Error(problem);
  switch (DetectLogFormat(path)) {
    case LogFormat::kCsv:
      // Another tool's export: its columns and units come from the column map.
      if (!options.column_map_path.empty()) {
        return ReadMappedCsv(path, ReadColumnMap(options.column_map_path), vehicle.num_rotors(), options.rotor_signal);
      }
      return ReadFlightCsv(path, vehicle.num_rotors());
    case LogFormat::kULog: {
      // docs/px4_ulog.md: measured esc_rpm when present ("auto"), else the motor commands.
      Px4FlightOptions px4;
      if (options.rotor_signal == "rpm") px4.rotor = Px4RotorSource::kEscRpm;
      if (options.rotor_signal == "command") px4.rotor = Px4RotorSource::kCommand;
      return ReadPx4Flight(path, vehicle.num_rotors(), px4);
    }
    case LogFormat::kCrazyflieUsd: {
      CrazyflieFlightOptions crazyflie;
      crazyflie.rotor_signal = options.rotor_signal;
      return LoadCrazyflieFlight(path, vehicle.num_rotors(), crazyflie);
    }
    case LogFormat::kBlackbox: {
      // docs/blackbox.md: measured omega[]/eRPM[] when present ("auto"), else motor[] commands.
      BlackboxFlightOptions blackbox;
      blackbox.rotor_signal = options.rotor_signal;
      return LoadBlackboxFlight(path, vehicle.num_rotors(), blackbox);
    }
  }
  return {};
}

}  // namespace rotorid

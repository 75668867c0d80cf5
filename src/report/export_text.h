#pragma once

// Shared pieces of the export formats (rotorid/report/export.h): numbers that round-trip, XML
// escaping and the header every format writes. Internal to src/report.

#include <optional>
#include <string>
#include <vector>

#include "rotorid/report/export.h"

namespace rotorid::internal {

// x with 17 significant digits (reads back to the same double); throws rotorid::Error naming
// `quantity` when x is not finite, so that no export holds inf or nan.
std::string ExportNumber(const std::string& quantity, double x);

// Text for XML content and attribute values: & < > " ' escaped.
std::string XmlEscape(const std::string& text);
// `<!-- text -->` with no "--" inside (XML forbids it in comments).
std::string XmlComment(const std::string& text, int indent);

// What a format says about itself in its header.
struct ExportHeader {
  std::string format;                 // "gz-sim model", ...
  std::string units;                  // its units and frames
  std::string command_to_speed;       // the command-to-speed mapping it assumes
  std::vector<std::string> holds;     // identified effects it holds, and how
  std::vector<std::string> not_held;  // identified effects it cannot hold, and why
};
// The header lines (no comment markers): source, vehicle, units, mapping, effects held and not,
// provenance of the values, other identified effects, failing checks (export forced).
std::vector<std::string> HeaderLines(const ExportModel& model, const ExportHeader& header);

// A rotor of a simulator's fixed layout: its bearing seen from O_d (degrees from x_d towards
// starboard, as ArduPilot and PX4 draw their frames) and its spin (+1 counter-clockwise from above).
struct RotorSlot {
  double bearing_deg;
  int spin;
};
// For each slot, the index of the vehicle's rotor at that bearing (within 20 degrees) turning that
// way; empty when the vehicle is not that layout.
std::optional<std::vector<int>> MatchLayout(const Vehicle& vehicle, const std::vector<RotorSlot>& slots);
// Bearing of a point of F_d, as RotorSlot::bearing_deg.
double BearingDeg(const Eigen::Vector3d& p_m);

// The rotor speed at full command, or rotorid::Error naming what gives it.
double RequireMaxRotorSpeed(const ExportModel& model, const char* format);

// Per format (src/report/export_<target>.cc).
std::vector<ExportedFile> GzModel(const ExportModel& model);
std::vector<ExportedFile> GazeboClassicModel(const ExportModel& model);
std::vector<ExportedFile> Px4Parameters(const ExportModel& model);
std::vector<ExportedFile> Px4SihParameters(const ExportModel& model);
std::vector<ExportedFile> ArduPilotFrame(const ExportModel& model);

}  // namespace rotorid::internal

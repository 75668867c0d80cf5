#include "export_text.h"

#include <cmath>
#include <cstdio>

#include "report/html_text.h"
#include "rotorid/core/error.h"
#include "rotorid/core/text.h"
#include "rotorid/core/units.h"

namespace rotorid::internal {

std::string ExportNumber(const std::string& quantity, double x) {
  if (!std::isfinite(x)) throw Error("export: " + quantity + " would be " + ShortNumber(x) + " (not a finite number)");
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", x);
  return buffer;
}

// The same five characters as the HTML report's (&#39; is XML's character reference for ').
std::string XmlEscape(const std::string& text) { return Html(text); }

std::string XmlComment(const std::string& text, int indent) {
  std::string body = text;  // a comment is not parsed for entities: only "--" must go
  for (size_t at = body.find("--"); at != std::string::npos; at = body.find("--", at)) body.replace(at, 2, "- -");
  if (!body.empty() && body.back() == '-') body += ' ';
  return std::string(static_cast<size_t>(indent), ' ') + "<!-- " + body + " -->\n";
}

std::vector<std::string> HeaderLines(const ExportModel& model, const ExportHeader& header) {
  std::vector<std::string> lines = {"rotorid export: " + header.format + " of vehicle '" + model.vehicle.name +
                                        "' from " + model.source + " (" + model.block + " parameters)",
                                    "units: " + header.units, "command to speed: " + header.command_to_speed};
  for (const std::string& h : header.holds) lines.push_back("holds: " + h);
  for (const std::string& n : header.not_held) lines.push_back("cannot hold: " + n);
  for (const std::string& p : model.provenance) lines.push_back("value: " + p);
  for (const std::string& e : model.other_effects) lines.push_back("identified but held by no simulator format: " + e);
  for (const FailedCheck& c : model.failed_checks)
    lines.push_back("FAILED CHECK (exported anyway: forced): " + c.name + ": " + c.message);
  return lines;
}

// A stretched X (the TU Delft 3-inch quad's rotors at x +-45.5, y +-63.5 mm sit at 54 degrees) is still
// that X, its arms written as they are; a plus layout lies 45 degrees from an X's slots, a hexa's
// neighbours 60 degrees apart.
constexpr double kLayoutBearingToleranceDeg = 20.0;

double BearingDeg(const Eigen::Vector3d& p_m) { return std::atan2(-p_m.y(), p_m.x()) * 180.0 / M_PI; }

std::optional<std::vector<int>> MatchLayout(const Vehicle& vehicle, const std::vector<RotorSlot>& slots) {
  if (vehicle.num_rotors() != static_cast<int>(slots.size())) return std::nullopt;
  std::vector<int> match;
  for (const RotorSlot& slot : slots) {
    int found = -1;
    for (int i = 0; i < vehicle.num_rotors(); ++i) {
      const Rotor& r = vehicle.rotors[static_cast<size_t>(i)];
      const double difference = std::remainder(BearingDeg(r.position_m) - slot.bearing_deg, 360.0);
      if (r.position_m.head<2>().norm() > 0.0 && std::abs(difference) < kLayoutBearingToleranceDeg &&
          r.spin == slot.spin)
        found = i;
    }
    if (found < 0) return std::nullopt;
    match.push_back(found);
  }
  return match;
}

double RequireMaxRotorSpeed(const ExportModel& model, const char* format) {
  const double w = model.max_rotor_speed_radps;
  if (!(w > 0.0))
    throw Error(std::string(format) +
                " needs the rotor speed at full command (the simulator saturates there and maps commands to it): give "
                "--max-rotor-speed RAD_S (from a full-throttle thrust-stand run or log) or a command_to_speed map in "
                "the vehicle file");
  const double thrust = model.parameters.rotor.kt * w * w;
  if (!std::isfinite(w) || !std::isfinite(thrust))
    throw Error(std::string(format) + ": a rotor speed of " + ShortNumber(w) +
                " rad/s at full command gives a thrust of " + ShortNumber(thrust) +
                " N per rotor (not a finite number); give a real --max-rotor-speed");
  // A bound no rotor reaches (about ten million rpm), which keeps the integer PX4 ESC range in range.
  if (w > 1e6)
    throw Error(std::string(format) + ": a rotor speed of " + ShortNumber(w) +
                " rad/s at full command is no real rotor's (above 1e6 rad/s); give the real --max-rotor-speed");
  const double weight_share = model.parameters.mass_kg * kStandardGravity / model.vehicle.num_rotors();
  if (!(thrust > weight_share))
    throw Error(std::string(format) + ": at " + ShortNumber(w) + " rad/s a rotor gives " + ShortNumber(thrust) +
                " N, no more than its share of the weight (" + ShortNumber(weight_share) +
                " N): the vehicle could not hover; give the real --max-rotor-speed");
  return w;
}

}  // namespace rotorid::internal

#include "rotorid/io/rotor_signal.h"

namespace rotorid {

std::string RotorSignalProblem(const std::string& text) {
  if (text == "auto" || text == "rpm" || text == "command") return {};
  return "rotor signal must be auto, rpm or command, got '" + text + "'";
}

}  // namespace rotorid

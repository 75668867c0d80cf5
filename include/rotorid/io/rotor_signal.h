#pragma once

#include <string>

namespace rotorid {

// The rotor signal a reader takes (--rotor-signal): "auto" (the measured speed when the log has it,
// else the command), "rpm" or "command". Empty when `text` is one of them, else the message; every
// reader's options check it here.
std::string RotorSignalProblem(const std::string& text);

}  // namespace rotorid

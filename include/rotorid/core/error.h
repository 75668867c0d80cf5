#pragma once

#include <stdexcept>
#include <string>

namespace rotorid {

// Thrown for anything the user can fix: a malformed file, an invalid option, data that cannot
// support the requested estimate. The CLI prints what() on one line and exits non-zero; library
// code never exits the process.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "file:line:column: message" (line/column 1-based; 0 leaves them out).
std::string Located(const std::string& file, int line, int column, const std::string& message);

}  // namespace rotorid

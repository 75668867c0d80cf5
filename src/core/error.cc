#include "rotorid/core/error.h"

namespace rotorid {

std::string Located(const std::string& file, int line, int column, const std::string& message) {
  std::string where = file;
  if (line > 0) where += ":" + std::to_string(line);
  if (line > 0 && column > 0) where += ":" + std::to_string(column);
  return where + ": " + message;
}

}  // namespace rotorid

#include "rotorid/core/text.h"

#include <cstdio>

namespace rotorid {

std::string FormatValue(const char* printf_format, double value) {
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), printf_format, value);
  return buffer;
}

}  // namespace rotorid

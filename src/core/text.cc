#include "rotorid/core/text.h"

#include <cstdio>

namespace rotorid {

std::string FormatValue(const char* printf_format, double value) {
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), printf_format, value);
  return buffer;
}

std::string Join(const std::vector<std::string>& parts, const char* separator) {
  std::string out;
  for (const std::string& part : parts) out += (out.empty() ? "" : separator) + part;
  return out;
}

std::string ShortText(const std::string& text, size_t max_chars) {
  if (text.size() <= max_chars) return text;
  const size_t head = max_chars * 2 / 3, tail = max_chars - head;
  return text.substr(0, head) + " ... (" + std::to_string(text.size() - head - tail) + " characters left out) ... " +
         text.substr(text.size() - tail);
}

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace rotorid

#pragma once

// Numbers and lists in messages and reports.

#include <cstddef>
#include <string>
#include <vector>

namespace rotorid {

// `value` through a printf format with one floating-point conversion ("%.2f s", "%.3g").
std::string FormatValue(const char* printf_format, double value);
// Three significant digits, as messages quote measured values.
inline std::string ShortNumber(double value) { return FormatValue("%.3g", value); }
// "a, b, c".
std::string Join(const std::vector<std::string>& parts, const char* separator = ", ");
// `text` if at most `max_chars` long, else its start and end around "... (N characters left out)
// ...": a message quoting a cell or key of a malformed file stays one readable line.
std::string ShortText(const std::string& text, size_t max_chars = 1000);
bool EndsWith(const std::string& text, const std::string& suffix);

}  // namespace rotorid

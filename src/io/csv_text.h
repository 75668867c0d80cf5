#pragma once

// Reading the text tables rotorid takes (the flight-log CSV and column-mapped CSV exports):
// lines, cells, numbers, and the checks every flight read from text must pass. Internal to the
// library.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>

namespace rotorid::internal {

// `s` without leading spaces and tabs, and without trailing spaces, tabs and '\r'.
std::string_view TrimSpaces(std::string_view s);

struct TextLine {
  std::string_view text;  // without '\n' and one trailing '\r'
  int number = 0;         // 1-based
};

// Takes the next line off the front of `rest`, counting lines in `number`; false at the end.
bool NextLine(std::string_view* rest, int* number, TextLine* line);

// The whole cell as a number (fast_float's syntax), or nothing when it is empty or holds more
// than a number. Infinity and NaN parse: callers that refuse them say so in their own words.
std::optional<double> ParseNumber(std::string_view cell);
// The same, also nothing for infinity and NaN.
std::optional<double> ParseFiniteNumber(std::string_view cell);

// Throws rotorid::Error "<source>: too few samples (n); at least kMinFlightSamples are needed".
void RequireMinFlightSamples(const std::string& source, int num_samples);

// The first sample i whose time does not exceed the one before (t[i] <= t[i - 1], or NaN), or
// nothing when `t_s` increases strictly.
std::optional<int> FirstNonIncreasingTime(const Eigen::VectorXd& t_s);

}  // namespace rotorid::internal

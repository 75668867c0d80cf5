#pragma once

// Reading the text tables rotorid takes (the flight-log CSV and column-mapped CSV exports):
// lines, cells, numbers, and the checks every flight read from text must pass. Internal to the
// library.

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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

// A time stamp in seconds as a coarse and a fine part whose sum is the stamp. A stamp of a wall clock
// (a UNIX epoch, 1.7e9 s) is split into whole seconds and the rest as the text gives them: one double
// resolves it only to 2.4e-7 s, 4.8e-5 of a 200 Hz interval, and the interval estimated from such
// stamps let the resampling grid drift off the samples (kd, I_zz -0.4 to -4 % on the bundled
// flights). A smaller stamp is its double alone (fine 0), as it always was.
struct TimeStamp {
  double coarse_s = 0.0;
  double fine_s = 0.0;
};
// Stamps at least this large are a wall clock rather than a time since boot (11.6 days).
constexpr double kWallClockStampS = 1e6;
// The cell (a number in units of `scale` x `unit_factor` seconds), or nothing when it holds no
// finite number.
std::optional<TimeStamp> ParseTimeStamp(std::string_view cell, double scale, double unit_factor);
// A log's times from its stamps. Wall-clock stamps become offsets from the first stamp, which is
// recorded as metadata 'time_origin_s' (its digits, e.g. "1772681685.527483940"); others are kept.
Eigen::VectorXd TimesFromStamps(const std::vector<TimeStamp>& stamps, std::map<std::string, std::string>* metadata);

// Throws rotorid::Error "<source>: too few samples (n); at least kMinFlightSamples are needed".
void RequireMinFlightSamples(const std::string& source, int num_samples);

// The first sample i whose time does not exceed the one before (t[i] <= t[i - 1], or NaN), or
// nothing when `t_s` increases strictly.
std::optional<int> FirstNonIncreasingTime(const Eigen::VectorXd& t_s);

}  // namespace rotorid::internal

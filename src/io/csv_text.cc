#include "io/csv_text.h"

#include <fast_float/fast_float.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <system_error>

#include "rotorid/core/error.h"
#include "rotorid/io/flight_csv.h"

namespace rotorid::internal {

std::string_view TrimSpaces(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

bool NextLine(std::string_view* rest, int* number, TextLine* line) {
  if (rest->empty()) return false;
  const size_t newline = rest->find('\n');
  std::string_view text = rest->substr(0, newline);
  *rest = newline == std::string_view::npos ? std::string_view() : rest->substr(newline + 1);
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  *line = {text, ++*number};
  return true;
}

std::optional<double> ParseNumber(std::string_view cell) {
  if (cell.empty()) return std::nullopt;
  double value = 0.0;
  const char* last = cell.data() + cell.size();
  const auto result = fast_float::from_chars(cell.data(), last, value);
  if (result.ec != std::errc() || result.ptr != last) return std::nullopt;
  return value;
}

std::optional<double> ParseFiniteNumber(std::string_view cell) {
  const std::optional<double> value = ParseNumber(cell);
  if (!value || !std::isfinite(*value)) return std::nullopt;
  return value;
}

namespace {

// The cell's digits split at the decimal point: the integer part exactly and the rest as a double of
// the integer part's sign. False for an exponent form or more integer digits than int64 holds.
bool SplitAtDecimalPoint(std::string_view cell, int64_t* integer, double* fraction) {
  if (cell.find_first_of("eE") != std::string_view::npos) return false;
  const size_t point = cell.find('.');
  std::string_view digits = cell.substr(0, point);
  const bool negative = !digits.empty() && digits.front() == '-';
  if (negative) digits.remove_prefix(1);
  *integer = 0;
  if (!digits.empty()) {
    const auto parsed = std::from_chars(digits.data(), digits.data() + digits.size(), *integer);
    if (parsed.ec != std::errc() || parsed.ptr != digits.data() + digits.size()) return false;
  }
  *fraction = 0.0;
  if (point != std::string_view::npos) {
    const std::optional<double> rest = ParseNumber("0" + std::string(cell.substr(point)));
    if (!rest) return false;
    *fraction = *rest;
  }
  if (negative) *integer = -*integer, *fraction = -*fraction;
  return true;
}

}  // namespace

std::optional<TimeStamp> ParseTimeStamp(std::string_view cell, double scale, double unit_factor) {
  const std::optional<double> value = ParseFiniteNumber(cell);
  if (!value) return std::nullopt;
  const double seconds = *value * scale * unit_factor;
  if (std::abs(seconds) < kWallClockStampS) return TimeStamp{seconds, 0.0};
  // Whole units per second (1 for s, 1000 for ms, ...): whole seconds and the rest come out exactly.
  const double seconds_per_unit = scale * unit_factor, units_per_second = std::round(1.0 / seconds_per_unit);
  int64_t integer = 0;
  double fraction = 0.0;
  if (units_per_second >= 1.0 && units_per_second <= 1e18 &&
      std::abs(units_per_second * seconds_per_unit - 1.0) < 1e-12 && SplitAtDecimalPoint(cell, &integer, &fraction)) {
    const auto per_second = static_cast<int64_t>(units_per_second);
    return TimeStamp{static_cast<double>(integer / per_second),
                     (static_cast<double>(integer % per_second) + fraction) / units_per_second};
  }
  // An exponent form or another scale: a long double's 64 bits resolve 1.7e9 s to 1.2e-10 s.
  const long double exact =
      std::strtold(std::string(cell).c_str(), nullptr) * static_cast<long double>(seconds_per_unit);
  const long double whole = std::trunc(exact);
  return TimeStamp{static_cast<double>(whole), static_cast<double>(exact - whole)};
}

Eigen::VectorXd TimesFromStamps(const std::vector<TimeStamp>& stamps, std::map<std::string, std::string>* metadata) {
  Eigen::VectorXd t(static_cast<Eigen::Index>(stamps.size()));
  if (stamps.empty()) return t;
  const TimeStamp first = stamps.front();
  const bool wall_clock = std::abs(first.coarse_s + first.fine_s) >= kWallClockStampS;
  for (size_t i = 0; i < stamps.size(); ++i)
    t[static_cast<Eigen::Index>(i)] = wall_clock
                                          ? (stamps[i].coarse_s - first.coarse_s) + (stamps[i].fine_s - first.fine_s)
                                          : stamps[i].coarse_s + stamps[i].fine_s;
  if (wall_clock) {
    char origin[64];
    std::snprintf(origin, sizeof(origin), "%.9Lf",
                  static_cast<long double>(first.coarse_s) + static_cast<long double>(first.fine_s));
    (*metadata)["time_origin_s"] = origin;
  }
  return t;
}

void RequireMinFlightSamples(const std::string& source, int num_samples) {
  if (num_samples < kMinFlightSamples) {
    throw Error(source + ": too few samples (" + std::to_string(num_samples) + "); at least " +
                std::to_string(kMinFlightSamples) + " are needed");
  }
}

std::optional<int> FirstNonIncreasingTime(const Eigen::VectorXd& t_s) {
  for (int i = 1; i < t_s.size(); ++i) {
    if (!(t_s[i] > t_s[i - 1])) return i;
  }
  return std::nullopt;
}

}  // namespace rotorid::internal

#include "io/csv_text.h"

#include <fast_float/fast_float.h>

#include <cmath>
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

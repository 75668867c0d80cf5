#pragma once

// The usage-error conventions (exit 2 before a command's options are validated, 1 after) and the
// parse-time checks of option values (apps/rotorid/usage.cc).

#include <CLI/CLI.hpp>
#include <functional>
#include <stdexcept>
#include <string>

namespace rotorid::cli {

// A mistake on the command line (exit code 2, INTERFACE.md 4). rotorid::Error thrown while a
// command still validates its options counts as one too: see MarkOptionsValidated.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Called once a command has validated its options and starts reading input: rotorid::Error from
// here on is bad input (exit 1), before it a usage error (exit 2).
void MarkOptionsValidated();
bool OptionsValidated();

// A CLI11 check (empty when valid, else the message) from a parser that throws rotorid::Error, so
// that a bad value is a usage error found while parsing.
template <class Parse>
std::function<std::string(const std::string&)> ParsesWith(Parse parse) {
  return [parse](const std::string& text) -> std::string {
    try {
      parse(text);
    } catch (const std::exception& e) {
      return e.what();
    }
    return {};
  };
}

// A CLI11 check: a number in [low, high] (NaN and infinities refused).
CLI::Validator Within(double low, double high);

}  // namespace rotorid::cli

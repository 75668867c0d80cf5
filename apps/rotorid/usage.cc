// The usage-error messages (docs/cli.md): which help to read, an unknown subcommand named, a value out of
// its range.

#include "commands.h"
#include "rotorid/core/text.h"

namespace rotorid::cli {

CLI::Validator Within(double low, double high) {
  return CLI::Validator(
      [low, high](const std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        if (!(value >= low && value <= high))  // NaN fails too
          return "must lie in [" + ShortNumber(low) + ", " + ShortNumber(high) + "], got " + text;
        return {};
      },
      "in [" + ShortNumber(low) + ", " + ShortNumber(high) + "]");
}

std::string UsageHint(const CLI::App& root, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    for (const CLI::App* sub : root.get_subcommands({}))
      if (sub->get_name() == argv[i]) return "run 'rotorid " + sub->get_name() + " --help' for its options";
  }
  return "run 'rotorid --help' for the subcommands";
}

std::string UnknownSubcommand(const CLI::App& root, int argc, char** argv) {
  std::string names;
  for (const CLI::App* sub : root.get_subcommands({})) names += (names.empty() ? "" : ", ") + sub->get_name();
  if (argc < 2) return "a subcommand is required: " + names;
  const std::string first = argv[1];
  if (!first.empty() && first[0] == '-') return {};
  for (const CLI::App* sub : root.get_subcommands({}))
    if (sub->get_name() == first) return {};
  return "unknown subcommand '" + first + "'; the subcommands are " + names;
}

}  // namespace rotorid::cli

// The usage-error messages (docs/cli.md): which help to read, and an unknown subcommand named.

#include "commands.h"

namespace rotorid::cli {

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

// The conventions every subcommand follows (docs/cli.md): output paths checked while parsing
// (before any work), effect lists checked while parsing, --config, and the usage-error message.

#include <unistd.h>

#include <filesystem>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/model/effects.h"

namespace rotorid::cli {

namespace {

namespace fs = std::filesystem;

std::string CheckOutputFile(const std::string& path) {
  if (path.empty()) return "an output file name must not be empty";
  std::error_code ec;
  if (fs::is_directory(path, ec)) return "'" + path + "' is a folder, not a file";
  const fs::path parent = fs::path(path).parent_path();
  const std::string folder = parent.empty() ? "." : parent.string();
  if (!fs::is_directory(folder, ec)) return "folder '" + folder + "' of '" + path + "' does not exist";
  if (::access(folder.c_str(), W_OK) != 0) return "folder '" + folder + "' of '" + path + "' is not writable";
  return {};
}

std::string CheckOutputFolder(const std::string& path) {
  if (path.empty()) return "a report folder name must not be empty";
  std::error_code ec;
  if (fs::exists(path, ec) && !fs::is_directory(path, ec)) return "'" + path + "' exists and is not a folder";
  return {};
}

}  // namespace

void ApplyConventions(const std::vector<Command>& commands) {
  for (const Command& command : commands) {
    for (const char* name : {"--json", "--out", "--truth", "--vehicle-out"})
      if (CLI::Option* option = command.app->get_option_no_throw(name)) option->check(CheckOutputFile);
    if (CLI::Option* option = command.app->get_option_no_throw("--report")) option->check(CheckOutputFolder);
    if (CLI::Option* option = command.app->get_option_no_throw("--effects")) option->check(ParsesWith(ParseEffectList));
  }
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

// The conventions every subcommand follows (docs/cli.md): output paths checked while parsing
// (before any work), effect lists checked while parsing, --config, and the usage-error message.

#include <utility>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/io/output_path.h"
#include "rotorid/model/effects.h"

namespace rotorid::cli {

namespace {

// The options naming a file the command writes, and the folder --report writes into.
constexpr const char* kOutputFileOptions[] = {"--json", "--out", "--truth", "--vehicle-out"};
constexpr const char* kOutputFolderOption = "--report";
// The options naming a file the command reads (--config is the root's). Only these: a value such
// as `--preset A` is no input even when a file A exists.
constexpr const char* kInputFileOptions[] = {"--vehicle", "--log",        "--validate-vehicle", "--validate-log",
                                             "--params",  "--column-map", "--manifest"};
constexpr int kMaxThreads = 256;

bool IsOutputOption(const std::string& name) {
  for (const char* output : kOutputFileOptions)
    if (name == output) return true;
  return name == kOutputFolderOption;
}

bool IsInputOption(const std::string& name) {
  for (const char* input : kInputFileOptions)
    if (name == input) return true;
  return false;
}

// Every (option, value) of `app` that names an output (or an input file, with the --config file of
// its parents).
std::vector<std::pair<std::string, std::string>> GivenPaths(const CLI::App& app, bool outputs) {
  std::vector<std::pair<std::string, std::string>> paths;
  for (const CLI::Option* option : app.get_options()) {
    if (option->count() == 0) continue;
    const std::string name = option->get_name();
    if (!(outputs ? IsOutputOption(name) : IsInputOption(name))) continue;
    for (const std::string& value : option->results()) paths.emplace_back(name, value);
  }
  if (!outputs)
    for (const CLI::App* parent = app.get_parent(); parent != nullptr; parent = parent->get_parent())
      if (const CLI::Option* config = parent->get_config_ptr(); config != nullptr && config->count() > 0)
        paths.emplace_back(config->get_name(), config->as<std::string>());
  return paths;
}

std::string Quoted(const std::pair<std::string, std::string>& option) {
  return option.first + " '" + option.second + "'";
}

}  // namespace

void CheckOutputsAgainstInputs(const CLI::App& app) {
  const auto outputs = GivenPaths(app, /*outputs=*/true);
  const auto inputs = GivenPaths(app, /*outputs=*/false);
  for (size_t i = 0; i < outputs.size(); ++i) {
    for (const auto& input : inputs)
      if (SameFile(outputs[i].second, input.second))
        throw UsageError(Quoted(outputs[i]) + " is the input " + Quoted(input) +
                         " (the same file): writing it would destroy the input; give another output path");
    for (size_t j = i + 1; j < outputs.size(); ++j)
      if (SameFile(outputs[i].second, outputs[j].second))
        throw UsageError(Quoted(outputs[i]) + " and " + Quoted(outputs[j]) +
                         " name the same file: one output would replace the other");
  }
}

void ApplyConventions(const std::vector<Command>& commands) {
  for (const Command& command : commands) {
    for (const char* name : kOutputFileOptions)
      if (CLI::Option* option = command.app->get_option_no_throw(name))
        option->check(command.out_may_be_folder && std::string(name) == "--out" ? OutputFileOrFolderProblem
                                                                                : OutputFileProblem);
    if (CLI::Option* option = command.app->get_option_no_throw(kOutputFolderOption)) option->check(OutputFolderProblem);
    if (CLI::Option* option = command.app->get_option_no_throw("--effects")) option->check(ParsesWith(ParseEffectList));
    // Each thread or job takes memory (a refinement's Jacobian, a process): 1e6 exhausted it.
    for (const char* name : {"--threads", "--jobs"})
      if (CLI::Option* option = command.app->get_option_no_throw(name)) option->check(Within(1, kMaxThreads));
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

// The conventions every subcommand follows (docs/cli.md): output paths checked while parsing
// (before any work), effect lists and thread counts checked while parsing.

#include <algorithm>
#include <iterator>

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

template <size_t N>
bool OneOf(const std::string& name, const char* const (&names)[N]) {
  return std::find(std::begin(names), std::end(names), name) != std::end(names);
}

// Every (option, value) of `app` that names an output (or an input file, with the --config file of
// its parents).
std::vector<OptionPath> GivenPaths(const CLI::App& app, bool outputs) {
  std::vector<OptionPath> paths;
  for (const CLI::Option* option : app.get_options()) {
    if (option->count() == 0) continue;
    const std::string name = option->get_name();
    if (!(outputs ? OneOf(name, kOutputFileOptions) || name == kOutputFolderOption : OneOf(name, kInputFileOptions)))
      continue;
    for (const std::string& value : option->results()) paths.emplace_back(name, value);
  }
  if (!outputs)
    for (const CLI::App* parent = app.get_parent(); parent != nullptr; parent = parent->get_parent())
      if (const CLI::Option* config = parent->get_config_ptr(); config != nullptr && config->count() > 0)
        paths.emplace_back(config->get_name(), config->as<std::string>());
  return paths;
}

}  // namespace

void CheckOutputsAgainstInputs(const CLI::App& app) {
  const std::string problem = OutputsAgainstInputsProblem(GivenPaths(app, /*outputs=*/true), GivenPaths(app, false));
  if (!problem.empty()) throw UsageError(problem);
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

}  // namespace rotorid::cli

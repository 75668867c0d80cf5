// rotorid batch: one subcommand over the logs of a manifest, one JSON line per entry
// (rotorid/commands/batch_command.h).

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/commands/batch_command.h"

namespace rotorid::cli {

Command AddBatchCommand(CLI::App& root) {
  auto options = std::make_shared<BatchCommandOptions>();
  Command command;
  command.app = root.add_subcommand(
      "batch",
      "runs one subcommand over the logs of a YAML manifest: one JSON line per entry (failures with their "
      "reason), parallel jobs, shards for array jobs, resumable");
  CLI::App* app = command.app;
  app->add_option("--manifest", options->manifest, "YAML manifest: logs: [{vehicle, log, window, options}]")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--out", options->out, "JSON lines output; entries already in it are skipped (resume)")->required();
  app->add_option("--command", options->command, "subcommand run on each entry")
      ->check(CLI::IsMember({"identify", "refine", "delay", "ablate", "diagnose", "validate"}))
      ->capture_default_str();
  app->add_option("--jobs", options->jobs, "entries run in parallel")->capture_default_str();
  app->add_option("--shard", options->shard, "I/N: run only every N-th entry from the I-th (array jobs)")
      ->check(ParsesWith(ParseBatchShard))
      ->capture_default_str();
  app->add_flag("--quiet,-q", options->quiet, "print nothing but errors");
  command.run = [options]() {
    if (const std::string problem = options->Validate(); !problem.empty()) throw UsageError(problem);
    MarkOptionsValidated();
    if (!options->quiet)
      options->note = [](const std::string& note) { std::cerr << "rotorid: note: " << note << "\n"; };
    const BatchCommandResult result = RunBatchCommand(*options);
    if (!options->quiet) std::cout << BatchSummaryLine(*options, result) << "\n";
    return result.failed > 0 ? 1 : 0;
  };
  return command;
}

}  // namespace rotorid::cli

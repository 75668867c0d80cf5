#pragma once

// rotorid batch as a library call (INTERFACE.md 4): one subcommand over the logs of a manifest,
// one JSON line per entry. Each entry runs as its own rotorid process (`executable`), so a crash or
// a bad log fails that entry only and its line holds exactly what the subcommand's --json writes.
// The output is locked against a second batch, appended one whole line at a time and resumed by
// (log, vehicle, window, options); an entry stopped by SIGINT or SIGTERM is not recorded, so a
// rerun runs it again.

#include <cstddef>
#include <functional>
#include <string>

#include "rotorid/io/batch_manifest.h"

namespace rotorid {

struct BatchCommandOptions {
  std::string manifest;
  std::string out;
  std::string command = "identify";
  int jobs = 1;
  std::string shard = "1/1";
  bool quiet = false;  // no progress line
  // The rotorid binary each entry runs.
  std::string executable = "/proc/self/exe";
  // Told what the run does beyond its lines (incomplete lines of an earlier run dropped).
  std::function<void(const std::string&)> note = [](const std::string&) {};

  // Empty when valid, else what is wrong (a usage error).
  std::string Validate() const;
};

struct BatchCommandResult {
  BatchShard shard;
  size_t entries = 0;  // in the manifest
  size_t run = 0;      // run now
  size_t skipped = 0;  // already in the output
  size_t failed = 0;   // of those run
};

// Throws rotorid::Error naming the manifest or output at fault.
BatchCommandResult RunBatchCommand(const BatchCommandOptions& options);

// "rotorid batch: identify on 3 of 4 entries (shard 1/1, 1 already in the output): 2 ok, 1 failed -> out.jsonl"
std::string BatchSummaryLine(const BatchCommandOptions& options, const BatchCommandResult& result);

}  // namespace rotorid

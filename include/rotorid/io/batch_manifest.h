#pragma once

// The manifest of `rotorid batch` (INTERFACE.md 4, v2) and the bookkeeping that lets array jobs
// split it (--shard I/N) and a stopped run resume (entries already in the output are skipped).
//
//   logs:
//     - {vehicle: A.yaml, log: flights/a1.csv}
//     - {vehicle: A.yaml, log: flights/a2.ulg, window: [12.0, 80.0], options: {cutoff-hz: 8}}
//
// Relative paths are taken from the manifest's folder.

#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "rotorid/io/flight_selection.h"

namespace rotorid {

struct BatchEntry {
  std::string vehicle;
  std::string log;
  std::optional<TimeWindow> window;
  // Options of the subcommand, in the manifest's order: name (no dashes) and its values (one for
  // a scalar, several for a list; "true"/"false" for a flag).
  std::vector<std::pair<std::string, std::vector<std::string>>> options;

  // What identifies the entry in an output line: log, vehicle, window and options.
  std::string Key() const;
  // The options as an output line holds them: {name: [values]}.
  nlohmann::json OptionsJson() const;
};

// Throws rotorid::Error naming the manifest, line and column of what is wrong.
std::vector<BatchEntry> ReadBatchManifest(const std::string& path);
// The manifest `text` of the file `path` (relative paths are taken from its folder).
std::vector<BatchEntry> ParseBatchManifest(const std::string& text, const std::string& path);

struct BatchShard {
  int index = 1;  // 1-based
  int count = 1;
};
// "I/N" with 1 <= I <= N; throws rotorid::Error otherwise.
BatchShard ParseBatchShard(const std::string& text);
// The positions of the entries shard `shard` runs: every N-th from I-1, so shards are disjoint and
// together cover every entry.
std::vector<size_t> ShardEntries(size_t num_entries, const BatchShard& shard);

// The key of one output line ({"log", "vehicle", "window", "options"}), or nullopt for a line that
// does not parse (e.g. cut short when a run was stopped).
std::optional<std::string> BatchLineKey(const std::string& line);

// What an existing output file holds (nothing when it does not exist).
struct BatchOutput {
  std::set<std::string> done;  // keys of its complete lines
  std::string complete_lines;  // those lines, each with its newline
  int broken_lines = 0;        // lines cut short (a run stopped, a full disk) or not an output line
};
BatchOutput ReadBatchOutput(const std::string& output_path);

}  // namespace rotorid

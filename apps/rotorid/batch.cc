// rotorid batch: one subcommand over the logs of a manifest, one JSON line per entry. Each entry
// runs as its own rotorid process (the same binary), so a crash or a bad log fails that entry only
// and the lines are exactly what the subcommand's --json would write.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/io/batch_manifest.h"
#include "rotorid/report/progress.h"

extern char** environ;

namespace rotorid::cli {

namespace {

struct BatchOptions {
  std::string manifest;
  std::string out;
  std::string command = "identify";
  int jobs = 1;
  std::string shard = "1/1";
  bool quiet = false;
};

std::vector<std::string> EntryArguments(const std::string& command, const BatchEntry& entry,
                                        const std::string& json_path) {
  std::vector<std::string> args = {command, "--vehicle", entry.vehicle, "--log", entry.log};
  if (entry.window) {
    std::ostringstream window;
    window.precision(17);
    window << entry.window->start_s << "," << entry.window->end_s;
    args.insert(args.end(), {"--window", window.str()});
  }
  for (const auto& [name, values] : entry.options) {
    for (const std::string& value : values) {
      if (value == "false") continue;  // a flag left off
      args.push_back("--" + name);
      if (value != "true") args.push_back(value);
    }
  }
  args.insert(args.end(), {"--json", json_path, "--quiet"});
  return args;
}

// Runs this binary with `args`, stderr into `err_path`; returns the exit code (128 + signal).
int RunSelf(const std::vector<std::string>& args, const std::string& err_path) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv;
  static const std::string self = "/proc/self/exe";
  argv.push_back(const_cast<char*>(self.c_str()));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, self.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw Error("batch: cannot start rotorid: " + std::string(std::strerror(spawned)));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// The reason a failed entry gives: its last stderr line without the "rotorid: error: " prefix.
std::string FailureReason(const std::string& err_path, int exit_code) {
  std::ifstream in(err_path);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  const std::string prefix = "rotorid: error: ";
  if (last.rfind(prefix, 0) == 0) last = last.substr(prefix.size());
  return last.empty() ? "exit code " + std::to_string(exit_code) : last;
}

nlohmann::json RunEntry(const BatchOptions& options, const BatchEntry& entry, const std::string& scratch, size_t k) {
  const std::string json_path = scratch + "/entry" + std::to_string(k) + ".json";
  const std::string err_path = scratch + "/entry" + std::to_string(k) + ".err";
  const int exit_code = RunSelf(EntryArguments(options.command, entry, json_path), err_path);
  nlohmann::json line = {
      {"log", entry.log},
      {"vehicle", entry.vehicle},
      {"window", entry.window ? nlohmann::json{entry.window->start_s, entry.window->end_s} : nlohmann::json()},
      {"status", exit_code == 0 ? "ok" : "failed"},
      {"exit_code", exit_code}};
  if (exit_code != 0) line["error"] = FailureReason(err_path, exit_code);
  // Exit 3 (a physical check failed) still writes the report.
  if (std::ifstream report(json_path); report) line["report"] = nlohmann::json::parse(report, nullptr, false);
  std::filesystem::remove(json_path);
  std::filesystem::remove(err_path);
  return line;
}

// Appends one line with a single write, so that lines of parallel entries never interleave.
class LineWriter {
 public:
  explicit LineWriter(const std::string& path) : fd_(::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644)) {
    if (fd_ < 0) throw Error(path + ": cannot open for appending: " + std::strerror(errno));
  }
  ~LineWriter() { ::close(fd_); }
  LineWriter(const LineWriter&) = delete;
  LineWriter& operator=(const LineWriter&) = delete;
  void Write(const nlohmann::json& line) {
    const std::string text = line.dump() + "\n";
    std::lock_guard<std::mutex> lock(mutex_);
    if (::write(fd_, text.data(), text.size()) != static_cast<ssize_t>(text.size()))
      throw Error("cannot append to the batch output: " + std::string(std::strerror(errno)));
  }

 private:
  int fd_;
  std::mutex mutex_;
};

int RunBatch(const BatchOptions& options) {
  const BatchShard shard = ParseBatchShard(options.shard);
  if (options.jobs < 1) throw UsageError("--jobs must be at least 1");
  MarkOptionsValidated();
  const std::vector<BatchEntry> entries = ReadBatchManifest(options.manifest);
  const std::set<std::string> done = CompletedBatchEntries(options.out);
  std::vector<size_t> todo;
  size_t skipped = 0;
  for (size_t k : ShardEntries(entries.size(), shard)) {
    if (done.count(entries[k].Key()))
      ++skipped;
    else
      todo.push_back(k);
  }
  char scratch_template[] = "/tmp/rotorid-batch-XXXXXX";
  if (::mkdtemp(scratch_template) == nullptr) throw Error("batch: cannot create a scratch folder in /tmp");
  const std::string scratch = scratch_template;

  LineWriter writer(options.out);
  Progress progress("batch", static_cast<int64_t>(todo.size()), options.quiet);
  std::atomic<size_t> next{0}, finished{0}, failed{0};
  const auto worker = [&] {
    for (size_t i = next++; i < todo.size(); i = next++) {
      const nlohmann::json line = RunEntry(options, entries[todo[i]], scratch, todo[i]);
      if (line["status"] != "ok") ++failed;
      writer.Write(line);
      progress.Update(static_cast<int64_t>(++finished));
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::min<int>(options.jobs, static_cast<int>(todo.size())); ++j) threads.emplace_back(worker);
  for (std::thread& t : threads) t.join();
  progress.Finish();
  std::filesystem::remove_all(scratch);
  if (!options.quiet) {
    std::cout << "rotorid batch: " << options.command << " on " << todo.size() << " of " << entries.size()
              << " entries (shard " << shard.index << "/" << shard.count << ", " << skipped
              << " already in the output): " << todo.size() - failed << " ok, " << failed << " failed -> "
              << options.out << "\n";
  }
  return failed > 0 ? 1 : 0;
}

}  // namespace

Command AddBatchCommand(CLI::App& root) {
  auto options = std::make_shared<BatchOptions>();
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
  command.run = [options]() { return RunBatch(*options); };
  return command;
}

}  // namespace rotorid::cli

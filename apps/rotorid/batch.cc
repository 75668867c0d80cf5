// rotorid batch: one subcommand over the logs of a manifest, one JSON line per entry. Each entry
// runs as its own rotorid process (the same binary), so a crash or a bad log fails that entry only
// and the lines are exactly what the subcommand's --json would write.

#include <fcntl.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <exception>
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
      {"options", entry.OptionsJson()},
      {"status", exit_code == 0 ? "ok" : "failed"},
      {"exit_code", exit_code}};
  if (exit_code != 0) line["error"] = FailureReason(err_path, exit_code);
  // Exit 3 (a physical check failed) still writes the report.
  if (std::ifstream report(json_path); report) line["report"] = nlohmann::json::parse(report, nullptr, false);
  std::filesystem::remove(json_path);
  std::filesystem::remove(err_path);
  return line;
}

// The output file, locked against a second batch on it, appended one whole line at a time: a line
// of parallel entries never interleaves with another, and a line the disk could not take is cut
// off again, so that a resumed run finds only complete lines.
class LineWriter {
 public:
  explicit LineWriter(const std::string& path) : path_(path), fd_(Open(path)) {}
  ~LineWriter() { ::close(fd_); }
  LineWriter(const LineWriter&) = delete;
  LineWriter& operator=(const LineWriter&) = delete;

  // Replaces the content by `text` (the complete lines of an earlier run), still under the lock.
  void Rewrite(const std::string& text) {
    if (::ftruncate(fd_, 0) != 0 || !WriteAll(text)) throw Error(path_ + ": cannot rewrite: " + std::strerror(errno));
  }
  void Write(const nlohmann::json& line) {
    const std::string text = line.dump() + "\n";
    std::lock_guard<std::mutex> lock(mutex_);
    struct stat before {};
    ::fstat(fd_, &before);
    if (!WriteAll(text)) {
      const std::string reason = std::strerror(errno);
      // The partial line cut off again; should that fail too, the next run drops it (ReadBatchOutput).
      (void)!::ftruncate(fd_, before.st_size);
      throw Error(path_ + ": cannot append a line (" + reason + "); the lines before it are complete: run again to " +
                  "resume");
    }
  }

 private:
  static int Open(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(path + ": cannot open for appending: " + std::strerror(errno));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd);
      throw Error(path + ": another rotorid batch is writing to it; give each run its own --out");
    }
    return fd;
  }
  bool WriteAll(const std::string& text) {
    for (size_t done = 0; done < text.size();) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<size_t>(n);
    }
    return true;
  }
  const std::string path_;
  const int fd_;
  std::mutex mutex_;
};

// A scratch folder for the entries' reports, removed however the run ends.
class ScratchFolder {
 public:
  ScratchFolder() {
    char name[] = "/tmp/rotorid-batch-XXXXXX";
    if (::mkdtemp(name) == nullptr) throw Error("batch: cannot create a scratch folder in /tmp");
    path_ = name;
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Runs the entries on `jobs` threads; the first error (the output cannot be written) stops the
// others after their current entry and is thrown here.
size_t RunEntries(const BatchOptions& options, const std::vector<BatchEntry>& entries, const std::vector<size_t>& todo,
                  LineWriter* writer) {
  const ScratchFolder scratch;
  Progress progress("batch", static_cast<int64_t>(todo.size()), options.quiet);
  std::atomic<size_t> next{0}, finished{0}, failed{0};
  std::mutex error_mutex;
  std::exception_ptr error;
  const auto worker = [&] {
    try {
      for (size_t i = next++; i < todo.size(); i = next++) {
        const nlohmann::json line = RunEntry(options, entries[todo[i]], scratch.path(), todo[i]);
        if (line["status"] != "ok") ++failed;
        writer->Write(line);
        progress.Update(static_cast<int64_t>(++finished));
      }
    } catch (...) {
      next = todo.size();
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::min<int>(options.jobs, static_cast<int>(todo.size())); ++j) threads.emplace_back(worker);
  for (std::thread& t : threads) t.join();
  progress.Finish();
  if (error) std::rethrow_exception(error);
  return failed;
}

int RunBatch(const BatchOptions& options) {
  const BatchShard shard = ParseBatchShard(options.shard);
  if (options.jobs < 1) throw UsageError("--jobs must be at least 1");
  MarkOptionsValidated();
  const std::vector<BatchEntry> entries = ReadBatchManifest(options.manifest);
  for (const BatchEntry& entry : entries)
    for (const std::string& input : {entry.log, entry.vehicle})
      if (SameFile(options.out, input))
        throw Error(options.manifest + ": lists --out '" + options.out + "' as an input ('" + input +
                    "'): the output would destroy it; give another --out");
  LineWriter writer(options.out);
  const BatchOutput earlier = ReadBatchOutput(options.out);
  if (earlier.broken_lines > 0) {
    writer.Rewrite(earlier.complete_lines);
    if (!options.quiet)
      std::cerr << "rotorid: note: " << options.out << ": dropped " << earlier.broken_lines
                << " incomplete line(s) of an earlier run; their entries run again\n";
  }
  std::vector<size_t> todo;
  size_t skipped = 0;
  for (size_t k : ShardEntries(entries.size(), shard)) {
    if (earlier.done.count(entries[k].Key()))
      ++skipped;
    else
      todo.push_back(k);
  }
  const size_t failed = RunEntries(options, entries, todo, &writer);
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

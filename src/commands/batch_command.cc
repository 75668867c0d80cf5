#include "rotorid/commands/batch_command.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/temp_dir.h"
#include "rotorid/core/error.h"
#include "rotorid/core/interrupt.h"
#include "rotorid/core/process.h"
#include "rotorid/io/output_path.h"
#include "rotorid/report/progress.h"

namespace rotorid {

namespace {

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

nlohmann::json RunEntry(const BatchCommandOptions& options, const BatchEntry& entry, const std::string& scratch,
                        size_t k) {
  const std::string json_path = scratch + "/entry" + std::to_string(k) + ".json";
  ChildProcess child;
  child.executable = options.executable;
  child.argv = EntryArguments(options.command, entry, json_path);
  child.argv.insert(child.argv.begin(), options.executable);
  child.stderr_path = scratch + "/entry" + std::to_string(k) + ".err";
  const int exit_code = RunChildProcess(child).exit_code;
  // Not a result of the entry: recorded, it would be skipped when the run is resumed.
  if (IsInterruptExitCode(exit_code))
    throw Error("batch: the entry of " + entry.log + " with " + entry.vehicle + " was interrupted (exit code " +
                std::to_string(exit_code) + "); run again to resume");
  nlohmann::json line = {
      {"log", entry.log},
      {"vehicle", entry.vehicle},
      {"window", entry.window ? nlohmann::json{entry.window->start_s, entry.window->end_s} : nlohmann::json()},
      {"options", entry.OptionsJson()},
      {"status", exit_code == 0 ? "ok" : "failed"},
      {"exit_code", exit_code}};
  if (exit_code != 0) line["error"] = FailureReason(child.stderr_path, exit_code);
  // Exit 3 (a physical check failed) still writes the report.
  if (std::ifstream report(json_path); report) line["report"] = nlohmann::json::parse(report, nullptr, false);
  std::filesystem::remove(json_path);
  std::filesystem::remove(child.stderr_path);
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
    const InterruptDeferral whole;
    if (::ftruncate(fd_, 0) != 0 || !WriteAll(text)) throw Error(path_ + ": cannot rewrite: " + std::strerror(errno));
  }
  void Write(const nlohmann::json& line) {
    const std::string text = line.dump() + "\n";
    std::lock_guard<std::mutex> lock(mutex_);
    const InterruptDeferral whole;
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

// Runs the entries on `jobs` threads; the first error (the output cannot be written) stops the
// others after their current entry and is thrown here. Returns the number that failed.
size_t RunEntries(const BatchCommandOptions& options, const std::vector<BatchEntry>& entries,
                  const std::vector<size_t>& todo, LineWriter* writer) {
  // The entries' reports, removed however the run ends (also by the Ctrl-C cleanup).
  const internal::TempDir scratch("rotorid-batch");
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

}  // namespace

std::string BatchCommandOptions::Validate() const {
  try {
    ParseBatchShard(shard);
  } catch (const Error& e) {
    return e.what();
  }
  return jobs < 1 ? "--jobs must be at least 1" : "";
}

BatchCommandResult RunBatchCommand(const BatchCommandOptions& options) {
  BatchCommandResult result;
  result.shard = ParseBatchShard(options.shard);
  const std::vector<BatchEntry> entries = ReadBatchManifest(options.manifest);
  result.entries = entries.size();
  for (const BatchEntry& entry : entries)
    for (const std::string& input : {entry.log, entry.vehicle})
      if (SameFile(options.out, input))
        throw Error(options.manifest + ": lists --out '" + options.out + "' as an input ('" + input +
                    "'): the output would destroy it; give another --out");
  LineWriter writer(options.out);
  const BatchOutput earlier = ReadBatchOutput(options.out);
  if (earlier.broken_lines > 0) {
    writer.Rewrite(earlier.complete_lines);
    options.note(options.out + ": dropped " + std::to_string(earlier.broken_lines) +
                 " incomplete line(s) of an earlier run; their entries run again");
  }
  std::vector<size_t> todo;
  for (size_t k : ShardEntries(entries.size(), result.shard)) {
    if (earlier.done.count(entries[k].Key()))
      ++result.skipped;
    else
      todo.push_back(k);
  }
  result.run = todo.size();
  result.failed = RunEntries(options, entries, todo, &writer);
  return result;
}

std::string BatchSummaryLine(const BatchCommandOptions& options, const BatchCommandResult& result) {
  std::ostringstream line;
  line << "rotorid batch: " << options.command << " on " << result.run << " of " << result.entries << " entries (shard "
       << result.shard.index << "/" << result.shard.count << ", " << result.skipped
       << " already in the output): " << result.run - result.failed << " ok, " << result.failed << " failed -> "
       << options.out;
  return line.str();
}

}  // namespace rotorid

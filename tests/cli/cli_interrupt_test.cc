// Ctrl-C cleanup (docs/cli.md, "Interrupting a run"): an interrupted process removes the temporary
// files and folders it registered, stops its children and exits with 128 + the signal; a batch
// interrupted mid-sweep leaves no scratch folder, only complete lines, and resumes to the lines an
// uninterrupted run writes.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <utility>

#include "rotorid/core/interrupt.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

namespace fs = std::filesystem;
using testing::MakeTempDir;
using testing::RunRotorid;
using testing::Slurp;

std::vector<std::string> SortedLines(const std::string& path) {
  std::vector<std::string> lines;
  std::istringstream in(Slurp(path));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::sort(lines.begin(), lines.end());
  return lines;
}

std::vector<std::string> Entries(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  return names;
}

// Exit status of a process ended by a signal it did not handle: 128 + signal, as a shell gives.
int ExitCode(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status); }

// A process that registers a file and a folder (with content), tells the parent, and waits to be
// stopped: the cleanup removes both, keeps what is not registered, and exits 130 or 143.
void ExpectCleanupOn(int signal) {
  const std::string dir = MakeTempDir("rotorid-interrupt");
  const std::string file = dir + "/out.json.tmp.abc", folder = dir + "/scratch", kept = dir + "/kept";
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    InstallInterruptCleanup();
    std::ofstream(file) << "partial";
    fs::create_directories(folder + "/entry");
    std::ofstream(folder + "/entry/err") << "x";
    std::ofstream(kept) << "kept";
    RegisterTemporaryPath(file);
    RegisterTemporaryPath(folder);
    (void)!::write(ready[1], "r", 1);
    for (;;) ::pause();
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ASSERT_TRUE(fs::exists(file) && fs::exists(folder));
  ::kill(pid, signal);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_EQ(ExitCode(status), 128 + signal);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(folder));
  EXPECT_TRUE(fs::exists(kept));
  ::close(ready[0]);
  ::close(ready[1]);
  fs::remove_all(dir);
}

TEST(InterruptCleanupTest, SigintRemovesRegisteredPathsAndExits130) { ExpectCleanupOn(SIGINT); }
TEST(InterruptCleanupTest, SigtermRemovesRegisteredPathsAndExits143) { ExpectCleanupOn(SIGTERM); }

// Starts `rotorid args` with TMPDIR=`tmpdir`, stdout and stderr into files of `dir`.
pid_t StartRotorid(const std::vector<std::string>& args, const std::string& tmpdir, const std::string& dir) {
  const char* binary = std::getenv("ROTORID_BINARY");
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("TMPDIR", tmpdir.c_str(), 1);
    ::dup2(::open((dir + "/stdout").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 1);
    ::dup2(::open((dir + "/stderr").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 2);
    std::vector<char*> argv = {const_cast<char*>(binary)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(binary, argv.data());
    ::_exit(127);
  }
  return pid;
}

// A child process of `parent` (0 when it has none yet), from /proc/PID/stat's fourth field.
pid_t ChildOf(pid_t parent) {
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string stat = Slurp(entry.path().string() + "/stat");
    const size_t end_of_name = stat.rfind(')');
    if (end_of_name == std::string::npos) continue;
    std::istringstream fields(stat.substr(end_of_name + 1));
    std::string state;
    pid_t ppid = 0;
    if (fields >> state >> ppid && ppid == parent) return static_cast<pid_t>(std::stol(entry.path().filename()));
  }
  return 0;
}

// The second entry's vehicle file is a FIFO nobody writes: its process waits in open() until it is
// stopped, so the batch is certainly mid-sweep (one line written, an entry running, its scratch
// folder present) when it is interrupted: the batch itself with SIGINT or SIGTERM (exit 130/143), or
// only its entry's process (as when Ctrl-C reaches the entry first: exit 1 naming it).
TEST(CliInterruptTest, BatchInterruptedMidSweepLeavesNothingAndResumes) {
  if (std::getenv("ROTORID_BINARY") == nullptr) GTEST_SKIP() << "ROTORID_BINARY is not set";
  const std::string dir = MakeTempDir("rotorid-batch-interrupt");
  fs::create_directories(dir + "/tmp");
  for (const char* seed : {"1", "2"}) {
    const auto r = RunRotorid({"simulate", "--preset", "B", "--seconds", "6", "--seed", seed, "--out",
                               dir + "/f" + seed + ".csv", "--vehicle-out", dir + "/B.yaml", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::ofstream(dir + "/manifest.yaml") << "logs:\n  - {vehicle: B.yaml, log: f1.csv}\n"
                                        << "  - {vehicle: B2.yaml, log: f2.csv}\n";
  const std::vector<std::string> batch = {"batch", "--manifest", dir + "/manifest.yaml", "--out", dir + "/out.jsonl"};
  for (const auto& [signal, entry_only] : {std::pair{SIGINT, false}, {SIGTERM, false}, {SIGINT, true}}) {
    fs::remove(dir + "/out.jsonl");
    fs::remove(dir + "/B2.yaml");
    ASSERT_EQ(::mkfifo((dir + "/B2.yaml").c_str(), 0644), 0);
    const pid_t pid = StartRotorid(batch, dir + "/tmp", dir);
    // Should an assertion fail: no process left behind. A child waiting on the FIFO is woken by a
    // writer; one still to open it finds a file instead.
    struct Reaped {
      pid_t pid;
      std::string fifo;
      ~Reaped() {
        if (pid > 0 && ::kill(pid, SIGKILL) == 0) ::waitpid(pid, nullptr, 0);
        const int writer = ::open(fifo.c_str(), O_RDWR | O_NONBLOCK);
        std::ofstream(fifo + ".empty").flush();
        fs::rename(fifo + ".empty", fifo);
        if (writer >= 0) ::close(writer);
      }
    } reaped{pid, dir + "/B2.yaml"};
    // Until the first entry's line is written (the second entry has then started).
    int status = 0;
    while (Slurp(dir + "/out.jsonl").find('\n') == std::string::npos) {
      ASSERT_EQ(::waitpid(pid, &status, WNOHANG), 0) << Slurp(dir + "/stderr");
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_EQ(Entries(dir + "/tmp").size(), 1u);  // the scratch folder, to be removed
    pid_t entry = 0;
    while (entry_only && (entry = ChildOf(pid)) == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ::kill(entry_only ? entry : pid, signal);
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    reaped.pid = 0;
    const std::string err = Slurp(dir + "/stderr");
    EXPECT_EQ(ExitCode(status), entry_only ? 1 : 128 + signal) << err;
    if (entry_only) {
      EXPECT_NE(err.find("f2.csv with " + dir + "/B2.yaml was interrupted"), std::string::npos) << err;
    }
    EXPECT_TRUE(Entries(dir + "/tmp").empty());
    const std::vector<std::string> lines = SortedLines(dir + "/out.jsonl");
    ASSERT_EQ(lines.size(), 1u);  // the interrupted entry is not recorded
    EXPECT_EQ(nlohmann::json::parse(lines[0])["status"], "ok");
  }
  for (const std::string& name : Entries(dir)) EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;

  // Resumed with the vehicle file in place: the second entry runs, and the lines are those of an
  // uninterrupted run.
  fs::remove(dir + "/B2.yaml");
  fs::copy_file(dir + "/B.yaml", dir + "/B2.yaml");
  const auto resumed = RunRotorid(batch);
  EXPECT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("1 of 2 entries (shard 1/1, 1 already in the output): 1 ok"), std::string::npos)
      << resumed.out;
  const auto fresh = RunRotorid({"batch", "--manifest", dir + "/manifest.yaml", "--out", dir + "/fresh.jsonl"});
  EXPECT_EQ(fresh.exit_code, 0) << fresh.err;
  EXPECT_EQ(SortedLines(dir + "/out.jsonl"), SortedLines(dir + "/fresh.jsonl"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rotorid

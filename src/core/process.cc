#include "rotorid/core/process.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "rotorid/core/error.h"
#include "rotorid/core/interrupt.h"

extern char** environ;

namespace rotorid {

namespace {

pid_t Start(const ChildProcess& child) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, child.stdin_path.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, child.stdout_path.c_str(), O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, child.stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0600);
  // Default handling and an empty mask: this process blocks SIGINT and SIGTERM for its cleanup thread.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  std::vector<char*> argv;
  for (const std::string& arg : child.argv) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  // Started and registered with the cleanup deferred: an interruption between the two would miss it.
  const InterruptDeferral deferral;
  const int error = posix_spawn(&pid, child.executable.c_str(), &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (error != 0) throw Error("cannot start " + child.executable + ": " + std::strerror(error));
  RegisterChildProcess(pid);
  return pid;
}

}  // namespace

ChildExit RunChildProcess(const ChildProcess& child) {
  const pid_t pid = Start(child);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(child.timeout_s);
  ChildExit result;
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(pid, &status, child.timeout_s > 0.0 ? WNOHANG : 0);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) {
      UnregisterChildProcess(pid);
      throw Error("waiting for " + child.executable + " failed: " + std::strerror(errno));
    }
    if (child.timeout_s > 0.0 && std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      result.timed_out = true;
      break;
    }
    if (done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  UnregisterChildProcess(pid);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  return result;
}

}  // namespace rotorid

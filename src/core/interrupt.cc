#include "rotorid/core/interrupt.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <set>
#include <thread>

namespace rotorid {

namespace {

// Never destroyed: the cleanup thread may use it while static destructors run at exit.
struct Registry {
  std::recursive_mutex mutex;
  std::set<std::string> paths;
  std::set<pid_t> children;
};

Registry& TheRegistry() {
  static Registry* registry = new Registry;
  return *registry;
}

// Waits for a child stopped by the cleanup, and kills it once `deadline` has passed.
void AwaitChild(pid_t pid, std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    // ECHILD: the thread that started it has collected it already.
    const pid_t done = ::waitpid(pid, nullptr, WNOHANG);
    if (done == pid || (done < 0 && errno != EINTR)) return;
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
      }
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

[[noreturn]] void CleanUpAndExit(int signal) {
  Registry& registry = TheRegistry();
  // Held until _exit: no thread registers, starts a child or writes a line from here on.
  registry.mutex.lock();
  for (const pid_t pid : registry.children) ::kill(pid, signal);
  // A child (a batch entry) removes its own temporary files given the time; it may be writing into
  // a registered folder until it has exited.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  for (const pid_t pid : registry.children) AwaitChild(pid, deadline);
  for (const std::string& path : registry.paths) {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  const std::string message = std::string("rotorid: interrupted (") + (signal == SIGINT ? "SIGINT" : "SIGTERM") +
                              "): stopped; temporary files removed\n";
  (void)!::write(STDERR_FILENO, message.data(), message.size());
  ::_exit(128 + signal);
}

}  // namespace

void InstallInterruptCleanup() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  TheRegistry();
  std::thread([signals] {
    int signal = 0;
    while (sigwait(&signals, &signal) != 0) {
    }
    CleanUpAndExit(signal);
  }).detach();
}

InterruptDeferral::InterruptDeferral() : lock_(TheRegistry().mutex) {}
InterruptDeferral::~InterruptDeferral() = default;

void RegisterTemporaryPath(const std::string& path) {
  const InterruptDeferral deferral;
  TheRegistry().paths.insert(path);
}

void UnregisterTemporaryPath(const std::string& path) {
  const InterruptDeferral deferral;
  TheRegistry().paths.erase(path);
}

void RegisterChildProcess(pid_t pid) {
  const InterruptDeferral deferral;
  TheRegistry().children.insert(pid);
}

void UnregisterChildProcess(pid_t pid) {
  const InterruptDeferral deferral;
  TheRegistry().children.erase(pid);
}

bool IsInterruptExitCode(int exit_code) { return exit_code == 128 + SIGINT || exit_code == 128 + SIGTERM; }

}  // namespace rotorid

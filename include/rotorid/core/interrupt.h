#pragma once

// Ctrl-C cleanup (docs/cli.md, "Interrupting a run"): the temporary files and folders a run
// creates (an atomic write's temporary file, batch's scratch folder, the figures' gnuplot folder)
// and the child processes it starts are registered here; a program that calls
// InstallInterruptCleanup() then answers SIGINT and SIGTERM by stopping its children, removing
// what is registered and exiting with 128 + the signal (130, 143).
//
// The signals are blocked in every thread and taken by one thread waiting in sigwait(), so the
// cleanup is ordinary code run outside a signal handler (no async-signal-safety limits), and it
// runs only when no InterruptDeferral is held: a temporary file is never left between its
// creation and its registration, nor a line of output half written.

#include <sys/types.h>

#include <mutex>
#include <string>

namespace rotorid {

// Call first in main, before any thread is started (threads inherit the blocked signals).
void InstallInterruptCleanup();

// While one is alive the cleanup waits: hold it around creating and registering a temporary
// path, starting and registering a child, and appending a line that must be whole.
class InterruptDeferral {
 public:
  InterruptDeferral();
  ~InterruptDeferral();
  InterruptDeferral(const InterruptDeferral&) = delete;
  InterruptDeferral& operator=(const InterruptDeferral&) = delete;

 private:
  std::unique_lock<std::recursive_mutex> lock_;
};

// A file or folder (removed with its content) to delete when the run is interrupted; unregister
// once it is renamed into place or removed.
void RegisterTemporaryPath(const std::string& path);
void UnregisterTemporaryPath(const std::string& path);

// A child process to stop (with the same signal, SIGKILL after 2 s) and wait for before the
// temporary paths are removed: it may still be writing into them.
void RegisterChildProcess(pid_t pid);
void UnregisterChildProcess(pid_t pid);

// Exit status of a process stopped by SIGINT or SIGTERM (128 + signal), as the cleanup gives.
bool IsInterruptExitCode(int exit_code);

}  // namespace rotorid

#pragma once

// Runs another program and waits for it: batch's entries (this binary again) and gnuplot. The
// child starts with the default signal handling and mask (InstallInterruptCleanup blocks SIGINT
// and SIGTERM in this process), and is registered for the Ctrl-C cleanup while it runs.

#include <string>
#include <vector>

namespace rotorid {

struct ChildProcess {
  std::string executable;
  std::vector<std::string> argv;  // argv[0] first
  std::string stdin_path = "/dev/null", stdout_path = "/dev/null";
  std::string stderr_path;  // created or truncated
  double timeout_s = 0.0;   // 0: none; else SIGKILL once it has passed
};

struct ChildExit {
  int exit_code = 0;  // 128 + signal when a signal ended it
  bool timed_out = false;
};

// Throws rotorid::Error when the program cannot be started or waited for.
ChildExit RunChildProcess(const ChildProcess& child);

}  // namespace rotorid

// Whole-process benchmark of the rotorid CLI: wall time and peak resident memory of each command on
// simulated logs (a 90 s and a 1 h flight at 200 Hz), measured with wait4(). Each figure is the
// median of several runs in one session, so ratios between rows are meaningful. When
// /usr/bin/python3 has numpy and scipy, the numpy/scipy implementation of the same identify
// pipeline (bench/identify_reference.py) runs in the same session and the ratio is printed.
//
//   cli_bench [runs=5] [--long]   (--long adds the 1 h log: about a minute to simulate)

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace {

struct Measurement {
  double seconds = 0.0;
  double peak_mb = 0.0;
  int exit_code = 0;
};

Measurement Run(const std::vector<std::string>& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    if (!std::freopen("/dev/null", "w", stdout)) _exit(126);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  Measurement m;
  m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  m.peak_mb = usage.ru_maxrss / 1024.0;
  m.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return m;
}

Measurement Median(const std::vector<std::string>& args, int runs) {
  std::vector<Measurement> all;
  for (int i = 0; i < runs; ++i) all.push_back(Run(args));
  std::sort(all.begin(), all.end(), [](const Measurement& a, const Measurement& b) { return a.seconds < b.seconds; });
  return all[all.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 && std::isdigit(argv[1][0]) ? std::atoi(argv[1]) : 5;
  bool long_log = false;
  for (int i = 1; i < argc; ++i) long_log = long_log || std::strcmp(argv[i], "--long") == 0;
  const std::string rotorid = ROTORID_CLI_PATH;
  const std::string dir = (std::filesystem::temp_directory_path() / "rotorid-cli-bench").string();
  std::filesystem::create_directories(dir);
  auto path = [&](const std::string& name) { return dir + "/" + name; };
  std::printf("preparing logs in %s ...\n", dir.c_str());
  Run({rotorid, "simulate", "--preset", "B", "--seconds", "90", "--seed", "3", "--effect", "delay_s=0.015",
       "--effect", "motor_tau_s=0.03", "--out", path("b90.csv"), "--vehicle-out", path("b.yaml"), "--quiet"});
  Run({rotorid, "simulate", "--preset", "B", "--seconds", "30", "--seed", "4", "--out", path("b30.csv"), "--quiet"});
  if (long_log)
    Run({rotorid, "simulate", "--preset", "B", "--seconds", "3600", "--seed", "5", "--out", path("b3600.csv"),
         "--quiet"});
  const std::vector<std::string> flight = {"--vehicle", path("b.yaml"), "--log", path("b90.csv")};
  auto with = [&](std::vector<std::string> head, const std::vector<std::string>& tail) {
    head.insert(head.end(), tail.begin(), tail.end());
    return head;
  };
  struct Case {
    std::string label;
    std::vector<std::string> args;
  };
  std::vector<Case> cases = {
      {"identify, 90 s log", with({rotorid, "identify"}, flight)},
      {"identify + HTML report, 90 s log", with({rotorid, "identify", "--report", path("report")}, flight)},
      {"refine, all effects, 90 s log", with({rotorid, "refine"}, flight)},
      {"delay, 90 s log", with({rotorid, "delay"}, flight)},
      {"ablate, 5 effects (32 subsets), 90 s log", with({rotorid, "ablate", "--threads", "2"}, flight)},
      {"diagnose, 90 s log", with({rotorid, "diagnose"}, flight)},
  };
  if (long_log)
    cases.push_back({"identify, 1 h log", {rotorid, "identify", "--vehicle", path("b.yaml"), "--log", path("b3600.csv")}});
  const std::string python = "/usr/bin/python3";
  const bool has_reference =
      Run({python, "-c", "import numpy, scipy, yaml"}).exit_code == 0;
  if (has_reference)
    cases.push_back({"numpy/scipy reference identify, 90 s log",
                     with({python, std::string(ROTORID_SOURCE_DIR) + "/bench/identify_reference.py"}, flight)});
  std::printf("%-44s %10s %10s %6s\n", "command", "median s", "peak MB", "exit");
  std::vector<Measurement> measured;
  for (const Case& c : cases) {
    const Measurement m = Median(c.args, c.label.find("ablate") != std::string::npos ? std::min(runs, 3) : runs);
    measured.push_back(m);
    std::printf("%-44s %10.3f %10.1f %6d\n", c.label.c_str(), m.seconds, m.peak_mb, m.exit_code);
    std::fflush(stdout);
  }
  if (has_reference)
    std::printf("identify is %.1fx faster than the numpy/scipy reference (same log, same run)\n",
                measured.back().seconds / measured.front().seconds);
  else
    std::printf("no numpy/scipy reference: apt-get install python3-numpy python3-scipy python3-yaml\n");
  return 0;
}

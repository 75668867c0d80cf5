// Whole-process benchmark of the rotorid CLI: wall time, CPU time and peak resident memory of each
// command on simulated logs (a 90 s and a 1 h flight at 200 Hz), measured with wait4(). Each figure
// is the median of several runs in one session, the cases interleaved (round-robin), so ratios
// between rows are meaningful on a loaded machine. When /usr/bin/python3 has numpy and scipy, the
// numpy/scipy implementation of the same identify pipeline (bench/identify_reference.py) runs in
// the same session and the ratio is printed. --baseline runs every rotorid case also with another
// binary (e.g. a copy of the one before a change), beside it, for a before/after table.
//
//   cli_bench [runs=5] [--long] [--identify-only] [--baseline /path/to/old/rotorid]
//   (--long adds the 1 h log: about a minute to simulate, once; identify on it, and refine unless
//   --identify-only; --identify-only skips refine, delay, ablate and diagnose. The diagnosis with
//   every candidate also runs on the real Crazyflie flight jana01 when ../shared/data/real holds it.)

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace {

struct Measurement {
  double seconds = 0.0;
  double cpu_seconds = 0.0;  // user + system: less disturbed than wall time by other work on the machine
  double peak_mb = 0.0;
  int exit_code = 0;
};

Measurement Run(const std::vector<std::string>& args) {
  std::fflush(stdout);  // else the child inherits and prints again what is still buffered
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
  m.cpu_seconds =
      usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  m.peak_mb = usage.ru_maxrss / 1024.0;
  m.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return m;
}

// Each figure's own median (wall, CPU and memory need not come from the same run).
Measurement Median(std::vector<Measurement> all) {
  auto median = [&all](double Measurement::*field) {
    std::sort(all.begin(), all.end(),
              [field](const Measurement& a, const Measurement& b) { return a.*field < b.*field; });
    return all[all.size() / 2].*field;
  };
  Measurement m;
  m.seconds = median(&Measurement::seconds);
  m.cpu_seconds = median(&Measurement::cpu_seconds);
  m.peak_mb = median(&Measurement::peak_mb);
  m.exit_code = 0;
  for (const Measurement& r : all) m.exit_code = std::max(m.exit_code, r.exit_code);
  return m;
}

struct Case {
  std::string label;
  std::vector<std::string> args;
  int runs = 0;
  std::vector<Measurement> measured = {};
};

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 && std::isdigit(argv[1][0]) ? std::atoi(argv[1]) : 5;
  bool long_log = false, identify_only = false;
  std::string baseline;
  for (int i = 1; i < argc; ++i) {
    long_log = long_log || std::strcmp(argv[i], "--long") == 0;
    identify_only = identify_only || std::strcmp(argv[i], "--identify-only") == 0;
    if (std::strcmp(argv[i], "--baseline") == 0 && i + 1 < argc) baseline = argv[++i];
  }
  const std::string rotorid = ROTORID_CLI_PATH;
  const std::string dir = (std::filesystem::temp_directory_path() / "rotorid-cli-bench").string();
  std::filesystem::create_directories(dir);
  auto path = [&](const std::string& name) { return dir + "/" + name; };
  std::printf("preparing logs in %s ...\n", dir.c_str());
  Run({rotorid, "simulate", "--preset", "B", "--seconds", "90", "--seed", "3", "--effect", "delay_s=0.015", "--effect",
       "motor_tau_s=0.03", "--out", path("b90.csv"), "--vehicle-out", path("b.yaml"), "--quiet"});
  Run({rotorid, "simulate", "--preset", "B", "--seconds", "30", "--seed", "4", "--out", path("b30.csv"), "--quiet"});
  Run({rotorid, "simulate", "--preset", "B", "--seconds", "90", "--seed", "6", "--effect", "motor_tau_s=0.03", "--out",
       path("b90_lag.csv"), "--quiet"});
  if (long_log && !std::filesystem::exists(path("b3600.csv")))  // the same seed gives the same log
    Run({rotorid, "simulate", "--preset", "B", "--seconds", "3600", "--seed", "5", "--out", path("b3600.csv"),
         "--quiet"});
  const std::vector<std::string> flight = {"--vehicle", path("b.yaml"), "--log", path("b90.csv")};
  auto with = [&](std::vector<std::string> head, const std::vector<std::string>& tail) {
    head.insert(head.end(), tail.begin(), tail.end());
    return head;
  };
  std::vector<Case> cases = {{"identify, 90 s log", with({rotorid, "identify"}, flight), runs}};
  if (!identify_only) {
    cases.push_back(
        {"identify + HTML report, 90 s log", with({rotorid, "identify", "--report", path("report")}, flight), runs});
    cases.push_back({"refine, all effects, 90 s log", with({rotorid, "refine"}, flight), runs});
    cases.push_back({"refine, the five v1 effects, 90 s log",
                     with({rotorid, "refine", "--effects", "delay,motor_lag,acc_bias,gyro_bias,misalignment"}, flight),
                     runs});
    cases.push_back({"delay, 90 s log", with({rotorid, "delay"}, flight), runs});
    cases.push_back(
        {"ablate, 5 effects (32 subsets), 90 s log",
         with({rotorid, "ablate", "--threads", "2", "--effects", "delay,motor_lag,acc_bias,gyro_bias,misalignment"},
              flight),
         std::min(runs, 3)});
    cases.push_back({"diagnose, 90 s log", with({rotorid, "diagnose"}, flight), runs});
    cases.push_back(
        {"diagnose --effects every, 90 s log, one effect",
         {rotorid, "diagnose", "--effects", "every", "--vehicle", path("b.yaml"), "--log", path("b90_lag.csv")},
         runs});
    const std::string source = ROTORID_SOURCE_DIR;
    const std::string jana01 = source + "/../shared/data/real/crazyflie-imrc-rpm/brushed/raw/jana01";
    if (std::filesystem::exists(jana01))  // a minute or two per run before issue 14: three runs
      cases.push_back({"diagnose --effects every, jana01 (real, 51 s at 500 Hz)",
                       {rotorid, "diagnose", "--effects", "every", "--allow-partial", "--vehicle",
                        source + "/data/vehicles/crazyflie21_brushed.yaml", "--log", jana01},
                       std::min(runs, 3)});
  }
  if (long_log) {
    const std::vector<std::string> long_flight = {"--vehicle", path("b.yaml"), "--log", path("b3600.csv")};
    cases.push_back({"identify, 1 h log", with({rotorid, "identify"}, long_flight), runs});
    if (!identify_only)  // a minute or two per run before issue 14: three runs
      cases.push_back(
          {"refine, the five v1 effects, 1 h log",
           with({rotorid, "refine", "--effects", "delay,motor_lag,acc_bias,gyro_bias,misalignment"}, long_flight),
           std::min(runs, 3)});
  }
  if (!baseline.empty()) {  // each rotorid case again with the baseline binary, run beside it
    std::vector<Case> paired;
    for (const Case& c : cases) {
      paired.push_back(c);
      Case b = c;
      b.label = "  baseline: " + c.label;
      b.args[0] = baseline;
      paired.push_back(b);
    }
    cases = paired;
  }
  const std::string python = "/usr/bin/python3";
  const bool has_reference = Run({python, "-c", "import numpy, scipy, yaml"}).exit_code == 0;
  if (has_reference)
    cases.push_back({"numpy/scipy reference identify, 90 s log",
                     with({python, std::string(ROTORID_SOURCE_DIR) + "/bench/identify_reference.py"}, flight), runs});
  // Round-robin: every case once per round, so that a change of the machine's load hits all alike.
  for (int round = 0; round < runs; ++round)
    for (Case& c : cases)
      if (round < c.runs) c.measured.push_back(Run(c.args));
  std::printf("%-52s %9s %9s %9s %5s\n", "command (median of runs)", "wall s", "CPU s", "peak MB", "exit");
  for (const Case& c : cases) {
    const Measurement m = Median(c.measured);
    std::printf("%-52s %9.3f %9.3f %9.1f %5d\n", c.label.c_str(), m.seconds, m.cpu_seconds, m.peak_mb, m.exit_code);
  }
  if (!baseline.empty()) {
    for (size_t k = 0; k + 1 < cases.size(); k += 2) {
      if (cases[k + 1].label.find("baseline") == std::string::npos) continue;
      const Measurement now = Median(cases[k].measured), before = Median(cases[k + 1].measured);
      std::printf("%s: %.2fx faster (wall), %.2fx (CPU) than the baseline\n", cases[k].label.c_str(),
                  before.seconds / now.seconds, before.cpu_seconds / now.cpu_seconds);
    }
  }
  if (has_reference) {
    const Measurement reference = Median(cases.back().measured), identify = Median(cases.front().measured);
    std::printf("identify is %.1fx faster than the numpy/scipy reference (wall; CPU %.1fx; same log, same run)\n",
                reference.seconds / identify.seconds, reference.cpu_seconds / identify.cpu_seconds);
    if (!baseline.empty())
      std::printf("the baseline was %.1fx faster than the reference (wall; CPU %.1fx)\n",
                  reference.seconds / Median(cases[1].measured).seconds,
                  reference.cpu_seconds / Median(cases[1].measured).cpu_seconds);
  } else {
    std::printf("no numpy/scipy reference: apt-get install python3-numpy python3-scipy python3-yaml\n");
  }
  return 0;
}

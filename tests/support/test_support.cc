#include "support/test_support.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rotorid/sim/presets.h"

namespace rotorid::testing {

std::string SourceDir() {
  const char* dir = std::getenv("ROTORID_SOURCE_DIR");
  return dir ? dir : ".";
}

std::string SharedDir() { return SourceDir() + "/../shared"; }

std::optional<std::string> SharedDataPath(const std::string& relative) {
  const std::string path = SharedDir() + "/data/" + relative;
  if (!std::filesystem::exists(path)) return std::nullopt;
  return path;
}

SimulationResult SimulatePreset(const std::string& preset, double seconds, std::uint64_t seed, const Effects& effects) {
  const SimulationVehicle vehicle = PresetVehicle(preset);
  SimulationOptions options;
  options.duration_s = seconds;
  options.seed = seed;
  options.effects = effects;
  return Simulate(vehicle.vehicle, vehicle.parameters, options);
}

IdentificationResult IdentifySimulated(const SimulationResult& sim) {
  IdentifyOptions identify;
  identify.allow_partial = true;
  return Identify({{sim.vehicle, sim.log, 1.0}}, identify);
}

std::string MakeTempDir(const std::string& prefix) {
  std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
  if (!mkdtemp(pattern.data())) return {};
  return pattern;
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

CommandResult RunRotorid(const std::vector<std::string>& args) {
  const char* binary = std::getenv("ROTORID_BINARY");
  CommandResult result;
  if (!binary) {
    result.err = "ROTORID_BINARY is not set";
    return result;
  }
  const std::string dir = MakeTempDir("rotorid-run");
  const std::string out_path = dir + "/out", err_path = dir + "/err";
  const pid_t pid = fork();
  if (pid == 0) {
    const int out_fd = open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out_fd, 1);
    dup2(err_fd, 2);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(binary));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(binary, argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = Slurp(out_path);
  result.err = Slurp(err_path);
  std::filesystem::remove_all(dir);
  return result;
}

}  // namespace rotorid::testing

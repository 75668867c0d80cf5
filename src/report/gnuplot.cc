#include "report/gnuplot.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/process.h"

namespace rotorid::internal {

namespace {

bool IsExecutableFile(const std::string& path) {
  struct stat info;
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

std::string Tail(const std::string& path, size_t max_chars) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

}  // namespace

std::string FindExecutable(const std::string& name) {
  if (name.empty()) return {};
  if (name.find('/') != std::string::npos) return IsExecutableFile(name) ? name : std::string();
  const char* path_env = std::getenv("PATH");
  std::stringstream dirs(path_env ? path_env : "/usr/local/bin:/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;  // an empty entry means ".": not searched, on purpose
    const std::string candidate = dir + "/" + name;
    if (IsExecutableFile(candidate)) return candidate;
  }
  return {};
}

std::string GnuplotString(const std::string& text) {
  static const std::string kAllowed = " .,:;_+-=()[]/%<>#*|~";
  std::string out = "'";
  for (const char c : text) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      kAllowed.find(c) != std::string::npos;
    out += keep ? c : '_';
  }
  return out + "'";
}

std::string GnuplotPath(const std::string& path) {
  // Single-quoted gnuplot strings have no escapes but '' and end at a newline; paths come from
  // mkdtemp under TMPDIR, so anything unusual here is refused rather than mangled.
  for (const char c : path)
    if (c == '\'' || c == '\n' || c == '\r' || c == '`')
      throw Error("temporary path '" + path + "' contains characters gnuplot cannot read; set TMPDIR to a plain path");
  return "'" + path + "'";
}

ProcessResult RunGnuplotScript(const std::string& executable, const std::string& script_path,
                               const std::string& stderr_path, double timeout_s) {
  ProcessResult result;
  ChildProcess child;
  child.executable = executable;
  child.argv = {"gnuplot", "--default-settings", script_path};
  child.stderr_path = stderr_path;
  child.timeout_s = timeout_s;
  try {
    const ChildExit exit = RunChildProcess(child);
    result.exit_code = exit.exit_code;
    result.timed_out = exit.timed_out;
  } catch (const Error& e) {
    result.error_text = e.what();
    return result;
  }
  result.ok = !result.timed_out && result.exit_code == 0;
  if (!result.ok) {
    result.error_text = Tail(stderr_path, 400);
    if (result.timed_out)
      result.error_text = "gnuplot killed after " + std::to_string(timeout_s) + " s" +
                          (result.error_text.empty() ? "" : ": " + result.error_text);
    else if (result.error_text.empty())
      result.error_text = "gnuplot exited with status " + std::to_string(result.exit_code);
  }
  return result;
}

}  // namespace rotorid::internal

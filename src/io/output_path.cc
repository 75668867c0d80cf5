#include "rotorid/io/output_path.h"

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>

namespace rotorid {

namespace fs = std::filesystem;

std::string OutputFileProblem(const std::string& path) {
  if (path.empty()) return "an output file name must not be empty";
  std::error_code ec;
  if (fs::is_directory(path, ec)) return "'" + path + "' is a folder, not a file";
  // Outputs are renamed into place: a device, FIFO or socket would be replaced, after all the work.
  if (fs::exists(path, ec) && !fs::is_regular_file(path, ec))
    return "'" + path + "' exists and is not a regular file (a device, FIFO or socket): give the path of a file";
  const fs::path parent = fs::path(path).parent_path();
  const std::string folder = parent.empty() ? "." : parent.string();
  if (!fs::is_directory(folder, ec)) return "folder '" + folder + "' of '" + path + "' does not exist";
  if (::access(folder.c_str(), W_OK) != 0) return "folder '" + folder + "' of '" + path + "' is not writable";
  return {};
}

std::string OutputFileOrFolderProblem(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) ? std::string() : OutputFileProblem(path);
}

std::string OutputFolderProblem(const std::string& path) {
  if (path.empty()) return "a report folder name must not be empty";
  std::error_code ec;
  if (fs::exists(path, ec) && !fs::is_directory(path, ec)) return "'" + path + "' exists and is not a folder";
  return {};
}

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa {};
  struct stat sb {};
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0)
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  std::error_code ec_a, ec_b;
  const fs::path ca = fs::weakly_canonical(a, ec_a), cb = fs::weakly_canonical(b, ec_b);
  return !ec_a && !ec_b && ca == cb;
}

namespace {

std::string Quoted(const OptionPath& option) { return option.first + " '" + option.second + "'"; }

}  // namespace

std::string OutputsAgainstInputsProblem(const std::vector<OptionPath>& outputs, const std::vector<OptionPath>& inputs) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    for (const OptionPath& input : inputs)
      if (SameFile(outputs[i].second, input.second))
        return Quoted(outputs[i]) + " is the input " + Quoted(input) +
               " (the same file): writing it would destroy the input; give another output path";
    for (size_t j = i + 1; j < outputs.size(); ++j)
      if (SameFile(outputs[i].second, outputs[j].second))
        return Quoted(outputs[i]) + " and " + Quoted(outputs[j]) +
               " name the same file: one output would replace the other";
  }
  return {};
}

}  // namespace rotorid

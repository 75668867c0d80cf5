#include "report/report_files.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"

namespace rotorid::internal {

namespace fs = std::filesystem;

const char* const ReportFiles::kManifestName = ".rotorid_report_figures";

std::string ContentHash(const std::string& bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const unsigned char c : bytes) hash = (hash ^ c) * 1099511628211ull;
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

namespace {

// A name this writer may remove: a figure, directly in the folder (the manifest is a file anyone can
// edit, so it names nothing else to delete).
bool IsFigureName(const std::string& name) {
  return name.rfind("fig_", 0) == 0 && name.find('/') == std::string::npos && fs::path(name).extension() == ".svg";
}

// name.new.svg, name.new2.svg, ... for the k-th try beside `name`.
std::string BesideName(const std::string& name, int k) {
  const fs::path path(name);
  return path.stem().string() + ".new" + (k > 1 ? std::to_string(k) : "") + path.extension().string();
}

}  // namespace

ReportFiles::ReportFiles(std::string dir) : dir_(std::move(dir)) {
  const fs::path manifest = fs::path(dir_) / kManifestName;
  std::error_code ec;
  if (!fs::is_regular_file(manifest, ec)) return;
  // "HASH NAME" per line; a line of a name alone (rotorid before the hashes) has no known bytes.
  std::istringstream lines(ReadFile(manifest.string()));
  for (std::string line; std::getline(lines, line);) {
    const size_t space = line.find(' ');
    if (space == 16)
      earlier_[line.substr(17)] = line.substr(0, 16);
    else if (!line.empty())
      earlier_[line] = "";
  }
}

bool ReportFiles::ChangedSinceWritten(const std::string& name) const {
  const fs::path path = fs::path(dir_) / name;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(path, ec))) return false;
  const auto it = earlier_.find(name);
  if (it == earlier_.end() || it->second.empty() || !fs::is_regular_file(fs::symlink_status(path, ec))) return true;
  try {
    return ContentHash(ReadFile(path.string())) != it->second;
  } catch (const Error&) {
    return true;
  }
}

std::string ReportFiles::Write(const std::string& name, const std::string& bytes, std::vector<std::string>* warnings) {
  std::string target = name;
  for (int k = 1; ChangedSinceWritten(target) || written_.count(target); ++k) {
    if (k > 99) throw Error(dir_ + ": " + name + " and 99 files beside it were changed since rotorid wrote them");
    target = BesideName(name, k);
  }
  if (target != name)
    warnings->push_back(dir_ + "/" + name +
                        " was changed since rotorid wrote it (or is not rotorid's): kept as it is; "
                        "this run's is " +
                        target);
  const std::string path = (fs::path(dir_) / target).string();
  WriteFileAtomically(path, bytes);
  written_[target] = ContentHash(bytes);
  return path;
}

void ReportFiles::RemoveStaleAndSave() {
  for (const auto& [name, hash] : earlier_) {
    if (written_.count(name) || !IsFigureName(name) || ChangedSinceWritten(name)) continue;
    std::error_code ec;
    fs::remove(fs::path(dir_) / name, ec);
  }
  std::string manifest;
  for (const auto& [name, hash] : written_) manifest += hash + " " + name + "\n";
  WriteFileAtomically((fs::path(dir_) / kManifestName).string(), manifest);
}

}  // namespace rotorid::internal

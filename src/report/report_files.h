#pragma once

// The files a report writes into its folder, and which of them it may write again or remove: a
// manifest in the folder lists each file rotorid wrote with the hash of its bytes, so that a file
// the user changed since (an edited figure) is neither overwritten nor removed (issue 42: a second
// --report into the folder deleted the user's edited figure). Internal to the library.

#include <map>
#include <string>
#include <vector>

namespace rotorid::internal {

class ReportFiles {
 public:
  // Reads the folder's manifest (none: nothing in the folder is rotorid's).
  explicit ReportFiles(std::string dir);

  // Writes `bytes` as `name` in the folder, atomically, and returns the path written. When `name`
  // exists and is not as rotorid left it, it is kept and the bytes go beside it (fig_a.new.svg,
  // fig_a.new2.svg, ...), with a warning naming both.
  std::string Write(const std::string& name, const std::string& bytes, std::vector<std::string>* warnings);

  // Removes the figures (fig_*.svg) an earlier report wrote that this one did not write again, where
  // they are still as rotorid left them; then the manifest lists this run's files.
  void RemoveStaleAndSave();

  static const char* const kManifestName;

 private:
  // True when `name` exists and is not the bytes rotorid last wrote there.
  bool ChangedSinceWritten(const std::string& name) const;

  std::string dir_;
  std::map<std::string, std::string> earlier_;  // name -> hash ("" for a manifest line without one)
  std::map<std::string, std::string> written_;
};

// FNV-1a 64 of `bytes` as 16 hex digits.
std::string ContentHash(const std::string& bytes);

}  // namespace rotorid::internal

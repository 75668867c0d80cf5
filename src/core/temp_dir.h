#pragma once

// Internal: a private temporary folder (gnuplot's scripts, batch's entry reports).

#include <string>

namespace rotorid::internal {

// A fresh private folder under the temporary directory ($TMPDIR, else /tmp), registered with the
// Ctrl-C cleanup (rotorid/core/interrupt.h) and removed with its content on destruction.
class TempDir {
 public:
  // Throws rotorid::Error when it cannot be created.
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace rotorid::internal

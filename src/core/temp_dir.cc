#include "core/temp_dir.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "rotorid/core/error.h"
#include "rotorid/core/interrupt.h"

namespace rotorid::internal {

TempDir::TempDir(const std::string& prefix) {
  std::error_code ec;
  std::filesystem::path base = std::filesystem::temp_directory_path(ec);
  if (ec) base = "/tmp";
  std::string pattern = (base / (prefix + "-XXXXXX")).string();
  const InterruptDeferral registered_once_created;
  if (!::mkdtemp(pattern.data()))
    throw Error("cannot create a temporary directory in " + base.string() + ": " + std::strerror(errno));
  path_ = pattern;
  RegisterTemporaryPath(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
  UnregisterTemporaryPath(path_);
}

}  // namespace rotorid::internal

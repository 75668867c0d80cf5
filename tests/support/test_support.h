#pragma once

#include <optional>
#include <string>
#include <vector>

namespace rotorid::testing {

// The project's source folder (set by CTest), and ../shared beside it.
std::string SourceDir();
std::string SharedDir();
// A path under ../shared/data, or nullopt when that data is absent (tests then GTEST_SKIP()).
std::optional<std::string> SharedDataPath(const std::string& relative);
// A fresh temporary directory for one test.
std::string MakeTempDir(const std::string& prefix);

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
// Runs the rotorid binary under test with these arguments (no shell quoting issues: args are passed as argv).
CommandResult RunRotorid(const std::vector<std::string>& args);

}  // namespace rotorid::testing

#pragma once

// Checks of the paths a command writes, made before any work (docs/cli.md): what would be
// replaced, whether the folder takes the file, and whether an output is one of the inputs.

#include <string>
#include <utility>
#include <vector>

namespace rotorid {

// Empty when `path` can be written as a file (atomically: renamed into place), else why not.
std::string OutputFileProblem(const std::string& path);
// The same, but an existing folder is accepted too (export's model directories).
std::string OutputFileOrFolderProblem(const std::string& path);
// Empty when `path` can be a report folder (absent or a folder), else why not.
std::string OutputFolderProblem(const std::string& path);

// An option and the path it gives ("--json", "out.json").
using OptionPath = std::pair<std::string, std::string>;
// Empty when no output is one of the inputs or another output (the same file, also through a hard
// link or a symlink), else the usage error naming both options.
std::string OutputsAgainstInputsProblem(const std::vector<OptionPath>& outputs, const std::vector<OptionPath>& inputs);

// Whether two paths name the same file (device and inode when both exist, else the same path).
bool SameFile(const std::string& a, const std::string& b);

}  // namespace rotorid

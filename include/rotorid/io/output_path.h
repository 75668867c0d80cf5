#pragma once

// Checks of the paths a command writes, made before any work (docs/cli.md): what would be
// replaced, whether the folder takes the file, and whether an output is one of the inputs.

#include <string>

namespace rotorid {

// Empty when `path` can be written as a file (atomically: renamed into place), else why not.
std::string OutputFileProblem(const std::string& path);
// The same, but an existing folder is accepted too (export's model directories).
std::string OutputFileOrFolderProblem(const std::string& path);
// Empty when `path` can be a report folder (absent or a folder), else why not.
std::string OutputFolderProblem(const std::string& path);

// Whether two paths name the same file (device and inode when both exist, else the same path).
bool SameFile(const std::string& a, const std::string& b);

}  // namespace rotorid

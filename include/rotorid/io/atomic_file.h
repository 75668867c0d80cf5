#pragma once

#include <string>

namespace rotorid {

// Writes the whole content to a temporary file beside `path`, then renames it over `path`, so a
// reader never sees a half-written output. Throws rotorid::Error naming the path on failure.
void WriteFileAtomically(const std::string& path, const std::string& content);

// Reads a whole file; throws rotorid::Error naming the path when it cannot be read.
std::string ReadFile(const std::string& path);

}  // namespace rotorid

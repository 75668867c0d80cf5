#pragma once

#include <cstdint>
#include <string>

namespace rotorid {

// Writes the whole content to a temporary file beside `path`, then renames it over `path`, so a
// reader never sees a half-written output. Throws rotorid::Error naming the path on failure.
void WriteFileAtomically(const std::string& path, const std::string& content);

// The largest input rotorid reads whole (a 1 h log at 1 kHz is about 500 MB of CSV): a bound on
// memory for a wrong path (a device, a disk image) instead of growing until the allocation fails.
inline constexpr std::uint64_t kMaxInputFileBytes = std::uint64_t{2} << 30;
// Small inputs (vehicle files, column maps, --config): 1 MB holds thousands of lines, and yaml-cpp
// takes about 60 times a file's size in memory.
inline constexpr std::uint64_t kMaxYamlFileBytes = std::uint64_t{1} << 20;

// Throws rotorid::Error naming the path unless it names a regular file (after symlinks) of at most
// `max_bytes`: a device (/dev/zero), a FIFO or a folder given as a log is refused before reading.
void RequireInputFile(const std::string& path, std::uint64_t max_bytes = kMaxInputFileBytes);

// Reads a whole regular file or pipe of at most `max_bytes` (a device or folder is refused by its
// path, a pipe once it exceeds the cap); throws rotorid::Error naming the path when it cannot be read.
std::string ReadFile(const std::string& path, std::uint64_t max_bytes = kMaxInputFileBytes);

}  // namespace rotorid

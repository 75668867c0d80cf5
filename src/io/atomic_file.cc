#include "rotorid/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

#include "rotorid/core/error.h"
#include "rotorid/core/interrupt.h"

namespace rotorid {

namespace {

// The folder holding `path`, for creating the temporary file beside it and syncing the rename.
std::string ParentFolder(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

// The temporary file beside an output, registered for the Ctrl-C cleanup from its creation, and
// removed unless it was renamed into place.
struct TemporaryFile {
  explicit TemporaryFile(const std::string& output) : path(output + ".tmp.XXXXXX") {
    const InterruptDeferral registered_once_created;
    fd = mkstemp(path.data());
    if (fd < 0) throw Error(output + ": cannot create a temporary file beside it: " + std::strerror(errno));
    RegisterTemporaryPath(path);
  }
  ~TemporaryFile() {
    if (fd >= 0) ::close(fd);
    if (!renamed) std::remove(path.c_str());
    UnregisterTemporaryPath(path);
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  std::string path;
  int fd = -1;
  bool renamed = false;
};

}  // namespace

void WriteFileAtomically(const std::string& path, const std::string& content) {
  if (path.empty()) throw Error("output path is empty");
  // A rename would replace a device node, a FIFO or a socket by a regular file.
  struct stat existing {};
  if (::stat(path.c_str(), &existing) == 0 && !S_ISREG(existing.st_mode))
    throw Error(path +
                ": exists and is not a regular file (a folder, device, FIFO or socket); rotorid replaces only "
                "regular files: give the path of a file");
  TemporaryFile tmp(path);
  size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(tmp.fd, content.data() + written, content.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw Error(path + ": write failed: " + std::strerror(errno));
    }
    written += static_cast<size_t>(n);
  }
  // mkstemp creates 0600; outputs are ordinary user files.
  fchmod(tmp.fd, 0644);
  // The content reaches the disk before the rename makes it visible: after a crash, the old file or
  // the whole new one, never an empty or partial one.
  const bool on_disk = ::fsync(tmp.fd) == 0 && ::close(std::exchange(tmp.fd, -1)) == 0;
  if (!on_disk || std::rename(tmp.path.c_str(), path.c_str()) != 0)
    throw Error(path + ": cannot write: " + std::strerror(errno));
  tmp.renamed = true;
  // And the rename itself (best effort: some file systems refuse to sync a folder).
  const int folder = ::open(ParentFolder(path).c_str(), O_RDONLY | O_DIRECTORY);
  if (folder >= 0) {
    ::fsync(folder);
    ::close(folder);
  }
}

namespace {

std::string SizeText(std::uint64_t bytes) {
  return bytes >= (1u << 20) ? std::to_string(bytes >> 20) + " MB" : std::to_string(bytes) + " bytes";
}

// The refusal of an input that is neither a regular file of at most `max_bytes` nor, where allowed, a
// pipe ("" when it is one). A device (/dev/zero) would be read until memory runs out.
std::string InputFileProblem(const std::string& path, const struct stat& info, std::uint64_t max_bytes,
                             bool pipe_allowed) {
  if (S_ISDIR(info.st_mode)) return path + ": is a folder, not a file";
  if (S_ISFIFO(info.st_mode) && !pipe_allowed)
    return path + ": is a pipe (FIFO); a log is read twice (its format, then its content): give a file";
  if (!S_ISREG(info.st_mode) && !S_ISFIFO(info.st_mode))
    return path + ": is not a regular file (a device or socket): rotorid reads its inputs from files";
  if (static_cast<std::uint64_t>(info.st_size) > max_bytes)
    return path + ": " + SizeText(static_cast<std::uint64_t>(info.st_size)) + ", more than the " + SizeText(max_bytes) +
           " rotorid reads for this input: is it the right file?";
  return {};
}

}  // namespace

void RequireInputFile(const std::string& path, std::uint64_t max_bytes) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) throw Error(path + ": cannot open: " + std::strerror(errno));
  if (const std::string problem = InputFileProblem(path, info, max_bytes, /*pipe_allowed=*/false); !problem.empty())
    throw Error(problem);
}

std::string ReadFile(const std::string& path, std::uint64_t max_bytes) {
  struct ClosedAtExit {
    int fd;
    ~ClosedAtExit() { ::close(fd); }
  };
  const ClosedAtExit file{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (file.fd < 0) throw Error(path + ": cannot open: " + std::strerror(errno));
  struct stat info {};
  if (::fstat(file.fd, &info) != 0) throw Error(path + ": cannot read: " + std::strerror(errno));
  if (const std::string problem = InputFileProblem(path, info, max_bytes, /*pipe_allowed=*/true); !problem.empty())
    throw Error(problem);
  auto read_some = [&](char* into, size_t size) {
    for (;;) {
      const ssize_t got = ::read(file.fd, into, size);
      if (got >= 0) return static_cast<size_t>(got);
      if (errno != EINTR) throw Error(path + ": read failed: " + std::strerror(errno));
    }
  };
  // Straight into one allocation of the file's size (a string stream held a long log, 100 MB for
  // 1 h at 200 Hz, up to three times over, and a buffered stream copies it once more); a pipe, or a
  // file that grows while it is read, in chunks up to the cap.
  std::string content(S_ISREG(info.st_mode) ? static_cast<size_t>(info.st_size) : 0, '\0');
  size_t done = 0;
  while (done < content.size()) {
    const size_t got = read_some(content.data() + done, content.size() - done);
    if (got == 0) break;
    done += got;
  }
  content.resize(done);
  char chunk[1 << 16];
  while (const size_t got = read_some(chunk, sizeof chunk)) {
    if (content.size() + got > max_bytes)
      throw Error(path + ": more than the " + SizeText(max_bytes) +
                  " rotorid reads for this input: is it the right file?");
    content.append(chunk, got);
  }
  return content;
}

}  // namespace rotorid

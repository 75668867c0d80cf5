#include "rotorid/io/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <csignal>
#include <cstdio>
#include <functional>
#include <string>
#include <thread>

#include "rotorid/core/error.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// 200 kB of every byte value, zeros included: more than one read's chunk.
std::string Bytes() {
  std::string bytes(200'000, '\0');
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>((i * 7919) % 256);
  return bytes;
}

TEST(ReadFile, ReturnsEveryByteOfAFileWrittenAtomically) {
  const std::string path = testing::MakeTempDir("read_file") + "/bytes.bin";
  WriteFileAtomically(path, Bytes());
  EXPECT_EQ(ReadFile(path), Bytes());
  WriteFileAtomically(path, "");
  EXPECT_EQ(ReadFile(path), "");
}

// A file whose size stat() does not know (0 for a /proc file) is read to its end all the same.
TEST(ReadFile, ReadsAFileWhoseSizeIsNotKnownInAdvance) {
  const std::string status = ReadFile("/proc/self/status");
  EXPECT_EQ(status.rfind("Name:", 0), 0u) << status.substr(0, 40);
  EXPECT_NE(status.find("VmPeak"), std::string::npos);
}

TEST(ReadFile, ReadsAPipeToItsEnd) {
  const std::string path = testing::MakeTempDir("read_file") + "/pipe";
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  std::thread writer([&path] {
    std::FILE* out = std::fopen(path.c_str(), "wb");
    const std::string bytes = Bytes();
    if (out) std::fwrite(bytes.data(), 1, bytes.size(), out);
    if (out) std::fclose(out);
  });
  const std::string read = ReadFile(path);
  writer.join();
  EXPECT_EQ(read, Bytes());
}

// A device would be read until memory runs out (--log /dev/zero grew to 17 GB): refused by its path;
// a file or a pipe beyond the cap is refused by its size, naming both.
TEST(ReadFile, RefusesDevicesAndInputsBeyondTheCap) {
  auto error_of = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(error_of([] { ReadFile("/dev/zero"); }).find("/dev/zero: is not a regular file"), std::string::npos);
  const std::string dir = testing::MakeTempDir("read_file");
  WriteFileAtomically(dir + "/big.yaml", std::string(2000, 'x'));
  EXPECT_EQ(ReadFile(dir + "/big.yaml", 2000).size(), 2000u);
  EXPECT_NE(error_of([&] { ReadFile(dir + "/big.yaml", 1999); }).find("big.yaml: 2000 bytes, more than the 1999 bytes"),
            std::string::npos);
  const std::string pipe = dir + "/pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  EXPECT_NE(error_of([&] { RequireInputFile(pipe); }).find("is a pipe"), std::string::npos);
  std::signal(SIGPIPE, SIG_IGN);  // the reader stops at the cap: the writer's rest fails with EPIPE
  std::thread writer([&pipe] {
    std::FILE* out = std::fopen(pipe.c_str(), "wb");
    const std::string bytes = Bytes();
    if (out) std::fwrite(bytes.data(), 1, bytes.size(), out);
    if (out) std::fclose(out);
  });
  EXPECT_NE(error_of([&] { ReadFile(pipe, 100'000); }).find("more than the 100000 bytes"), std::string::npos);
  writer.join();
}

TEST(ReadFile, NamesThePathItCannotOpen) {
  const std::string path = testing::MakeTempDir("read_file") + "/missing.csv";
  try {
    ReadFile(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot open: No such file"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rotorid

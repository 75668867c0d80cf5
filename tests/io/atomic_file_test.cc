#include "rotorid/io/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
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

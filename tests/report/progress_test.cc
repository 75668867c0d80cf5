#include "rotorid/report/progress.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

namespace rotorid {
namespace {

std::string ReadAll(int fd) {
  std::string out;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n <= 0) break;
    out.append(buffer, static_cast<size_t>(n));
  }
  return out;
}

void Work(Progress* progress, int total) {
  for (int k = 1; k <= total; ++k) progress->Update(k);
  progress->Finish();
}

TEST(ProgressTest, PrintsNothingWhenStderrIsNotATerminal) {
  // Point the real stderr at a file, as in a pipe, a log or CI.
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  const int saved = ::dup(2);
  ASSERT_GE(saved, 0);
  ::dup2(::fileno(file), 2);
  {
    Progress progress("refine", 1000);
    EXPECT_FALSE(progress.enabled());
    for (int k = 1; k <= 1000; ++k) progress.Update(k);
  }  // the destructor finishes
  Progress unknown_total("diagnose", 0);
  unknown_total.Update(5);
  unknown_total.Finish();
  ::dup2(saved, 2);
  ::close(saved);
  std::fflush(file);
  ::lseek(::fileno(file), 0, SEEK_SET);
  EXPECT_EQ(ReadAll(::fileno(file)), "");
  std::fclose(file);
}

class TerminalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) GTEST_SKIP() << "no pseudo-terminal";
    terminal_ = ::open(::ptsname(master_), O_RDWR | O_NOCTTY);
    if (terminal_ < 0) GTEST_SKIP() << "no pseudo-terminal";
    ::fcntl(master_, F_SETFL, O_NONBLOCK);
  }
  void TearDown() override {
    if (terminal_ >= 0) ::close(terminal_);
    if (master_ >= 0) ::close(master_);
  }
  int master_ = -1;
  int terminal_ = -1;
};

TEST_F(TerminalTest, DrawsOnATerminalThrottled) {
  Progress progress("ablate", 100000, /*quiet=*/false, terminal_);
  EXPECT_TRUE(progress.enabled());
  Work(&progress, 100000);  // far faster than 100 ms: one draw, then the final line
  const std::string shown = ReadAll(master_);
  EXPECT_NE(shown.find("ablate"), std::string::npos);
  EXPECT_NE(shown.find("100%"), std::string::npos);
  EXPECT_NE(shown.find("(100000/100000)"), std::string::npos);
  int draws = 0;
  for (char c : shown) draws += c == '\r';
  EXPECT_LE(draws, 3);
  EXPECT_EQ(shown.back(), '\n');
}

TEST_F(TerminalTest, DrawsAboutTenTimesASecond) {
  Progress progress("refine", 0, /*quiet=*/false, terminal_);
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(550);
  int k = 0;
  while (std::chrono::steady_clock::now() < end) {
    progress.Update(++k);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  progress.Finish();
  const std::string shown = ReadAll(master_);
  int draws = 0;
  for (char c : shown) draws += c == '\r';
  EXPECT_GE(draws, 3);
  EXPECT_LE(draws, 8);  // <= 10 per second over 0.55 s, plus the final line
  EXPECT_NE(shown.find("done"), std::string::npos);
}

TEST_F(TerminalTest, QuietPrintsNothing) {
  Progress progress("refine", 10, /*quiet=*/true, terminal_);
  EXPECT_FALSE(progress.enabled());
  Work(&progress, 10);
  EXPECT_EQ(ReadAll(master_), "");
}

TEST_F(TerminalTest, SafeFromSeveralThreads) {
  Progress progress("diagnose", 40000, /*quiet=*/false, terminal_);
  std::thread a([&] {
    for (int k = 0; k < 20000; ++k) progress.Update(k);
  });
  std::thread b([&] {
    for (int k = 20000; k < 40000; ++k) progress.Update(k);
  });
  a.join();
  b.join();
  progress.Finish();
  EXPECT_NE(ReadAll(master_).find("diagnose"), std::string::npos);
}

TEST_F(TerminalTest, TicksWithoutUpdatesAndEndsItsLine) {
  Progress progress("refine: Ceres", 0, /*quiet=*/false, terminal_);
  progress.StartTicking(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  progress.Finish();
  const std::string shown = ReadAll(master_);
  int draws = 0;
  for (char c : shown) draws += c == '\r';
  EXPECT_GE(draws, 3) << shown;  // about 7 ticks and the final line
  EXPECT_NE(shown.find("refine: Ceres running, "), std::string::npos) << shown;
  EXPECT_NE(shown.find("refine: Ceres done in "), std::string::npos) << shown;
  EXPECT_EQ(shown.back(), '\n');
  // Nothing after Finish.
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  EXPECT_EQ(ReadAll(master_), "");
}

}  // namespace
}  // namespace rotorid

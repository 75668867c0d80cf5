#include "report/gnuplot.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"

namespace rotorid::internal {
namespace {

TEST(GnuplotStringTest, KeepsNothingThatCouldRunOrEscape) {
  EXPECT_EQ(GnuplotString("Fz (N), linear: 3.2 %"), "'Fz (N), linear: 3.2 %'");
  const std::string hostile = GnuplotString("a'b`ls`$(x)@m\\n\nc\"d");
  EXPECT_EQ(hostile, "'a_b_ls__(x)_m_n_c_d'");
  EXPECT_EQ(GnuplotString("\xc3\xa9"), "'__'");  // non-ASCII bytes
}

TEST(GnuplotPathTest, RefusesUnquotablePaths) {
  EXPECT_EQ(GnuplotPath("/tmp/a b/c.svg"), "'/tmp/a b/c.svg'");
  EXPECT_THROW(GnuplotPath("/tmp/it's"), Error);
  EXPECT_THROW(GnuplotPath("/tmp/a\nb"), Error);
}

TEST(FindExecutableTest, PathsAndNames) {
  EXPECT_EQ(FindExecutable("/nonexistent/gnuplot"), "");
  EXPECT_EQ(FindExecutable(""), "");
  EXPECT_EQ(FindExecutable("sh").empty(), false);
  EXPECT_EQ(FindExecutable("/bin/sh"), "/bin/sh");
  EXPECT_EQ(FindExecutable("/tmp"), "");  // a directory is not an executable
}

class GnuplotRunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gnuplot_ = FindExecutable("gnuplot");
    if (gnuplot_.empty()) GTEST_SKIP() << "gnuplot is not installed";
  }
  std::string gnuplot_;
};

TEST_F(GnuplotRunTest, DrawsAFigure) {
  TempDir dir("rotorid-gnuplot-test");
  WriteFileAtomically(dir.path() + "/a.gp",
                      "set terminal svg\nset output " + GnuplotPath(dir.path() + "/a.svg") + "\nplot sin(x)\n");
  const ProcessResult run = RunGnuplotScript(gnuplot_, dir.path() + "/a.gp", dir.path() + "/a.err", 30.0);
  EXPECT_TRUE(run.ok) << run.error_text;
  EXPECT_NE(ReadFile(dir.path() + "/a.svg").find("</svg>"), std::string::npos);
}

TEST_F(GnuplotRunTest, ReportsErrors) {
  TempDir dir("rotorid-gnuplot-test");
  WriteFileAtomically(dir.path() + "/a.gp", "set terminal svg\nplot this is not gnuplot\n");
  const ProcessResult run = RunGnuplotScript(gnuplot_, dir.path() + "/a.gp", dir.path() + "/a.err", 30.0);
  EXPECT_FALSE(run.ok);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_FALSE(run.error_text.empty());
}

TEST_F(GnuplotRunTest, KillsAHangingRun) {
  TempDir dir("rotorid-gnuplot-test");
  WriteFileAtomically(dir.path() + "/a.gp", "pause 30\n");
  const auto start = std::chrono::steady_clock::now();
  const ProcessResult run = RunGnuplotScript(gnuplot_, dir.path() + "/a.gp", dir.path() + "/a.err", 0.3);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_FALSE(run.ok);
  EXPECT_TRUE(run.timed_out);
  EXPECT_LT(seconds, 5.0);
  EXPECT_NE(run.error_text.find("killed"), std::string::npos);
}

TEST(TempDirTest, RemovedOnDestruction) {
  std::string path;
  {
    TempDir dir("rotorid-tempdir-test");
    path = dir.path();
    WriteFileAtomically(path + "/x", "y");
    EXPECT_TRUE(std::filesystem::is_directory(path));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace rotorid::internal

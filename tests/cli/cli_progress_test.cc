// End-to-end test of the progress bars (docs/cli.md "Progress"): the CLI run on a pseudo-terminal,
// as a person at a terminal runs it, draws a bar with the total for identify, refine, delay and
// diagnose, and nothing with --quiet.

#include <gtest/gtest.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::CommandResult;
using testing::MakeTempDir;
using testing::RunRotorid;

// Runs rotorid with stdin, stdout and stderr on a pseudo-terminal; `out` is everything the
// terminal received.
CommandResult RunOnTerminal(const std::vector<std::string>& args) {
  CommandResult result;
  const char* binary = std::getenv("ROTORID_BINARY");
  if (!binary) {
    result.err = "ROTORID_BINARY is not set";
    return result;
  }
  int terminal = -1;
  const pid_t pid = forkpty(&terminal, nullptr, nullptr, nullptr);
  if (pid < 0) {
    result.err = "forkpty failed";
    return result;
  }
  if (pid == 0) {
    std::vector<char*> argv = {const_cast<char*>(binary)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(binary, argv.data());
    _exit(127);
  }
  char buffer[4096];
  for (;;) {  // until the child closes the terminal (read fails with EIO)
    const ssize_t n = read(terminal, buffer, sizeof buffer);
    if (n > 0) {
      result.out.append(buffer, static_cast<size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;
    }
  }
  close(terminal);
  int status = 0;
  waitpid(pid, &status, 0);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

class CliProgressTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(MakeTempDir("rotorid-cli-progress"));
    // A delay, so that the diagnosis refines candidates in its folds.
    const auto r = RunRotorid({"simulate", "--preset", "B", "--seconds", "30", "--seed", "8", "--effect",
                               "delay_s=0.02", "--out", *dir_ + "/f.csv", "--vehicle-out", *dir_ + "/B.yaml", "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::vector<std::string> Args(std::vector<std::string> head) {
    for (const std::string& a : {std::string("--vehicle"), *dir_ + "/B.yaml", std::string("--log"), *dir_ + "/f.csv"})
      head.push_back(a);
    return head;
  }
  static std::string* dir_;
};
std::string* CliProgressTest::dir_ = nullptr;

TEST_F(CliProgressTest, EachLongCommandDrawsABarWithItsTotal) {
  const struct {
    std::vector<std::string> command;
    std::string bar;
  } cases[] = {
      {{"identify"}, "identify: processing, system, TLS ["},
      // One effect each: the bars are under test, not the fits (the confounded delay and lag pair
      // took 22 s under the sanitizers, the default five candidates 13 s).
      {{"refine", "--effects", "delay"}, "refine: delay search and Ceres passes ["},
      {{"delay"}, "delay: search and Ceres passes ["},
      {{"diagnose", "--folds", "3", "--effects", "delay"}, "diagnose: fitting "},
  };
  for (const auto& c : cases) {
    const CommandResult r = RunOnTerminal(Args(c.command));
    ASSERT_EQ(r.exit_code, 0) << c.command[0] << "\n" << r.out;
    const size_t bar = r.out.find(c.bar);
    ASSERT_NE(bar, std::string::npos) << c.command[0] << "\n" << r.out;
    // The bar ends at its total ("(n/n)") and its line is ended before the results are printed.
    const size_t count = r.out.find('(', bar);
    const size_t slash = r.out.find('/', count);
    const size_t close = r.out.find(')', slash);
    ASSERT_NE(close, std::string::npos) << r.out;
    const std::string total = r.out.substr(slash + 1, close - slash - 1);
    EXPECT_NE(r.out.find("(" + total + "/" + total + ")", bar), std::string::npos) << c.command[0] << "\n" << r.out;
    EXPECT_NE(r.out.find("\n", r.out.rfind("(" + total + "/" + total + ")")), std::string::npos) << r.out;
    if (c.command[0] == "diagnose") {
      EXPECT_NE(r.out.find(" folds [", bar), std::string::npos) << r.out;
    }
  }
}

TEST_F(CliProgressTest, QuietDrawsNothing) {
  const CommandResult r = RunOnTerminal(Args({"refine", "--effects", "delay", "-q"}));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(r.out.find("refine: delay search"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find('\r'), std::string::npos) << r.out;
}

}  // namespace
}  // namespace rotorid

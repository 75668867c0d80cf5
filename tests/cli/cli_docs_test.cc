// docs/cli.md stays in sync with the binary: every subcommand and every long option that a
// subcommand's --help lists appears in it (as `name` / `--option`).

#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <sstream>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::RunRotorid;

// The long options of a --help text: the option column of lines that start with "-".
std::set<std::string> LongOptions(const std::string& help) {
  std::set<std::string> options;
  std::istringstream lines(help);
  const std::regex option("--[a-z][a-z0-9-]*");
  for (std::string line; std::getline(lines, line);) {
    const size_t start = line.find_first_not_of(' ');
    if (start == std::string::npos || line[start] != '-') continue;
    const std::string column = line.substr(start, line.find("  ", start) - start);
    for (auto it = std::sregex_iterator(column.begin(), column.end(), option); it != std::sregex_iterator(); ++it)
      options.insert(it->str());
  }
  return options;
}

TEST(CliDocsTest, EveryOptionOfEverySubcommandIsDocumented) {
  const std::string docs = testing::Slurp(testing::SourceDir() + "/docs/cli.md");
  ASSERT_FALSE(docs.empty());
  const auto root = RunRotorid({"--help"});
  ASSERT_EQ(root.exit_code, 0);
  const std::vector<std::string> subcommands = {"simulate", "identify", "validate", "refine", "delay",  "ablate",
                                                "diagnose", "vehicle",  "export",   "batch",  "predict"};
  for (const std::string& sub : subcommands) {
    EXPECT_NE(root.out.find(sub), std::string::npos) << sub << " missing from rotorid --help";
    EXPECT_NE(docs.find("`" + sub + "`"), std::string::npos) << "docs/cli.md does not list " << sub;
    const auto help = RunRotorid({sub, "--help"});
    ASSERT_EQ(help.exit_code, 0) << sub;
    const std::set<std::string> options = LongOptions(help.out);
    EXPECT_GT(options.size(), 3u) << sub << ": " << help.out;
    for (const std::string& option : options) {
      if (option == "--help") continue;
      EXPECT_NE(docs.find("`" + option), std::string::npos) << "docs/cli.md lacks " << sub << " " << option;
    }
  }
}

}  // namespace
}  // namespace rotorid

// rotorid batch end to end: a manifest with a window, options and a missing log; one JSON line per
// entry; two shards give the same lines as one run; a second run resumes (skips what is done).

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;
using testing::Slurp;

std::vector<std::string> Lines(const std::string& path) {
  std::vector<std::string> lines;
  std::istringstream in(Slurp(path));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> Sorted(std::vector<std::string> lines) {
  std::sort(lines.begin(), lines.end());
  return lines;
}

TEST(CliBatchTest, ManifestShardsAndResume) {
  const std::string dir = MakeTempDir("rotorid-batch");
  std::filesystem::create_directories(dir + "/logs");
  for (const char* seed : {"1", "2", "3"}) {
    const auto r = RunRotorid({"simulate", "--preset", "B", "--seconds", "8", "--seed", seed, "--out",
                               dir + "/logs/f" + seed + ".csv", "--vehicle-out", dir + "/B.yaml", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::ofstream(dir + "/manifest.yaml") << "logs:\n"
                                        << "  - {vehicle: B.yaml, log: logs/f1.csv}\n"
                                        << "  - {vehicle: B.yaml, log: logs/f2.csv, window: [1, 7]}\n"
                                        << "  - {vehicle: B.yaml, log: logs/f3.csv, options: {cutoff-hz: 8}}\n"
                                        << "  - {vehicle: B.yaml, log: logs/missing.csv}\n";
  const std::string manifest = dir + "/manifest.yaml";
  const auto all = RunRotorid({"batch", "--manifest", manifest, "--out", dir + "/all.jsonl", "--jobs", "2"});
  EXPECT_EQ(all.exit_code, 1) << all.err;  // one entry failed
  const std::vector<std::string> lines = Lines(dir + "/all.jsonl");
  ASSERT_EQ(lines.size(), 4u);
  int ok = 0;
  for (const std::string& text : lines) {
    const nlohmann::json line = nlohmann::json::parse(text);
    EXPECT_EQ(line["vehicle"], dir + "/B.yaml");
    if (line["log"] == dir + "/logs/missing.csv") {
      EXPECT_EQ(line["status"], "failed");
      EXPECT_NE(line["error"].get<std::string>().find("missing.csv"), std::string::npos) << text;
      continue;
    }
    ++ok;
    EXPECT_EQ(line["status"], "ok") << text;
    const nlohmann::json& report = line["report"];
    EXPECT_EQ(report["command"], "identify");
    EXPECT_GT(report["linear"]["parameters"]["kt"]["value"].get<double>(), 0.0);
    if (line["log"] == dir + "/logs/f2.csv") {
      EXPECT_EQ(line["window"], nlohmann::json({1.0, 7.0}));
      EXPECT_NEAR(report["input"]["flights"][0]["used_s"].get<double>(), 6.0, 0.01);
    }
    if (line["log"] == dir + "/logs/f3.csv") {
      EXPECT_EQ(report["settings"]["observation"]["filter"]["cutoff_hz"].get<double>(), 8.0)
          << report["settings"].dump();
    }
  }
  EXPECT_EQ(ok, 3);

  // Two shards, as two array jobs would run them, give the same lines.
  for (const char* shard : {"1/2", "2/2"}) {
    const auto r = RunRotorid({"batch", "--manifest", manifest, "--out", dir + "/shards.jsonl", "--shard", shard});
    EXPECT_NE(r.exit_code, 2) << r.err;
  }
  EXPECT_EQ(Sorted(Lines(dir + "/shards.jsonl")), Sorted(lines));

  // Resume: nothing left to do, nothing appended.
  const auto again = RunRotorid({"batch", "--manifest", manifest, "--out", dir + "/all.jsonl", "--jobs", "2"});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("4 already in the output"), std::string::npos) << again.out;
  EXPECT_EQ(Lines(dir + "/all.jsonl").size(), 4u);

  // A stopped run left a cut line: that entry runs again.
  std::vector<std::string> kept = Lines(dir + "/all.jsonl");
  std::ofstream(dir + "/cut.jsonl") << kept[0] << "\n" << kept[1].substr(0, 40);
  const auto resumed = RunRotorid({"batch", "--manifest", manifest, "--out", dir + "/cut.jsonl"});
  EXPECT_NE(resumed.out.find("on 3 of 4 entries"), std::string::npos) << resumed.out;

  const auto bad_shard = RunRotorid({"batch", "--manifest", manifest, "--out", dir + "/x.jsonl", "--shard", "3/2"});
  EXPECT_EQ(bad_shard.exit_code, 2);
  std::ofstream(dir + "/bad.yaml") << "logs:\n  - {vehicle: B.yaml, lg: a.csv}\n";
  const auto bad_manifest = RunRotorid({"batch", "--manifest", dir + "/bad.yaml", "--out", dir + "/y.jsonl"});
  EXPECT_EQ(bad_manifest.exit_code, 1);
  EXPECT_NE(bad_manifest.err.find("bad.yaml:2"), std::string::npos) << bad_manifest.err;
}

}  // namespace
}  // namespace rotorid

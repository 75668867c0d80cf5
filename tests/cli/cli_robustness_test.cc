// Nothing lost, nothing silently wrong (issue 42): each case of the adversarial campaign as a run of
// the CLI that either gives a clear error (exit 1, 2 or 3 naming the cause and the file) or a correct
// result, and that changes no input file.

#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;
using testing::Slurp;

bool Contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::vector<std::string> Lines(const std::string& path) {
  std::vector<std::string> lines;
  std::istringstream in(Slurp(path));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

class CliRobustnessTest : public ::testing::Test {
 protected:
  // One simulated flight of configuration A (10 s) with its vehicle file.
  static void SetUpTestSuite() {
    dir_ = new std::string(MakeTempDir("rotorid-robust"));
    const auto r = RunRotorid(
        {"simulate", "--preset", "A", "--seconds", "10", "--out", Log(), "--vehicle-out", Vehicle(), "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { delete dir_; }

  static const std::string& Dir() { return *dir_; }
  static std::string Log() { return Dir() + "/a.csv"; }
  static std::string Vehicle() { return Dir() + "/A.yaml"; }
  static std::string Write(const std::string& name, const std::string& text) {
    const std::string path = Dir() + "/" + name;
    std::ofstream(path) << text;
    return path;
  }
  // The log with every rotor column multiplied by `factor` (the units of another tool).
  static std::string ScaledRotorLog(const std::string& name, double factor) {
    return EditedLog(name, [factor](std::vector<double>* row) {
      for (size_t k = 7; k < row->size(); ++k) (*row)[k] *= factor;
    });
  }
  // The log with the gyro and accelerometer turned `yaw_deg` about z (an IMU board mounted yawed).
  static std::string YawedImuLog(const std::string& name, double yaw_deg) {
    const double c = std::cos(yaw_deg * M_PI / 180.0), s = std::sin(yaw_deg * M_PI / 180.0);
    return EditedLog(name, [c, s](std::vector<double>* row) {
      for (size_t k : {1, 4}) {
        const double x = (*row)[k], y = (*row)[k + 1];
        (*row)[k] = c * x + s * y;
        (*row)[k + 1] = -s * x + c * y;
      }
    });
  }
  // `first` with `second`'s samples after its first 2 s appended on one time base (5 ms steps).
  static std::string JoinedLog(const std::string& name, const std::string& first, const std::string& second) {
    std::string joined = Slurp(first);
    const double first_end = std::stod(joined.substr(joined.rfind('\n', joined.size() - 2) + 1));
    std::istringstream rest(Slurp(second));
    int sample = 0;
    for (std::string line; std::getline(rest, line);) {
      if (line.empty() || !std::isdigit(static_cast<unsigned char>(line[0])) || sample++ < 400) continue;
      std::ostringstream t;
      t.precision(17);
      t << first_end + 0.005 * (sample - 400);
      joined += t.str() + line.substr(line.find(',')) + "\n";
    }
    return Write(name, joined);
  }
  // The log (or `source`) with each data row (t, gyro, acc, rotors, ...) changed by `edit`.
  static std::string EditedLog(const std::string& name, const std::function<void(std::vector<double>*)>& edit,
                               const std::string& source = Log()) {
    std::istringstream in(Slurp(source));
    std::ostringstream out;
    out.precision(17);
    bool header_seen = false;
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#' || !header_seen) {
        header_seen = header_seen || (!line.empty() && line[0] != '#');
        out << line << "\n";
        continue;
      }
      std::istringstream cells(line);
      std::vector<double> row;
      for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
      edit(&row);
      for (size_t k = 0; k < row.size(); ++k) out << (k ? "," : "") << row[k];
      out << "\n";
    }
    return Write(name, out.str());
  }

 private:
  static std::string* dir_;
};
std::string* CliRobustnessTest::dir_ = nullptr;

// 1. An output path that is an input (the same path, a hard link, a symlink) is refused with exit 2
// before any work, and the input keeps its bytes.
TEST_F(CliRobustnessTest, OutputsNamingAnInputAreRefusedBeforeAnyWork) {
  const std::string log_copy = Write("copy.csv", Slurp(Log()));
  const std::string vehicle_copy = Write("copy.yaml", Slurp(Vehicle()));
  const std::string hard_link = Dir() + "/hard.csv", symlink = Dir() + "/link.yaml";
  std::filesystem::create_hard_link(log_copy, hard_link);
  std::filesystem::create_symlink(vehicle_copy, symlink);
  const std::string map = Write("map.yaml",
                                "time: {column: t, unit: s}\ngyro: {columns: [gyro_x, gyro_y, gyro_z], unit: rad/s}\n"
                                "acc: {columns: [acc_x, acc_y, acc_z], unit: m/s^2}\n"
                                "rotors: {columns: [rotor_1, rotor_2, rotor_3, rotor_4], unit: rad/s}\n");
  const std::string manifest = Write("manifest.yaml", "logs:\n  - {vehicle: copy.yaml, log: copy.csv}\n");
  const std::string config = Write("config.yaml", "cutoff-hz: 8\n");
  const std::vector<std::string> base = {"identify", "--vehicle", vehicle_copy, "--log", log_copy, "--quiet"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  const std::vector<std::vector<std::string>> cases = {
      with({"--json", log_copy}),
      with({"--json", vehicle_copy}),
      with({"--json", hard_link}),  // the log through a hard link
      with({"--json", symlink}),    // the vehicle file through a symlink
      with({"--column-map", map, "--json", map}),
      with({"--config", config, "--json", config}),
      {"validate", "--params", vehicle_copy, "--vehicle", vehicle_copy, "--log", log_copy, "--json", vehicle_copy},
      {"vehicle", "--log", log_copy, "--mass", "1", "--column-map", map, "--out", log_copy},
      {"simulate", "--vehicle", vehicle_copy, "--seconds", "2", "--out", Dir() + "/s.csv", "--vehicle-out", symlink},
      {"simulate", "--seconds", "2", "--out", Dir() + "/s.csv", "--json", Dir() + "/s.csv"},
      {"batch", "--manifest", manifest, "--out", manifest},
  };
  const std::string log_bytes = Slurp(log_copy), vehicle_bytes = Slurp(vehicle_copy), map_bytes = Slurp(map),
                    manifest_bytes = Slurp(manifest), config_bytes = Slurp(config);
  for (const auto& args : cases) {
    std::string line;
    for (const std::string& a : args) line += a + " ";
    const auto r = RunRotorid(args);
    EXPECT_EQ(r.exit_code, 2) << line << "\n" << r.err;
    EXPECT_TRUE(Contains(r.err, "is the input") || Contains(r.err, "name the same file")) << line << "\n" << r.err;
  }
  EXPECT_EQ(Slurp(log_copy), log_bytes);
  EXPECT_EQ(Slurp(vehicle_copy), vehicle_bytes);
  EXPECT_EQ(Slurp(map), map_bytes);
  EXPECT_EQ(Slurp(manifest), manifest_bytes);
  EXPECT_EQ(Slurp(config), config_bytes);
  EXPECT_TRUE(std::filesystem::is_symlink(symlink));

  // A value that is no input may name an existing file: `--preset A --out A`, run twice in one folder.
  const std::filesystem::path cwd = std::filesystem::current_path();
  std::filesystem::current_path(Dir());
  for (int run = 0; run < 2; ++run) {
    const auto again = RunRotorid({"simulate", "--preset", "A", "--seconds", "2", "--out", "A", "--quiet"});
    EXPECT_EQ(again.exit_code, 0) << again.err;
  }
  std::filesystem::current_path(cwd);

  // batch: an entry's log as --out.
  const std::string entry_manifest = Write("entry_manifest.yaml", "logs:\n  - {vehicle: copy.yaml, log: copy.csv}\n");
  const auto r = RunRotorid({"batch", "--manifest", entry_manifest, "--out", log_copy});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "lists --out")) << r.err;
  EXPECT_EQ(Slurp(log_copy), log_bytes);
}

// 9. A FIFO, a device or a missing folder as an output: exit 2 while parsing, not exit 1 after the
// whole computation (a FIFO without a reader would also block it).
TEST_F(CliRobustnessTest, OutputsThatCannotBeWrittenAreRefusedWhileParsing) {
  const std::string fifo = Dir() + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  for (const std::string& output : {fifo, std::string("/dev/null"), Dir() + "/missing/report.json"}) {
    const auto r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Log(), "--json", output, "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << output << ": " << r.err;
    EXPECT_TRUE(Contains(r.err, output) || Contains(r.err, Dir() + "/missing")) << r.err;
  }
}

// 2, 6. rad/s gyro data read through a column map that says deg/s (57x too little), rotor speeds in
// rev/s, an IMU yawed 45 deg: the input checks fail (exit 3) and name the cause.
TEST_F(CliRobustnessTest, UnitAndAlignmentMistakesFailTheirChecks) {
  const std::string map = Write("deg_map.yaml",
                                "time: {column: t, unit: s}\ngyro: {columns: [gyro_x, gyro_y, gyro_z], unit: deg/s}\n"
                                "acc: {columns: [acc_x, acc_y, acc_z], unit: m/s^2}\n"
                                "rotors: {columns: [rotor_1, rotor_2, rotor_3, rotor_4], unit: rad/s}\n");
  const std::string json = Dir() + "/deg.json";
  auto r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Log(), "--column-map", map, "--json", json});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "57 times too little")) << r.err;
  bool named = false;
  const nlohmann::json report = nlohmann::json::parse(Slurp(json));
  for (const auto& check : report["checks"]) named |= check["name"] == "gyro_units" && check["status"] == "error";
  EXPECT_TRUE(named);

  const std::string rev_log = ScaledRotorLog("rev.csv", 1.0 / (2.0 * M_PI));
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", rev_log, "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "rev/s") && Contains(r.err, "rev.csv")) << r.err;

  // deg/s data read as rad/s (57x too much): named before the segmentation leaves most of it out.
  const std::string fast = EditedLog("fast.csv", [](std::vector<double>* row) {
    for (size_t k = 1; k < 4; ++k) (*row)[k] *= 180.0 / M_PI;
  });
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", fast, "--quiet"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "fast.csv: the gyro appears to be in deg/s")) << r.err;

  // An IMU yawed 45 deg against the rotors (board alignment, or an X vehicle file for a + quad).
  const std::string yawed = YawedImuLog("yawed.csv", 45.0);
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", yawed, "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "IMU appears yawed") && Contains(r.err, "yawed.csv")) << r.err;

  // Motion-capture Euler angles in degrees.
  const std::string mocap = Dir() + "/mocap.csv";
  r = RunRotorid({"simulate", "--preset", "A", "--seconds", "10", "--mocap", "--out", mocap, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string degrees = EditedLog(
      "degrees.csv",
      [](std::vector<double>* row) {
        for (size_t k = 14; k < 17; ++k) (*row)[k] *= 180.0 / M_PI;
      },
      mocap);
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", degrees, "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check attitude") && Contains(r.err, "in degrees")) << r.err;

  // A motion-capture quaternion written x, y, z, w under qw, qx, qy, qz (another tool's order).
  std::string xyzw = Slurp(EditedLog(
      "xyzw_rows.csv",
      [](std::vector<double>* row) {
        const Eigen::Quaterniond q = Eigen::AngleAxisd((*row)[16], Eigen::Vector3d::UnitZ()) *
                                     Eigen::AngleAxisd((*row)[15], Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd((*row)[14], Eigen::Vector3d::UnitX());
        (*row)[14] = q.x(), (*row)[15] = q.y(), (*row)[16] = q.z();
        row->insert(row->begin() + 17, q.w());
      },
      mocap));
  xyzw.replace(xyzw.find("roll,pitch,yaw"), 14, "qw,qx,qy,qz");
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Write("xyzw.csv", xyzw), "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check attitude: error") && Contains(r.err, "quaternion order")) << r.err;

  // Two motion-capture flights joined on one time base: the position jumps.
  const std::string second = Dir() + "/mocap2.csv";
  r = RunRotorid({"simulate", "--preset", "A", "--seconds", "10", "--seed", "2", "--mocap", "--out", second, "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", JoinedLog("joined.csv", mocap, second), "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check state_jump") && Contains(r.err, "joined.csv: the position jumps")) << r.err;

  // The same without motion capture: the gyro steps by 0.57 rad/s, which no rotor moment made (exit 0
  // before, kd and I_zz discarded and ms_z -6e-3 for 0).
  const std::string second_imu = Dir() + "/imu2.csv";
  r = RunRotorid({"simulate", "--preset", "A", "--seconds", "10", "--seed", "2", "--out", second_imu, "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", JoinedLog("joined_imu.csv", Log(), second_imu), "-q"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check state_jump: error: ") &&
              Contains(r.err, "joined_imu.csv: the angular velocity jumps by") &&
              Contains(r.err, "two flights joined on one time base"))
      << r.err;

  // An accelerometer that saturates at 11 m/s^2.
  const std::string clipped = EditedLog("clipped.csv", [](std::vector<double>* row) {
    for (size_t k = 4; k < 7; ++k) (*row)[k] = std::clamp((*row)[k], -11.0, 11.0);
  });
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", clipped, "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check saturation") && Contains(r.err, "acc_z sits at 11")) << r.err;

  // A dead rotor (its column all zeros), even with --allow-partial.
  const std::string dead = EditedLog("dead.csv", [](std::vector<double>* row) { (*row)[9] = 0.0; });
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", dead, "--allow-partial", "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check rotor_signal") && Contains(r.err, "rotor_3 reads 0")) << r.err;

  // Rotors 1 and 3 exchanged (a column map or vehicle file with two rotors of opposite spin swapped):
  // roll and pitch still correlate at 0.5, the yaw pattern is lost (exit 0 with --allow-partial
  // before, kd and I_zz wrong; without it "fly more roll and pitch", or "IMU yawed").
  const std::string swapped =
      EditedLog("swapped.csv", [](std::vector<double>* row) { std::swap((*row)[7], (*row)[9]); });
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", swapped, "--allow-partial", "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check rotor_order: error: rotors 1 and 3 appear swapped")) << r.err;
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", swapped, "--quiet"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "likely cause: rotors 1 and 3 appear swapped")) << r.err;

  // A 50 Hz log at the default 10 Hz cut-off.
  const std::string slow = Dir() + "/slow.csv";
  r = RunRotorid({"simulate", "--preset", "A", "--seconds", "10", "--rate", "50", "--out", slow, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", slow, "--quiet"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(Contains(r.err, "check sample_rate") && Contains(r.err, "--cutoff-hz 2.5")) << r.err;
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", slow, "--cutoff-hz", "2.5", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;

  // The same flight in rad/s, IMU aligned, passes every check.
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Log(), "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// 6. UNIX-epoch time stamps: the bundled A flight with 1.7e9 s added to each stamp's digits gives the
// parameters of the flight from 0 to 1e-9 (kd, I_zz were -0.4 to -4 % off: a double resolves 1.7e9 s to
// 2.4e-7 s). Stamps already rounded through a double (printed with 17 digits) come within 1e-5; a
// --window on the wall clock is the same window counted from the first stamp.
TEST_F(CliRobustnessTest, EpochTimeStampsGiveTheParametersOfTheFlightFromZero) {
  const std::string bundled = testing::SourceDir() + "/data/sim/A_train.csv";
  const std::string vehicle = testing::SourceDir() + "/data/sim/A.yaml";
  std::istringstream in(Slurp(bundled));
  std::string shifted, rounded;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || !std::isdigit(static_cast<unsigned char>(line[0]))) {
      shifted += line + "\n", rounded += line + "\n";
      continue;
    }
    const size_t comma = line.find(','), point = line.find('.');
    const std::string stamp = line.substr(0, comma);
    const long long whole = std::stoll(stamp.substr(0, std::min(point, comma)));
    shifted += std::to_string(1700000000LL + whole) + (point < comma ? line.substr(point) : line.substr(comma)) + "\n";
    std::ostringstream t;
    t.precision(17);
    t << std::stod(stamp) + 1.7e9;
    rounded += t.str() + line.substr(comma) + "\n";
  }
  auto parameters = [&](const std::string& log, std::vector<std::string> extra) {
    const std::string json = Dir() + "/epoch.json";
    std::vector<std::string> args = {"identify", "--vehicle", vehicle, "--log", log, "--json", json};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = RunRotorid(args);
    EXPECT_EQ(r.exit_code, 0) << log << ": " << r.err;
    return std::make_pair(nlohmann::json::parse(Slurp(json))["linear"]["parameters"], r.out + r.err);
  };
  const auto reference = parameters(bundled, {"-q"}).first;
  auto largest_difference = [&](const nlohmann::json& p) {
    double largest = 0.0;
    for (const auto& [name, value] : reference.items())
      if (value["value"].get<double>() != 0.0)
        largest = std::max(largest, std::abs(p[name]["value"].get<double>() / value["value"].get<double>() - 1.0));
    return largest;
  };
  const auto [epoch, console] = parameters(Write("epoch.csv", shifted), {});
  EXPECT_LT(largest_difference(epoch), 1e-9);
  EXPECT_TRUE(Contains(console, "wall clock from 1700000000.000000000 s")) << console;
  EXPECT_FALSE(Contains(console, "check time_base")) << console;
  EXPECT_LT(largest_difference(parameters(Write("epoch17.csv", rounded), {"-q"}).first), 1e-5);
  EXPECT_EQ(parameters(Dir() + "/epoch.csv", {"--window", "1700000010,1700000050", "-q"}).first,
            parameters(Dir() + "/epoch.csv", {"--window", "10,50", "-q"}).first);
}

// 3. A YAML alias bomb (a few hundred bytes that expand to 9^9 nodes) is refused by every YAML
// reader instead of hanging them; so are a second document and an unknown vehicle-file key.
TEST_F(CliRobustnessTest, YamlAliasBombsAndExtraDocumentsAreRefused) {
  std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 9; ++i) {
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) bomb += (k ? ", *a" : "*a") + std::to_string(i - 1);
    bomb += "]\n";
  }
  const std::string vehicle = Write("bomb_vehicle.yaml", bomb + "mass: 1\nrotors: *a8\n");
  const std::string map = Write("bomb_map.yaml", bomb + "time: {column: t, unit: s}\n");
  const std::string manifest = Write("bomb_manifest.yaml", bomb + "logs: *a8\n");
  const std::string config = Write("bomb_config.yaml", bomb + "cutoff-hz: 8\n");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"identify", "--vehicle", vehicle, "--log", Log()}, vehicle},
      {{"identify", "--vehicle", Vehicle(), "--log", Log(), "--column-map", map}, map},
      {{"batch", "--manifest", manifest, "--out", Dir() + "/bomb.jsonl"}, manifest},
      {{"identify", "--vehicle", Vehicle(), "--log", Log(), "--config", config}, config},
  };
  for (const auto& [args, file] : cases) {
    const auto r = RunRotorid(args);
    EXPECT_TRUE(r.exit_code == 1 || r.exit_code == 2) << file << ": " << r.err;
    EXPECT_TRUE(Contains(r.err, file) && Contains(r.err, "aliases")) << r.err;
  }
  const std::string two_documents = Write("two.yaml", Slurp(Vehicle()) + "---\nmass: 2\n");
  auto r = RunRotorid({"identify", "--vehicle", two_documents, "--log", Log(), "--quiet"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "two.yaml") && Contains(r.err, "second YAML document")) << r.err;
  const std::string unknown_key = Write("unknown.yaml", Slurp(Vehicle()) + "masss: 2\n");
  r = RunRotorid({"identify", "--vehicle", unknown_key, "--log", Log(), "--quiet"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "unknown.yaml") && Contains(r.err, "masss")) << r.err;
}

// 4. Option values far out of range are usage errors found while parsing (--edge-trim-s 1e7 and
// inf crashed identify and refine; --threads 1e6 exhausted the machine).
TEST_F(CliRobustnessTest, OptionValuesOutOfRangeAreUsageErrors) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"--edge-trim-s", {"identify", "--edge-trim-s", "1e7"}}, {"--edge-trim-s", {"refine", "--edge-trim-s", "inf"}},
      {"--cutoff-hz", {"identify", "--cutoff-hz", "nan"}},     {"--filter-order", {"identify", "--filter-order", "99"}},
      {"--threads", {"refine", "--threads", "1000000"}},       {"--weight", {"identify", "--weight", "-1"}},
  };
  for (const auto& [option, args] : cases) {
    std::vector<std::string> full = args;
    full.insert(full.end(), {"--vehicle", Vehicle(), "--log", Log(), "--quiet"});
    const auto r = RunRotorid(full);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
    EXPECT_TRUE(Contains(r.err, option)) << r.err;
  }
}

// 5. A device as a log (--log /dev/zero grew to 17 GB) and a vehicle file of a million rotors
// (3.85 GB) are refused by their path and size before they are parsed.
TEST_F(CliRobustnessTest, DevicesAndOversizedInputsAreRefusedBeforeReading) {
  auto r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", "/dev/zero", "--quiet"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "/dev/zero") && Contains(r.err, "not a regular file")) << r.err;
  std::string rotors = "name: A\nmass: 1\nrotors:\n";
  for (int i = 0; i < 1000000; ++i) rotors += "  - {position: [0.2, 0, 0], spin: 1}\n";
  const std::string huge = Write("huge.yaml", rotors);
  r = RunRotorid({"identify", "--vehicle", huge, "--log", Log(), "--quiet"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "huge.yaml") && Contains(r.err, "MB")) << r.err;
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Log(), "--config", "/dev/zero"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(Contains(r.err, "--config")) << r.err;
}

// 4, 7. batch: an output that fills up (a file size limit) ends the run with exit 1 and only complete
// lines; a cut-short line of an earlier run is dropped; entries are told apart by their options; a
// second batch on the same output is refused.
TEST_F(CliRobustnessTest, BatchOutputStaysLineCompleteAndResumesByOptions) {
  const std::string manifest = Write("sweep.yaml",
                                     "logs:\n"
                                     "  - {vehicle: A.yaml, log: missing1.csv}\n"
                                     "  - {vehicle: A.yaml, log: missing2.csv}\n"
                                     "  - {vehicle: A.yaml, log: missing3.csv}\n"
                                     "  - {vehicle: A.yaml, log: a.csv, options: {cutoff-hz: 8}}\n"
                                     "  - {vehicle: A.yaml, log: a.csv, options: {cutoff-hz: 12}}\n");
  const std::string out = Dir() + "/sweep.jsonl";
  // A file size limit as a full disk: writes past it fail with EFBIG (SIGXFSZ ignored, inherited).
  struct rlimit saved {};
  ::getrlimit(RLIMIT_FSIZE, &saved);
  const auto previous = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit limited = saved;
  limited.rlim_cur = 700;
  ::setrlimit(RLIMIT_FSIZE, &limited);
  auto r = RunRotorid({"batch", "--manifest", manifest, "--out", out, "--quiet"});
  ::setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, previous);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, out) && Contains(r.err, "cannot append")) << r.err;
  const std::string partial = Slurp(out);
  ASSERT_FALSE(partial.empty());
  EXPECT_EQ(partial.back(), '\n');
  for (const std::string& line : Lines(out)) EXPECT_NO_THROW(nlohmann::json::parse(line)) << line;

  // A line cut short by a crash: dropped, and its entry runs again.
  std::ofstream(out, std::ios::app) << R"({"log": ")" << Dir() << "/missing2.c";
  r = RunRotorid({"batch", "--manifest", manifest, "--out", out});
  EXPECT_EQ(r.exit_code, 1) << r.err;  // the missing logs fail
  EXPECT_TRUE(Contains(r.err, "dropped 1 incomplete line")) << r.err;
  const std::vector<std::string> lines = Lines(out);
  ASSERT_EQ(lines.size(), 5u) << Slurp(out);
  std::set<double> cutoffs;
  for (const std::string& text : lines) {
    const nlohmann::json line = nlohmann::json::parse(text);
    if (line["status"] == "ok")
      cutoffs.insert(line["report"]["settings"]["observation"]["filter"]["cutoff_hz"].get<double>());
  }
  EXPECT_EQ(cutoffs, (std::set<double>{8.0, 12.0}));

  // Another run holds the output: refused, nothing appended.
  const int fd = ::open(out.c_str(), O_RDONLY);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  r = RunRotorid({"batch", "--manifest", manifest, "--out", out});
  ::close(fd);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "another rotorid batch")) << r.err;
  EXPECT_EQ(Lines(out).size(), 5u);
}

// 9. --report into the folder of an earlier report whose figures the user edited: an edited figure
// the new report does not draw is kept (it was deleted), one it draws again is kept and this run's is
// written beside it with a warning; figures as rotorid left them are replaced or removed as before.
TEST_F(CliRobustnessTest, ReportKeepsFiguresTheUserChanged) {
  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) GTEST_SKIP() << "gnuplot is not installed";
  const std::string folder = Dir() + "/report";
  auto r = RunRotorid({"refine", "--vehicle", Vehicle(), "--log", Log(), "--validate-vehicle", Vehicle(),
                       "--validate-log", Log(), "--report", folder, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string held_out = folder + "/fig_spectrum_held_out.svg", parameters = folder + "/fig_parameters.svg";
  ASSERT_TRUE(std::filesystem::exists(held_out) && std::filesystem::exists(folder + "/fig_wrench_2.svg"));
  std::ofstream(held_out, std::ios::app) << "<!-- the user's note -->\n";
  std::ofstream(parameters, std::ios::app) << "<!-- the user's note -->\n";
  const std::string held_out_bytes = Slurp(held_out), parameters_bytes = Slurp(parameters);
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Log(), "--report", folder});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Slurp(held_out), held_out_bytes);
  EXPECT_EQ(Slurp(parameters), parameters_bytes);
  EXPECT_TRUE(Contains(r.err, parameters + " was changed since rotorid wrote it") &&
              Contains(r.err, "fig_parameters.new.svg"))
      << r.err;
  EXPECT_TRUE(Contains(Slurp(folder + "/fig_parameters.new.svg"), "<svg"));
  EXPECT_FALSE(std::filesystem::exists(folder + "/fig_wrench_2.svg"));  // rotorid's, unchanged: removed
}

// 10. A spreadsheet's CSV: a byte-order mark and quoted cells are read as they are meant; a header
// separated by ';' names the column map's delimiter instead of "missing required column 't'".
TEST_F(CliRobustnessTest, SpreadsheetCsvIsReadOrNamesItsSeparator) {
  std::istringstream in(Slurp(Log()));
  std::string quoted = "\xEF\xBB\xBF", semicolons;
  for (std::string line; std::getline(in, line);) {
    std::string q = line, c = line;
    if (!line.empty() && line[0] != '#') {
      q = "\"" + line + "\"";
      for (size_t k = 0; (k = q.find(',', k)) != std::string::npos; k += 3) q.replace(k, 1, "\",\"");
      std::replace(c.begin(), c.end(), ',', ';');
    }
    quoted += q + "\n";
    semicolons += c + "\n";
  }
  const std::string json = Dir() + "/quoted.json", reference = Dir() + "/reference.json";
  auto r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Write("quoted.csv", quoted), "--json", json, "-q"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Log(), "--json", reference, "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(Slurp(json))["linear"]["parameters"],
            nlohmann::json::parse(Slurp(reference))["linear"]["parameters"]);
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log", Write("semicolons.csv", semicolons), "-q"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "semicolons.csv") && Contains(r.err, "delimiter: ';'")) << r.err;
  // A cell of 100 kB quoted in the error: the message stays one line of at most about 1000 characters.
  const std::string header = "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,rotor_1,rotor_2,rotor_3,rotor_4\n";
  r = RunRotorid({"identify", "--vehicle", Vehicle(), "--log",
                  Write("long_cell.csv", header + std::string(100000, 'x') + ",0,0,0,0,0,9.8,1,1,1,1\n"), "-q"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "long_cell.csv") && Contains(r.err, "characters left out")) << r.err;
  EXPECT_LT(r.err.size(), 1200u);
}

// 10. A configuration name that YAML would read otherwise is quoted in the written vehicle file.
TEST_F(CliRobustnessTest, VehicleNameIsWrittenQuoted) {
  const std::string map =
      Write("rotor_map.yaml",
            "time: {column: t, unit: s}\ngyro: {columns: [gyro_x, gyro_y, gyro_z], unit: rad/s}\n"
            "acc: {columns: [acc_x, acc_y, acc_z], unit: m/s^2}\n"
            "rotors: {columns: [rotor_1, rotor_2, rotor_3, rotor_4], unit: rad/s}\n"
            "metadata: {rotor_positions: '[[0, -0.225, 0], [0, 0.225, 0], [0.225, 0, 0], [-0.225, 0, 0]]',\n"
            "           rotor_spins: '[1, 1, -1, -1]'}\n");
  const std::string named = Dir() + "/named.yaml", json = Dir() + "/named.json";
  auto r = RunRotorid({"vehicle", "--log", Log(), "--column-map", map, "--mass", "1.285", "--name", "A: #1", "--out",
                       named, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunRotorid({"identify", "--vehicle", named, "--log", Log(), "--json", json, "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(Slurp(json))["linear"]["parameters"].contains("A: #1.I_zz")) << Slurp(named);
}

}  // namespace
}  // namespace rotorid

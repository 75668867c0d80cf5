// `rotorid simulate` end to end: outputs, byte-for-byte determinism, option errors.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "rotorid/io/flight_csv.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/sim/truth.h"
#include "sim/sim_test_options.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;

using testing::Slurp;

// Short flights; in Debug (sanitizer) builds also the lightest physics, as the binary is slow there.
std::vector<std::string> LightFlight() {
  if (testing::kOptimisedBuild) return {"--seconds", "3"};
  return {"--seconds", "0.5", "--physics-rate", "1000", "--warmup-s", "0.2"};
}

std::vector<std::string> Args(const std::string& dir, const std::string& tag, std::vector<std::string> extra) {
  std::vector<std::string> args = {"simulate",
                                   "--out",
                                   dir + "/" + tag + ".csv",
                                   "--truth",
                                   dir + "/" + tag + ".json",
                                   "--vehicle-out",
                                   dir + "/" + tag + ".yaml"};
  for (const std::string& a : LightFlight()) args.push_back(a);
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

TEST(SimCliTest, WritesLogTruthAndVehicle) {
  const std::string dir = MakeTempDir("sim-cli");
  const auto result = RunRotorid(Args(dir, "b",
                                      {"--preset", "B", "--mocap", "--effect", "delay_s=0.01", "--effect",
                                       "acc_bias=0.1,0.2,0.3", "--json", dir + "/summary.json"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find(testing::kOptimisedBuild ? "simulated 3.0 s" : "simulated 0.5 s"), std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("roll ["), std::string::npos) << result.out;

  const Vehicle vehicle = ReadVehicleYaml(dir + "/b.yaml");
  EXPECT_EQ(vehicle.name, "B");
  EXPECT_DOUBLE_EQ(vehicle.mass_kg, 1.452);
  const FlightLog log = ReadFlightCsv(dir + "/b.csv", vehicle.num_rotors());
  EXPECT_EQ(log.num_samples(), testing::kOptimisedBuild ? 600 : 100);
  EXPECT_TRUE(log.mocap.has_value());
  EXPECT_EQ(log.gravity_mps2, kStandardGravity);
  EXPECT_EQ(log.metadata.at("preset"), "B");

  const SimulationTruth truth = ReadTruthJson(dir + "/b.json");
  EXPECT_EQ(truth.vehicle_name, "B");
  EXPECT_EQ(truth.effects.Scalar("delay_s"), 0.01);
  EXPECT_EQ(truth.effects.Get("acc_bias"), Eigen::Vector3d(0.1, 0.2, 0.3));
  const std::string json = Slurp(dir + "/b.json");
  for (const char* key : {"\"kt\"", "\"kd\"", "\"B.ms_x\"", "\"B.I_yz\"", "\"motor_tau_s\"", "\"misalignment_rad\"",
                          "\"mass\"", "\"noise\"", "\"seed\""})
    EXPECT_NE(json.find(key), std::string::npos) << key;
  EXPECT_NE(Slurp(dir + "/summary.json").find("\"max_tilt_deg\""), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(SimCliTest, SameSeedSameBytesDifferentSeedDifferentFlight) {
  const std::string dir = MakeTempDir("sim-cli");
  const std::vector<std::string> extra = {"--seed",  "7",        "--jitter-s",      "0.0005",
                                          "--mocap", "--effect", "motor_tau_s=0.02"};
  ASSERT_EQ(RunRotorid(Args(dir, "first", extra)).exit_code, 0);
  ASSERT_EQ(RunRotorid(Args(dir, "second", extra)).exit_code, 0);
  for (const char* ext : {".csv", ".json", ".yaml"}) {
    const std::string first = Slurp(dir + "/first" + ext);
    ASSERT_FALSE(first.empty()) << ext;
    EXPECT_EQ(first, Slurp(dir + "/second" + ext)) << ext;
  }
  ASSERT_EQ(
      RunRotorid(Args(dir, "other", {"--seed", "8", "--jitter-s", "0.0005", "--mocap", "--effect", "motor_tau_s=0.02"}))
          .exit_code,
      0);
  EXPECT_NE(Slurp(dir + "/first.csv"), Slurp(dir + "/other.csv"));
  std::filesystem::remove_all(dir);
}

TEST(SimCliTest, FliesAVehicleFileWithItsSimulationMapping) {
  const std::string dir = MakeTempDir("sim-cli");
  std::ofstream(dir + "/hexa.yaml") << "name: H\nmass: 2.0\nrotors:\n"
                                       "  - {position: [0.30, 0.00, 0], spin: +1}\n"
                                       "  - {position: [0.15, 0.26, 0], spin: -1}\n"
                                       "  - {position: [-0.15, 0.26, 0], spin: +1}\n"
                                       "  - {position: [-0.30, 0.00, 0], spin: -1}\n"
                                       "  - {position: [-0.15, -0.26, 0], spin: +1}\n"
                                       "  - {position: [0.15, -0.26, 0], spin: -1}\n"
                                       "simulation: {kt: 3.0e-6, kd: 4.5e-8}\n";
  std::vector<std::string> args = {"simulate",     "--vehicle", dir + "/hexa.yaml", "--out",
                                   dir + "/h.csv", "--truth",   dir + "/h.json"};
  for (const std::string& a : LightFlight()) args.push_back(a);
  const auto result = RunRotorid(args);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const SimulationTruth truth = ReadTruthJson(dir + "/h.json");
  EXPECT_EQ(truth.vehicle_name, "H");
  EXPECT_DOUBLE_EQ(truth.parameters.rotor.kt, 3.0e-6);
  EXPECT_NE(Slurp(dir + "/h.json").find("derived from mass and arm length"), std::string::npos);
  EXPECT_EQ(ReadFlightCsv(dir + "/h.csv", 6).num_rotors(), 6);
  std::filesystem::remove_all(dir);
}

// The Crazyflie-like preset logs at its own rate and noise; --battery writes a command log with a
// voltage column and the vehicle file with its map, which `rotorid` reads back as a command log.
TEST(SimCliTest, CrazyflieLikePresetWithItsBattery) {
  const std::string dir = MakeTempDir("sim-cli");
  const auto result = RunRotorid(
      Args(dir, "cf", {"--preset", "CF", "--battery", "--effect", "battery_exponent=1", "--profile", "yaw-spin"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("at 500 Hz) of vehicle CF"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("noise bmi088"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("profile yaw-spin, battery ["), std::string::npos) << result.out;
  const Vehicle vehicle = ReadVehicleYaml(dir + "/cf.yaml");
  ASSERT_TRUE(vehicle.command_to_speed && vehicle.command_to_speed_voltage_v);
  EXPECT_DOUBLE_EQ(*vehicle.command_to_speed_voltage_v, 3.8);
  const FlightLog log = ReadFlightCsv(dir + "/cf.csv", vehicle.num_rotors());
  ASSERT_TRUE(log.voltage_v.has_value());
  EXPECT_EQ(log.metadata.at("rotor_signal"), "command");
  EXPECT_LE(log.rotor_radps.maxCoeff(), 1.0);
  const std::string truth = Slurp(dir + "/cf.json");
  EXPECT_NE(truth.find("\"profile\": \"yaw-spin\""), std::string::npos);
  EXPECT_NE(truth.find("\"hover_sag_v\": 0.3"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// The external force reaches the truth file; without one the truth has no such key.
TEST(SimCliTest, ExternalForceIsRecordedInTheTruth) {
  const std::string dir = MakeTempDir("sim-cli");
  const auto result =
      RunRotorid(Args(dir, "pushed", {"--external-force", "0.5,-0.25,0", "--external-force-period", "12"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json truth = nlohmann::json::parse(Slurp(dir + "/pushed.json"));
  const nlohmann::json& force = truth["simulation"]["external_force"];
  EXPECT_EQ(force["world_n"], nlohmann::json::array({0.5, -0.25, 0.0}));
  EXPECT_EQ(force["turn_period_s"], 12.0);
  ASSERT_EQ(RunRotorid(Args(dir, "free", {})).exit_code, 0);
  EXPECT_FALSE(nlohmann::json::parse(Slurp(dir + "/free.json"))["simulation"].contains("external_force"));
  std::filesystem::remove_all(dir);
}

TEST(SimCliTest, BadOptionsGiveAOneLineErrorAndANonZeroExit) {
  const std::string dir = MakeTempDir("sim-cli");
  const std::string out = dir + "/x.csv";
  const std::vector<std::vector<std::string>> bad = {
      {"simulate", "--out", out, "--effect", "bogus=1"},
      {"simulate", "--out", out, "--effect", "delay_s=abc"},
      {"simulate", "--out", out, "--seconds", "-5"},
      {"simulate", "--out", out, "--seconds=-5"},
      {"simulate", "--out", out, "--preset", "C"},
      {"simulate", "--out", out, "--noise", "loud"},
      {"simulate", "--out", out, "--rate", "10"},
      {"simulate", "--out", out, "--jitter-s", "0.01"},
      {"simulate", "--out", out, "--preset", "A", "--vehicle", dir + "/missing.yaml"},
      {"simulate", "--out", out, "--vehicle", dir + "/missing.yaml"},
      {"simulate", "--seconds", "2"},
      {"simulate", "--out", out, "--profile", "loop"},
      {"simulate", "--out", out, "--effect", "battery_exponent=1"},
      {"simulate", "--out", out, "--profile", "circle", "--circle-radius", "1", "--circle-speed", "5"},
      {"simulate", "--out", out, "--external-force", "10,0,0"},  // above 0.3 m g of A's 1.285 kg
      {"simulate", "--out", out, "--external-force", "1,0"},
      {"simulate", "--out", out, "--external-force", "1,0,0", "--external-force-period", "-1"},
  };
  for (const auto& args : bad) {
    std::string joined;
    for (const auto& a : args) joined += a + " ";
    const auto result = RunRotorid(args);
    EXPECT_NE(result.exit_code, 0) << joined;
    EXPECT_EQ(result.err.find("rotorid: error: "), 0u) << joined << "\n" << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << joined << "\n" << result.err;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rotorid

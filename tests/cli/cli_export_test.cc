// rotorid vehicle and rotorid export end to end: vehicle files from a PX4 log's CA_ROTOR*
// parameters, the Crazyflie layout and a column map; exports parsed back (the SDF with python3's
// XML parser, the YAML with yaml-cpp, the SIH lines as text) and compared with the report.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "rotorid/io/vehicle_yaml.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::RunRotorid;
using testing::Slurp;

// Every leaf element of the SDF as "path/to/element" -> text, read with python3's xml.etree.
std::optional<nlohmann::json> ParseSdf(const std::string& path) {
  const std::string script =
      "import json,sys,xml.etree.ElementTree as E\n"
      "root=E.parse(sys.argv[1]).getroot()\n"
      "out={}\n"
      "def walk(e,p):\n"
      "  kids=list(e)\n"
      "  name=p+'/'+e.tag+('['+e.get('name')+']' if e.get('name') else '')\n"
      "  if not kids: out[name]=(e.text or '')\n"
      "  for k in kids: walk(k,name)\n"
      "walk(root,'')\n"
      "print(json.dumps(out))\n";
  std::ofstream(path + ".py") << script;
  FILE* pipe = ::popen(("python3 " + path + ".py " + path + " 2>&1").c_str(), "r");
  if (!pipe) return std::nullopt;
  std::string text;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof(buffer), pipe)) text.append(buffer, n);
  if (::pclose(pipe) != 0) return std::nullopt;
  return nlohmann::json::parse(text);
}

double Number(const nlohmann::json& sdf, const std::string& key) { return std::stod(sdf.at(key).get<std::string>()); }

TEST(CliExportTest, ExportsRoundTrip) {
  const std::string dir = MakeTempDir("rotorid-export");
  const auto sim =
      RunRotorid({"simulate", "--preset", "B", "--seconds", "20", "--seed", "3", "--effect", "motor_tau_s=0.02",
                  "--out", dir + "/f.csv", "--vehicle-out", dir + "/B.yaml", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto refine = RunRotorid({"refine", "--vehicle", dir + "/B.yaml", "--log", dir + "/f.csv", "--effects",
                                  "motor_lag", "--json", dir + "/r.json", "-q"});
  ASSERT_EQ(refine.exit_code, 0) << refine.err;
  const nlohmann::json report = nlohmann::json::parse(Slurp(dir + "/r.json"));
  const nlohmann::json& p = report["refined"]["parameters"];
  const auto value = [&](const std::string& name) { return p[name]["value"].get<double>(); };
  const double kt = value("kt"), kd = value("kd"), tau = report["refined"]["effects"]["motor_tau_s"]["value"];
  const Vehicle vehicle = ReadVehicleYaml(dir + "/B.yaml");
  const double m = vehicle.mass_kg;
  const auto run = [&](const std::string& format, const std::string& out, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"export",   "--params", dir + "/r.json",     "--vehicle", dir + "/B.yaml",
                                     "--format", format,     "--max-rotor-speed", "1200",      "--out",
                                     out,        "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunRotorid(args);
  };
  for (const char* format : {"gz", "gazebo-classic", "gazebo", "px4", "ardupilot", "yaml"}) {
    const auto r = run(format, dir + "/model." + format);
    ASSERT_EQ(r.exit_code, 0) << format << ": " << r.err;
  }
  // B is a plus quad: SIH flies X layouts only, and says so.
  const auto sih = run("px4-sih", dir + "/model.sih");
  EXPECT_EQ(sih.exit_code, 1);
  EXPECT_NE(sih.err.find("plus layout"), std::string::npos) << sih.err;

  // The gz model directory, read by a strict XML parser: the links add up to the identified body.
  for (const char* format : {"gz", "gazebo-classic"}) {
    const auto sdf = ParseSdf(dir + "/model." + format + "/model.sdf");
    if (!sdf) GTEST_SKIP() << "python3 cannot parse the SDF (python3 missing?)";
    EXPECT_TRUE(ParseSdf(dir + "/model." + format + "/model.config")) << "model.config is no XML";
    double mass = 0.0;
    for (const std::string link : {"base_link", "rotor_0", "rotor_1", "rotor_2", "rotor_3"})
      mass += Number(*sdf, "/sdf/model[B]/link[" + link + "]/inertial/mass");
    EXPECT_NEAR(mass, m, 1e-12);
    const std::string plugin =
        std::string("/sdf/model[B]/plugin[") +
        (std::string(format) == "gz" ? "gz::sim::systems::MulticopterMotorModel" : "rotor_3_motor_model") + "]/";
    EXPECT_NEAR(Number(*sdf, plugin + "motorConstant"), kt, 1e-12 * kt);
    EXPECT_NEAR(Number(*sdf, plugin + "momentConstant"), kd / kt, 1e-12 * kd / kt);
    EXPECT_NEAR(Number(*sdf, plugin + "timeConstantUp"), tau, 1e-12 * tau);
    EXPECT_DOUBLE_EQ(Number(*sdf, plugin + "maxRotVelocity"), 1200.0);
  }
  EXPECT_EQ(Slurp(dir + "/model.gazebo/model.sdf"), Slurp(dir + "/model.gazebo-classic/model.sdf"));

  const nlohmann::json frame = nlohmann::json::parse(Slurp(dir + "/model.ardupilot"));
  // Every key ArduPilot SITL's frame loader (SIM_Frame.cpp, load_frame_params) reads for a multicopter.
  for (const char* key : {"mass",       "diagonal_size", "refSpd",     "refAngle",       "refVoltage", "refCurrent",
                          "refAlt",     "refTempC",      "maxVoltage", "battCapacityAh", "refBatRes",  "propExpo",
                          "refRotRate", "hoverThrOut",   "pwmMin",     "pwmMax",         "spin_min",   "spin_max",
                          "slew_max",   "disc_area",     "mdrag_coef", "moment_inertia", "num_motors"})
    EXPECT_TRUE(frame.contains(key)) << key;
  for (int k = 1; k <= 4; ++k)
    for (const char* key : {"_position", "_vector", "_yaw"})
      EXPECT_TRUE(frame.contains("motor" + std::to_string(k) + key)) << k << key;
  EXPECT_DOUBLE_EQ(frame["mass"].get<double>(), m);
  EXPECT_NEAR(frame["hoverThrOut"].get<double>(), m * 9.80665 / (4 * kt * 1200 * 1200), 1e-12);

  const YAML::Node yaml = YAML::LoadFile(dir + "/model.yaml");
  for (const auto& [name, entry] : p.items()) {
    EXPECT_NEAR(yaml["parameters"][name]["value"].as<double>(), entry["value"].get<double>(),
                1e-10 * std::abs(entry["value"].get<double>()) + 1e-15)
        << name;
    EXPECT_NEAR(yaml["parameters"][name]["std"].as<double>(), entry["std"].get<double>(),
                1e-10 * std::abs(entry["std"].get<double>()) + 1e-15)
        << name;
  }
  EXPECT_NEAR(yaml["effects"]["motor_tau_s"]["value"].as<double>(), tau, 1e-10 * tau);
  EXPECT_FALSE(yaml["effects"]["delay_s"]) << "an effect not estimated is not exported";
  EXPECT_NE(Slurp(dir + "/model.px4").find("param set SIM_GZ_EC_MAX4 1200\n"), std::string::npos);

  // Without the rotor speed at full command (and no command_to_speed map): exit 1 saying how to give it.
  const auto no_speed = RunRotorid(
      {"export", "--params", dir + "/r.json", "--vehicle", dir + "/B.yaml", "--format", "gz", "--out", dir + "/x"});
  EXPECT_EQ(no_speed.exit_code, 1);
  EXPECT_NE(no_speed.err.find("--max-rotor-speed"), std::string::npos) << no_speed.err;
  const auto huge = RunRotorid({"export", "--params", dir + "/r.json", "--vehicle", dir + "/B.yaml", "--format", "px4",
                                "--max-rotor-speed", "1e200", "--out", dir + "/x.px4"});
  EXPECT_EQ(huge.exit_code, 1);
  EXPECT_NE(huge.err.find("not a finite number"), std::string::npos) << huge.err;
  EXPECT_EQ(run("urdf", dir + "/x").exit_code, 2);
  EXPECT_EQ(run("gz", dir + "/x", {"--set", "kd"}).exit_code, 2);

  // A report that failed a check: refused naming it, or with --force written into the header.
  nlohmann::json failed = report;
  failed["checks"].push_back({{"name", "gravity_magnitude"}, {"status", "error"}, {"message", "12.3 m/s^2 in hover"}});
  std::ofstream(dir + "/failed.json") << failed.dump();
  const auto refused = RunRotorid({"export", "--params", dir + "/failed.json", "--vehicle", dir + "/B.yaml", "--format",
                                   "px4", "--max-rotor-speed", "1200", "--out", dir + "/f.px4"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("gravity_magnitude"), std::string::npos) << refused.err;
  const auto forced = RunRotorid({"export", "--params", dir + "/failed.json", "--vehicle", dir + "/B.yaml", "--format",
                                  "px4", "--max-rotor-speed", "1200", "--out", dir + "/f.px4", "--force"});
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_NE(Slurp(dir + "/f.px4").find("# FAILED CHECK (exported anyway: forced): gravity_magnitude"),
            std::string::npos);
}

// The bundled identify report of B (data/sim) discards kd and I_zz: the export names them, the
// flight that fixes them and --set; given both, every format B can fly is written.
TEST(CliExportTest, IdentifyReportWithDiscardedParameters) {
  const std::string dir = MakeTempDir("rotorid-export-id");
  const std::string vehicle = testing::SourceDir() + "/data/sim/B.yaml";
  const auto id = RunRotorid({"identify", "--vehicle", vehicle, "--log", testing::SourceDir() + "/data/sim/B_train.csv",
                              "--json", dir + "/id.json", "-q"});
  ASSERT_EQ(id.exit_code, 0) << id.err;
  const nlohmann::json p = nlohmann::json::parse(Slurp(dir + "/id.json"))["linear"]["parameters"];
  ASSERT_FALSE(p["kd"]["essential"].get<bool>());
  ASSERT_FALSE(p["B.I_zz"]["essential"].get<bool>());
  const auto run = [&](const std::string& format, std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "export", "--params", dir + "/id.json",      "--vehicle", vehicle, "--format", format, "--max-rotor-speed",
        "1200",   "--out",    dir + "/out." + format};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunRotorid(args);
  };
  const auto no_kd = run("gz", {});
  EXPECT_EQ(no_kd.exit_code, 1);
  EXPECT_NE(no_kd.err.find("does not fix kd"), std::string::npos) << no_kd.err;
  EXPECT_NE(no_kd.err.find("second configuration"), std::string::npos) << no_kd.err;
  // I_zz's estimate is too small for any body with B's I_xx and I_yy: the report predicts with a value
  // inside the range a body allows, which no flight picked, so the export names it and the range.
  const auto bad_izz = run("gz", {"--set", "kd=5.1e-8"});
  EXPECT_EQ(bad_izz.exit_code, 1);
  EXPECT_NE(bad_izz.err.find("does not fix B.I_zz"), std::string::npos) << bad_izz.err;
  EXPECT_NE(bad_izz.err.find("a physically possible body allows"), std::string::npos) << bad_izz.err;
  for (const char* format : {"gz", "gazebo-classic", "px4", "ardupilot", "yaml"}) {
    const auto r = run(format, {"--set", "kd=5.1e-8", "--set", "I_zz=0.05"});
    EXPECT_EQ(r.exit_code, 0) << format << ": " << r.err;
  }
  EXPECT_NE(Slurp(dir + "/out.yaml").find("# value: B.I_zz = 0.05: given by the user"), std::string::npos);
  // The model directory of gz is written again in place (a user re-exporting after a new flight).
  const std::string before = Slurp(dir + "/out.gz/model.sdf");
  ASSERT_FALSE(before.empty());
  const auto again = run("gz", {"--set", "kd=5.1e-8", "--set", "I_zz=0.052"});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(Slurp(dir + "/out.gz/model.sdf"), before);
}

// Real flights (skipped without ../shared/data/real): a Crazyflie identify report discards kd (refused
// by name; with a thrust-stand kd every format is written, the X layout in SIH's and ArduPilot's motor
// order); the TU Delft throw fails its relative-error check (refused until --force).
TEST(CliExportTest, RealCrazyflieAndTuDelftFlights) {
  const auto cf = testing::SharedDataPath("real/crazyflie-imrc-rpm/brushed/raw/jana01");
  const auto td = testing::SharedDataPath("real/indiflight-tudelft-throw/raw/LOG00271.BFL");
  if (!cf || !td) GTEST_SKIP() << "no real flights under ../shared/data/real";
  const std::string dir = MakeTempDir("rotorid-export-real");
  const std::string cf_vehicle = testing::SourceDir() + "/data/vehicles/crazyflie21_brushed.yaml";
  const std::string td_vehicle = testing::SourceDir() + "/data/vehicles/tudelft_indiflight_3inch.yaml";
  ASSERT_EQ(RunRotorid({"identify", "--vehicle", cf_vehicle, "--log", *cf, "--allow-partial", "--json",
                        dir + "/cf.json", "-q"})
                .exit_code,
            0);
  const auto no_kd = RunRotorid({"export", "--params", dir + "/cf.json", "--vehicle", cf_vehicle, "--format", "px4-sih",
                                 "--out", dir + "/cf.sih"});
  EXPECT_EQ(no_kd.exit_code, 1);
  EXPECT_NE(no_kd.err.find("does not fix kd"), std::string::npos) << no_kd.err;
  for (const char* format : {"gz", "gazebo-classic", "px4", "px4-sih", "ardupilot", "yaml"}) {
    const auto r = RunRotorid({"export", "--params", dir + "/cf.json", "--vehicle", cf_vehicle, "--format", format,
                               "--out", dir + "/cf." + format, "--set", "kd=1.2e-10", "-q"});
    EXPECT_EQ(r.exit_code, 0) << format << ": " << r.err;
  }
  EXPECT_NE(Slurp(dir + "/cf.px4-sih").find("SIH motor 1 = rotor 3, SIH motor 2 = rotor 4, SIH motor 3 = rotor 2"),
            std::string::npos);

  const auto id = RunRotorid({"identify", "--vehicle", td_vehicle, "--log", *td, "--cutoff-hz", "30",
                              "--all-parameters", "--allow-partial", "--json", dir + "/td.json", "-q"});
  ASSERT_TRUE(id.exit_code == 0 || id.exit_code == 3) << id.err;
  const bool failed = id.exit_code == 3;
  const std::vector<std::string> args = {"export",   "--params", dir + "/td.json", "--vehicle",
                                         td_vehicle, "--format", "px4-sih",        "--max-rotor-speed",
                                         "5000",     "--out",    dir + "/td.sih"};
  EXPECT_EQ(RunRotorid(args).exit_code, failed ? 1 : 0);
  std::vector<std::string> forced = args;
  forced.push_back("--force");
  EXPECT_EQ(RunRotorid(forced).exit_code, 0);
  EXPECT_EQ(Slurp(dir + "/td.sih").find("FAILED CHECK") != std::string::npos, failed);
}

TEST(CliExportTest, HelpListsEveryFormatAsAChoice) {
  const auto help = RunRotorid({"export", "--help"});
  ASSERT_EQ(help.exit_code, 0);
  const size_t open = help.out.find("{gz,"), close = help.out.find('}', open);
  ASSERT_NE(open, std::string::npos) << help.out;
  const std::string choices = help.out.substr(open, close - open + 1);
  for (const char* format : {"gz", "gazebo-classic", "px4", "px4-sih", "ardupilot", "yaml"})
    EXPECT_NE(choices.find(std::string(format) + ","), std::string::npos) << choices;
}

TEST(CliVehicleTest, FromPx4CrazyflieAndColumnMap) {
  const std::string dir = MakeTempDir("rotorid-vehicle");
  if (const auto ulog = testing::SharedDataPath("real/px4-flightreview-rs-lowrate/raw/ekf_failure.ulg")) {
    const auto r = RunRotorid({"vehicle", "--log", *ulog, "--mass", "2.1", "--out", dir + "/px4.yaml"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Vehicle v = ReadVehicleYaml(dir + "/px4.yaml");
    ASSERT_EQ(v.num_rotors(), 4);
    EXPECT_DOUBLE_EQ(v.mass_kg, 2.1);
    // SOURCE.md: CA_ROTOR*_PX/PY = +-0.11 m, KM = 0.05 (all positive in the log's first two).
    for (const Rotor& rotor : v.rotors) {
      EXPECT_NEAR(std::abs(rotor.position_m.x()), 0.11, 1e-6);
      EXPECT_NEAR(std::abs(rotor.position_m.y()), 0.11, 1e-6);
    }
  }
  if (const auto cf = testing::SharedDataPath("real/crazyflie-arpl-sysid/raw/log15")) {
    const auto r = RunRotorid({"vehicle", "--log", *cf, "--mass", "0.027", "--name", "cf", "--out", dir + "/cf.yaml"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Vehicle v = ReadVehicleYaml(dir + "/cf.yaml");
    EXPECT_EQ(v.name, "cf");
    ASSERT_EQ(v.num_rotors(), 4);
    EXPECT_NEAR(v.rotors[0].position_m.x(), 0.0325, 1e-12);  // M1 front-right, CCW
    EXPECT_NEAR(v.rotors[0].position_m.y(), -0.0325, 1e-12);
    EXPECT_EQ(v.rotors[0].spin, 1);
    EXPECT_EQ(v.rotors[1].spin, -1);
  }
  // A column map carrying the layout in its metadata.
  std::ofstream(dir + "/log.csv") << "time,gx,gy,gz,ax,ay,az,m1,m2,m3\n0,0,0,0,0,0,9.8,1,1,1\n";
  std::ofstream(dir + "/map.yaml")
      << "time: {column: time, unit: s}\n"
      << "gyro: {columns: [gx, gy, gz], unit: rad/s}\n"
      << "acc: {columns: [ax, ay, az], unit: m/s^2}\n"
      << "rotors: {columns: [m1, m2, m3], unit: rad/s}\n"
      << "metadata: {rotor_positions: \"[[0.2, 0, 0], [-0.1, 0.17, 0], [-0.1, -0.17, 0]]\", "
      << "rotor_spins: \"[1, -1, 1]\"}\n";
  const auto mapped = RunRotorid({"vehicle", "--log", dir + "/log.csv", "--column-map", dir + "/map.yaml", "--mass",
                                  "1.5", "--out", dir + "/tri.yaml"});
  ASSERT_EQ(mapped.exit_code, 0) << mapped.err;
  const Vehicle tri = ReadVehicleYaml(dir + "/tri.yaml");
  ASSERT_EQ(tri.num_rotors(), 3);
  EXPECT_DOUBLE_EQ(tri.rotors[1].position_m.y(), 0.17);
  EXPECT_EQ(tri.rotors[1].spin, -1);
  const auto plain = RunRotorid({"vehicle", "--log", dir + "/log.csv", "--mass", "1.5", "--out", dir + "/x.yaml"});
  EXPECT_EQ(plain.exit_code, 1);
  EXPECT_NE(plain.err.find("log.csv"), std::string::npos) << plain.err;
  EXPECT_EQ(RunRotorid({"vehicle", "--log", dir + "/log.csv", "--mass", "-1", "--out", dir + "/x.yaml"}).exit_code, 2);
}

TEST(CliVehicleTest, FromBlackboxHeaderWithTheArmLength) {
  const auto log = testing::SharedDataPath("real/betaflight-fcblackbox-gecko/raw/btfl_002.bbl");
  if (!log) GTEST_SKIP() << "no Betaflight log under ../shared/data/real";
  const std::string dir = MakeTempDir("rotorid-vehicle-bbl");
  // The header says Quad-X with 4 motors but not the geometry: the command asks for it.
  const auto no_arm = RunRotorid({"vehicle", "--log", *log, "--mass", "0.6", "--out", dir + "/q.yaml"});
  EXPECT_EQ(no_arm.exit_code, 1);
  EXPECT_NE(no_arm.err.find("arm"), std::string::npos) << no_arm.err;
  const auto r =
      RunRotorid({"vehicle", "--log", *log, "--mass", "0.6", "--arm-length", "0.1", "--out", dir + "/q.yaml"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Vehicle v = ReadVehicleYaml(dir + "/q.yaml");
  ASSERT_EQ(v.num_rotors(), 4);
  EXPECT_DOUBLE_EQ(v.mass_kg, 0.6);
  // Betaflight's motor order: rear-right, front-right, rear-left, front-left, hubs at 45 degrees.
  const double d = 0.1 / std::sqrt(2.0);
  EXPECT_NEAR(v.rotors[0].position_m.x(), -d, 1e-9);
  EXPECT_NEAR(v.rotors[0].position_m.y(), -d, 1e-9);
  EXPECT_NEAR(v.rotors[3].position_m.x(), d, 1e-9);
  EXPECT_NEAR(v.rotors[3].position_m.y(), d, 1e-9);
  EXPECT_EQ(v.rotors[0].spin, -v.rotors[1].spin);
  EXPECT_EQ(v.rotors[0].spin, v.rotors[3].spin);
}

}  // namespace
}  // namespace rotorid

// rotorid vehicle and rotorid export end to end: vehicle files from a PX4 log's CA_ROTOR*
// parameters, the Crazyflie layout and a column map; exports parsed back (the SDF with python3's
// XML parser, the YAML with yaml-cpp, the SIH lines as text) and compared with the report.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <cmath>
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
  // Inertia about the centre of mass, computed here independently: I_c = I_O - m (|c|^2 E - c c^T).
  const Eigen::Vector3d c = Eigen::Vector3d(value("B.ms_x"), value("B.ms_y"), value("B.ms_z")) / m;
  const double ixx_c = value("B.I_xx") - m * (c.y() * c.y() + c.z() * c.z());
  const double ixy_c = value("B.I_xy") + m * c.x() * c.y();
  const double izz_c = value("B.I_zz") - m * (c.x() * c.x() + c.y() * c.y());

  for (const char* format : {"gazebo", "px4-sih", "yaml"}) {
    const auto r = RunRotorid({"export", "--params", dir + "/r.json", "--vehicle", dir + "/B.yaml", "--format", format,
                               "--max-rotor-speed", "900", "--out", dir + "/model." + format});
    ASSERT_EQ(r.exit_code, 0) << format << ": " << r.err;
  }
  const auto sdf = ParseSdf(dir + "/model.gazebo");
  if (!sdf) GTEST_SKIP() << "python3 cannot parse the SDF (python3 missing?)";
  const std::string link = "/sdf/model[B]/link[base_link]/inertial";
  EXPECT_DOUBLE_EQ(Number(*sdf, link + "/mass"), m);
  EXPECT_NEAR(Number(*sdf, link + "/inertia/ixx"), ixx_c, 1e-8 * std::abs(ixx_c) + 1e-12);
  EXPECT_NEAR(Number(*sdf, link + "/inertia/ixy"), ixy_c, 1e-8 * std::abs(ixy_c) + 1e-12);
  EXPECT_NEAR(Number(*sdf, link + "/inertia/izz"), izz_c, 1e-8 * std::abs(izz_c) + 1e-12);
  std::istringstream pose(sdf->at(link + "/pose").get<std::string>());
  double px = 0, py = 0, pz = 0;
  pose >> px >> py >> pz;
  EXPECT_NEAR(px, c.x(), 1e-8);
  EXPECT_NEAR(pz, c.z(), 1e-8);
  for (int i = 0; i < vehicle.num_rotors(); ++i) {
    const std::string plugin = "/sdf/model[B]/plugin[rotor_" + std::to_string(i) + "_motor_model]/";
    EXPECT_NEAR(Number(*sdf, plugin + "motorConstant"), kt, 1e-8 * kt);
    EXPECT_NEAR(Number(*sdf, plugin + "momentConstant"), kd / kt, 1e-8 * kd / kt);
    EXPECT_NEAR(Number(*sdf, plugin + "timeConstantUp"), tau, 1e-8 * tau);
    EXPECT_DOUBLE_EQ(Number(*sdf, plugin + "maxRotVelocity"), 900.0);
    EXPECT_EQ(sdf->at(plugin + "turningDirection"), vehicle.rotors[static_cast<size_t>(i)].spin > 0 ? "ccw" : "cw");
    EXPECT_EQ(sdf->count(plugin + "rotorDragCoefficient"), 0u) << "not identified, so not written";
  }

  std::map<std::string, double> sih;
  std::istringstream lines(Slurp(dir + "/model.px4-sih"));
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string param, set, name;
    double x = 0;
    if (words >> param >> set >> name >> x && param == "param") sih[name] = x;
  }
  EXPECT_NEAR(sih.at("SIH_T_MAX"), kt * 900 * 900, 1e-6 * kt * 900 * 900);
  EXPECT_NEAR(sih.at("SIH_Q_MAX"), kd * 900 * 900, 1e-6 * kd * 900 * 900);
  EXPECT_NEAR(sih.at("SIH_IXX"), ixx_c, 1e-8 * std::abs(ixx_c) + 1e-12);
  EXPECT_NEAR(sih.at("SIH_IXY"), -ixy_c, 1e-8 * std::abs(ixy_c) + 1e-12);  // FRD
  EXPECT_NEAR(sih.at("SIH_T_TAU"), tau, 1e-8 * tau);
  EXPECT_DOUBLE_EQ(sih.at("SIH_MASS"), m);

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

  // SIH needs the rotor speed at full command: without it (and without a command_to_speed map), exit 1.
  const auto no_speed = RunRotorid({"export", "--params", dir + "/r.json", "--vehicle", dir + "/B.yaml", "--format",
                                    "px4-sih", "--out", dir + "/x.sih"});
  EXPECT_EQ(no_speed.exit_code, 1);
  EXPECT_NE(no_speed.err.find("--max-rotor-speed"), std::string::npos) << no_speed.err;
  EXPECT_EQ(RunRotorid({"export", "--params", dir + "/r.json", "--vehicle", dir + "/B.yaml", "--format", "urdf",
                        "--out", dir + "/x"})
                .exit_code,
            2);
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
  const auto r = RunRotorid({"vehicle", "--log", *log, "--mass", "0.6", "--arm-length", "0.1", "--out", dir + "/q.yaml"});
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

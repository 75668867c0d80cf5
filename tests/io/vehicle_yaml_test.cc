#include "rotorid/io/vehicle_yaml.h"

#include <gtest/gtest.h>

#include "rotorid/core/error.h"
#include "rotorid/io/flight_source.h"

namespace rotorid {
namespace {

constexpr const char* kQuad = R"(name: cf
mass: 0.0347
rotors:
  - {position: [ 0.0325, -0.0325, 0.0], spin: +1}
  - {position: [-0.0325, -0.0325, 0.0], spin: -1}
  - {position: [-0.0325,  0.0325, 0.0], spin: +1}
  - {position: [ 0.0325,  0.0325, 0.0], spin: -1}
)";

std::string ErrorOf(const std::string& text) {
  try {
    ParseVehicleYaml(text, "v.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(VehicleYaml, ReadsNameMassRotorsAndRoundTrips) {
  const Vehicle v = ParseVehicleYaml(kQuad, "v.yaml");
  EXPECT_EQ(v.name, "cf");
  EXPECT_DOUBLE_EQ(v.mass_kg, 0.0347);
  ASSERT_EQ(v.num_rotors(), 4);
  EXPECT_DOUBLE_EQ(v.rotors[1].position_m.x(), -0.0325);
  EXPECT_EQ(v.rotors[1].spin, -1);
  EXPECT_FALSE(v.command_to_speed);
  const Vehicle again = ParseVehicleYaml(VehicleToYaml(v), "again.yaml");
  EXPECT_EQ(again.name, v.name);
  EXPECT_EQ(again.rotors[3].position_m, v.rotors[3].position_m);
  EXPECT_FALSE(again.command_to_speed);
}

TEST(VehicleYaml, CommandToSpeedMapIsReadWrittenAndApplied) {
  const Vehicle v = ParseVehicleYaml(std::string(kQuad) + "command_to_speed: [297.9, 2733.8, -593.4]\n", "v.yaml");
  ASSERT_TRUE(v.command_to_speed);
  EXPECT_DOUBLE_EQ(v.command_to_speed->coefficients[1], 2733.8);
  EXPECT_DOUBLE_EQ((*v.command_to_speed)(0.5), 297.9 + 0.5 * 2733.8 - 0.25 * 593.4);
  const Vehicle again = ParseVehicleYaml(VehicleToYaml(v), "again.yaml");
  ASSERT_TRUE(again.command_to_speed);
  EXPECT_EQ(again.command_to_speed->coefficients, v.command_to_speed->coefficients);

  FlightLog log;
  log.rotor_radps = Eigen::MatrixXd::Constant(3, 4, 0.5);
  log.rotor_radps(0, 0) = -1.0;  // below the map's zero: clamped, never a negative speed
  EXPECT_FALSE(RotorSignalIsCommand(log));
  log.metadata["rotor_signal"] = "command";
  EXPECT_TRUE(RotorSignalIsCommand(log));
  ApplyCommandToSpeed(*v.command_to_speed, &log);
  EXPECT_DOUBLE_EQ(log.rotor_radps(1, 2), (*v.command_to_speed)(0.5));
  EXPECT_EQ(log.rotor_radps(0, 0), 0.0);
  EXPECT_FALSE(RotorSignalIsCommand(log));
  EXPECT_NE(log.metadata["command_to_speed"].find("vehicle file"), std::string::npos);
}

TEST(VehicleYaml, ErrorsNameTheLineAndColumn) {
  EXPECT_NE(ErrorOf(std::string(kQuad) + "command_to_speed: [1, 2]\n").find("v.yaml:8:19: command_to_speed must be"),
            std::string::npos)
      << ErrorOf(std::string(kQuad) + "command_to_speed: [1, 2]\n");
  EXPECT_NE(ErrorOf(std::string(kQuad) + "command_to_speed: [1, x, 3]\n").find("must be a finite number, got 'x'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(std::string(kQuad) + "command_to_speed: [100, 0, 0]\n").find("must depend on the command"),
            std::string::npos);
  EXPECT_NE(ErrorOf("name: x\nmass: -1\nrotors: []\n").find("v.yaml:2:7: mass must be positive"), std::string::npos);
  EXPECT_NE(ErrorOf("name: x\nmass: [1\n").find("not valid YAML"), std::string::npos);
  EXPECT_NE(ErrorOf("name: x\nrotors: []\n").find("missing 'mass'"), std::string::npos);
}

// The YAML loader every reader shares (issue 42): aliases within twice the document's size pass,
// a bomb, deep nesting, a second document and inputs that hung yaml-cpp's LoadAll
// (",e,", found by fuzz/yaml_fuzzer) are errors naming the file; a written name reads back.
TEST(VehicleYaml, LoaderBoundsAliasesNestingAndDocuments) {
  const std::string reused = std::string(kQuad) + "imu_position: &p [0, 0, 0]\nsimulation: {kt: 1e-8, ms: *p}\n";
  EXPECT_EQ(ErrorOf(reused), "");
  std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 7; ++i) {
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) bomb += (k ? ", *a" : "*a") + std::to_string(i - 1);
    bomb += "]\n";
  }
  EXPECT_NE(ErrorOf(bomb).find("v.yaml:"), std::string::npos);
  EXPECT_NE(ErrorOf(bomb).find("aliases (*name) expand this document beyond"), std::string::npos) << ErrorOf(bomb);
  const std::string chain = "name: " + std::string(300, '[') + std::string(300, ']') + "\n";
  EXPECT_NE(ErrorOf(chain).find("nested deeper than 200 levels"), std::string::npos) << ErrorOf(chain);
  EXPECT_NE(ErrorOf(std::string(kQuad) + "---\nmass: 1\n").find("v.yaml:8:1: a second YAML document"),
            std::string::npos);
  EXPECT_NE(ErrorOf(std::string(kQuad) + "...\nmass: 1\n").find("a second YAML document"), std::string::npos);
  EXPECT_EQ(ErrorOf("---\n" + std::string(kQuad) + "...\n"), "");
  EXPECT_NE(ErrorOf(",e,").find("v.yaml"), std::string::npos);
  EXPECT_NE(ErrorOf(std::string(kQuad) + "rotor_raduis: 0.02\n").find("unknown key 'rotor_raduis'"), std::string::npos);
  Vehicle named = ParseVehicleYaml(kQuad, "v.yaml");
  named.name = "A: #1 \"x\"";
  EXPECT_EQ(ParseVehicleYaml(VehicleToYaml(named), "w.yaml").name, named.name);
}

}  // namespace
}  // namespace rotorid

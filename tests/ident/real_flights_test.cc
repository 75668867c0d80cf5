// Identification on the real Crazyflie flights of ../shared/data/real/crazyflie-imrc-rpm (measured
// rotor speed from the RPM deck). The references are the thrust stands and the flight check of its
// SOURCE.md; skipped when the shared data is absent.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "rotorid/ident/identify.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/io/vehicle_yaml.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

IdentificationResult IdentifyImrc(const std::string& kind, const std::vector<std::string>& names,
                                  const std::string& rotor_signal = "auto") {
  const std::string root = *testing::SharedDataPath("real/crazyflie-imrc-rpm");
  const Vehicle vehicle = ReadVehicleYaml(testing::SourceDir() + "/data/vehicles/crazyflie21_" + kind + ".yaml");
  FlightSourceOptions source;
  source.rotor_signal = rotor_signal;
  std::vector<FlightData> flights;
  for (const std::string& name : names)
    flights.push_back({vehicle, LoadFlightLog(root + "/" + kind + "/raw/" + name, vehicle, source), 1.0});
  IdentifyOptions options;
  options.allow_partial = true;
  return Identify(flights, options);
}

double Parameter(const IdentificationResult& r, const std::string& name) {
  const auto& names = r.system.parameter_names;
  const auto it = std::find(names.begin(), names.end(), name);
  EXPECT_NE(it, names.end()) << name;
  return it == names.end() ? 0.0 : r.solution.chi[it - names.begin()];
}

// Brushed Crazyflie 2.1 (34.7 g): kt within 10 % of the thrust stand's 2.02e-8 N s^2 on each long
// flight; roll and pitch inertia near the literature's 1.43e-5 kg m^2 (within 25 %: another frame
// with other decks).
TEST(RealFlightIdentification, BrushedCrazyflieMatchesTheThrustStand) {
  if (!testing::SharedDataPath("real/crazyflie-imrc-rpm")) GTEST_SKIP() << "shared IMRC Crazyflie data not present";
  for (const std::string name : {"jana01", "jana04"}) {
    SCOPED_TRACE(name);
    const IdentificationResult r = IdentifyImrc("brushed", {name});
    EXPECT_NEAR(Parameter(r, "kt"), 2.02e-8, 0.1 * 2.02e-8);
    EXPECT_NEAR(r.solution.std[0] / r.solution.chi[0], 0.0, 0.01);
  }
  const IdentificationResult roll_pitch = IdentifyImrc("brushed", {"jana01"});
  EXPECT_NEAR(Parameter(roll_pitch, "cf21_brushed.I_xx"), 1.43e-5, 0.25 * 1.43e-5);
  EXPECT_NEAR(Parameter(roll_pitch, "cf21_brushed.I_yy"), 1.43e-5, 0.25 * 1.43e-5);
}

// Without the RPM deck: the PWM command through the vehicle file's command_to_speed map (fitted on
// the Bitcraze thrust stand) still gives kt within 10 % of the stand's value.
TEST(RealFlightIdentification, BrushedCrazyflieFromPwmThroughTheCommandMap) {
  if (!testing::SharedDataPath("real/crazyflie-imrc-rpm")) GTEST_SKIP() << "shared IMRC Crazyflie data not present";
  for (const std::string name : {"jana01", "jana04"}) {
    SCOPED_TRACE(name);
    const IdentificationResult r = IdentifyImrc("brushed", {name}, "command");
    EXPECT_NEAR(Parameter(r, "kt"), 2.02e-8, 0.1 * 2.02e-8);
  }
}

// Brushless (37 g): kt within 10 % of its thrust stand's 3.86e-8 N s^2, on each short flight and on
// the three together. These weakly excited yaw axes once drove the noise-aware weights into a
// collapse (kd, I_zz -> 0 and the yaw group's weight without bound).
TEST(RealFlightIdentification, BrushlessCrazyflieMatchesTheThrustStand) {
  if (!testing::SharedDataPath("real/crazyflie-imrc-rpm")) GTEST_SKIP() << "shared IMRC Crazyflie data not present";
  for (const std::vector<std::string>& names : std::vector<std::vector<std::string>>{
           {"eckart00"}, {"eckart17"}, {"eckart34"}, {"eckart00", "eckart17", "eckart34"}}) {
    SCOPED_TRACE(names.size() == 1 ? names[0] : "all three");
    const IdentificationResult r = IdentifyImrc("brushless", names);
    EXPECT_NEAR(Parameter(r, "kt"), 3.86e-8, 0.1 * 3.86e-8);
    // Roll and pitch inertia are determined and physically plausible.
    const double ixx = Parameter(r, "cf21_brushless.I_xx"), iyy = Parameter(r, "cf21_brushless.I_yy");
    EXPECT_GT(ixx, 0.5e-5);
    EXPECT_LT(ixx, 4e-5);
    EXPECT_GT(iyy, 0.5e-5);
    EXPECT_LT(iyy, 4e-5);
  }
}

}  // namespace
}  // namespace rotorid

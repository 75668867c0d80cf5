// The exported gz-sim and Gazebo Classic models loaded by libsdformat (Debian libsdformat-dev, found
// by tests/CMakeLists.txt): no errors, one link and joint per rotor, and the links' masses add up to
// the identified mass. Skips when libsdformat was not found at configure time.

#include <gtest/gtest.h>

#include <fstream>

#include "report/export_cases.h"
#include "rotorid/report/export.h"
#include "support/test_support.h"

#ifdef ROTORID_HAVE_SDFORMAT
#include <sdf/sdf.hh>
#endif

namespace rotorid {
namespace {

TEST(ExportSdformatTest, GzAndClassicModelsLoadWithoutErrors) {
#ifndef ROTORID_HAVE_SDFORMAT
  GTEST_SKIP() << "libsdformat was not found when configuring (Debian: libsdformat-dev)";
#else
  const std::string dir = testing::MakeTempDir("rotorid-export-sdf");
  for (testing::Case c : testing::Cases()) {
    c.vehicle.name += "<&\"'>";  // escaped in the model name
    const IdentifiedModel identified = IdentifiedModelFromReport(testing::Report(c, true), "r--x.json", c.vehicle);
    ExportOptions options;
    if (c.max_rotor_speed_radps > 0.0) options.set["max_rotor_speed"] = c.max_rotor_speed_radps;
    const ExportModel model = ResolveExportModel(identified, options);
    for (const ExportFormat format : {ExportFormat::kGz, ExportFormat::kGazeboClassic}) {
      const std::string path = dir + "/" + ExportFormatName(format) + ".sdf";
      std::ofstream(path) << ExportFiles(model, format).front().text;
      sdf::Root root;
      const sdf::Errors errors = root.Load(path);
      for (const sdf::Error& e : errors) ADD_FAILURE() << path << ": " << e.Message();
      const sdf::Model* loaded = root.Model();
      ASSERT_NE(loaded, nullptr) << path;
      EXPECT_EQ(loaded->Name(), c.vehicle.name);
      const int n = c.vehicle.num_rotors();
      EXPECT_EQ(loaded->LinkCount(), static_cast<uint64_t>(n + 1));
      EXPECT_EQ(loaded->JointCount(), static_cast<uint64_t>(n));
      double mass = 0.0;
      for (uint64_t i = 0; i < loaded->LinkCount(); ++i) {
        const auto& inertia = loaded->LinkByIndex(i)->Inertial().MassMatrix();
        EXPECT_TRUE(inertia.IsValid()) << loaded->LinkByIndex(i)->Name() << ": not a possible body for gz-math";
        mass += inertia.Mass();
      }
      EXPECT_NEAR(mass, c.vehicle.mass_kg, 1e-12 * c.vehicle.mass_kg);
      EXPECT_EQ(loaded->JointByIndex(0)->Type(), sdf::JointType::REVOLUTE);
    }
  }
#endif
}

}  // namespace
}  // namespace rotorid

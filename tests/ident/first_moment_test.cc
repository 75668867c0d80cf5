// Per-flight first moments (IdentifyOptions::first_moment, INTERFACE.md v2 --first-moment): flights of
// one vehicle whose centre of mass moves between flights (the battery), against the simulator's truth.

#include <gtest/gtest.h>

#include <cmath>

#include "rotorid/ident/identify.h"
#include "rotorid/refine/refine.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"

namespace rotorid {
namespace {

// Centre-of-mass shifts (m) of the flights against the preset: a battery slid forward, to the left
// and back between flights. The inertia is kept (a battery of ~0.2 kg moved by 2 cm near O_d changes
// it by < 0.1 %), so that the shared parameters have one truth.
const std::vector<Eigen::Vector3d> kShifts = {{0.02, 0.0, 0.0}, {0.0, 0.02, 0.0}, {-0.015, -0.01, 0.0}};

struct ShiftedFlight {
  SimulationResult sim;
  Eigen::Vector3d first_moment;  // truth, kg m
};

ShiftedFlight SimulateShifted(const Eigen::Vector3d& shift, std::uint64_t seed, double seconds) {
  const SimulationVehicle preset = PresetVehicle("A");
  VehicleParameters truth = preset.parameters;
  truth.body.first_moment += preset.vehicle.mass_kg * shift;
  SimulationOptions options;
  options.duration_s = seconds;
  options.seed = seed;
  return {Simulate(preset.vehicle, truth, options), truth.body.first_moment};
}

class FirstMomentTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    flights_ = new std::vector<ShiftedFlight>;
    for (size_t k = 0; k < kShifts.size(); ++k) flights_->push_back(SimulateShifted(kShifts[k], 11 + k, 60.0));
  }
  static void TearDownTestSuite() {
    delete flights_;
    flights_ = nullptr;
  }
  static std::vector<FlightData> Data() {
    std::vector<FlightData> data;
    for (size_t k = 0; k < flights_->size(); ++k)
      data.push_back({(*flights_)[k].sim.vehicle, (*flights_)[k].sim.log, 1.0, static_cast<int>(k)});
    return data;
  }
  static IdentificationResult IdentifyAll(FirstMoment mode) {
    IdentifyOptions options;
    options.allow_partial = true;
    options.first_moment = mode;
    return Identify(Data(), options);
  }
  static const VehicleParameters& Truth() { return flights_->front().sim.truth; }
  static std::vector<ShiftedFlight>* flights_;
};
std::vector<ShiftedFlight>* FirstMomentTest::flights_ = nullptr;

// Value and std of a named parameter of a solution.
std::pair<double, double> Estimate(const IdentificationResult& r, const std::string& name) {
  const int k = r.system.Column(name);
  EXPECT_GE(k, 0) << name;
  if (k < 0) return {0.0, 0.0};
  return {r.solution.chi[k], r.solution.std[k]};
}

TEST_F(FirstMomentTest, EachFlightsFirstMomentAndTheSharedParametersAreRecovered) {
  const IdentificationResult r = IdentifyAll(FirstMoment::kPerFlight);
  EXPECT_EQ(r.system.num_parameters(), 2 + 3 * 3 + 6);
  for (size_t k = 0; k < flights_->size(); ++k) {
    const std::string owner = "A.flight" + std::to_string(k + 1) + ".";
    for (int a = 0; a < 2; ++a) {  // ms_z is nearly unobservable (thrust along z): ms_x, ms_y
      const auto [value, std] = Estimate(r, owner + kBodyParameterNames[a]);
      ASSERT_GT(std, 0.0) << owner << kBodyParameterNames[a];
      EXPECT_NEAR(value, (*flights_)[k].first_moment[a], 3.0 * std) << owner << kBodyParameterNames[a];
      // Distinguishes the flights: the std is well below the 2 cm shifts times the mass.
      EXPECT_LT(std, 0.1 * 0.015 * Truth().mass_kg) << owner << kBodyParameterNames[a];
    }
  }
  const auto [kt, kt_std] = Estimate(r, "kt");
  EXPECT_NEAR(kt, Truth().rotor.kt, 3.0 * kt_std);
  EXPECT_NEAR(kt, Truth().rotor.kt, 0.01 * Truth().rotor.kt);
  for (int a = 0; a < 3; ++a) {
    const auto [inertia, std] = Estimate(r, std::string("A.") + kBodyParameterNames[3 + a]);
    EXPECT_NEAR(inertia, Truth().body.inertia(a, a), std::max(3.0 * std, 0.03 * Truth().body.inertia(a, a)))
        << kBodyParameterNames[3 + a];
  }
}

// With one shared first moment the same flights cannot be explained: the moment rows keep the
// shifts' gravity torque, the shared estimate is far (in its own std) from the flights' truths and
// the rest of the solution is biased with it (on these flights: Mx 88 % instead of 1.0 %, I_zz
// 0.0045 instead of 0.0289, truth 0.029).
TEST_F(FirstMomentTest, ASharedFirstMomentIsBiasedOnTheSameFlights) {
  const IdentificationResult shared = IdentifyAll(FirstMoment::kShared);
  const IdentificationResult own = IdentifyAll(FirstMoment::kPerFlight);
  for (int a = 0; a < 2; ++a) {
    const auto [value, std] = Estimate(shared, std::string("A.") + kBodyParameterNames[a]);
    double farthest = 0.0;
    for (const ShiftedFlight& f : *flights_) farthest = std::max(farthest, std::abs(value - f.first_moment[a]));
    EXPECT_GT(farthest, 10.0 * std) << kBodyParameterNames[a];
  }
  for (int c = 3; c < 5; ++c)  // Mx, My
    EXPECT_GT(*shared.relative_error_pct[c], 10.0 * *own.relative_error_pct[c]) << kWrenchComponentNames[c];
  double shared_error = 0.0, own_error = 0.0;  // of the diagonal inertia, relative
  for (int a = 0; a < 3; ++a) {
    const double truth = Truth().body.inertia(a, a);
    shared_error += std::abs(Estimate(shared, std::string("A.") + kBodyParameterNames[3 + a]).first - truth) / truth;
    own_error += std::abs(Estimate(own, std::string("A.") + kBodyParameterNames[3 + a]).first - truth) / truth;
  }
  EXPECT_GT(shared_error, 5.0 * own_error);
  EXPECT_GT(std::abs(Estimate(shared, "kd").first - Truth().rotor.kd),
            5.0 * std::abs(Estimate(own, "kd").first - Truth().rotor.kd));
}

// One flight: the per-flight layout is the shared one under other names, with the same numbers.
TEST_F(FirstMomentTest, OneFlightGivesTheSameNumbersAsTheSharedFirstMoment) {
  const std::vector<FlightData> one = {Data().front()};
  IdentifyOptions options;
  options.allow_partial = true;
  const IdentificationResult shared = Identify(one, options);
  options.first_moment = FirstMoment::kPerFlight;
  const IdentificationResult own = Identify(one, options);
  ASSERT_EQ(own.system.parameter_names.size(), shared.system.parameter_names.size());
  EXPECT_EQ(own.system.parameter_names[2], "A.flight1.ms_x");
  EXPECT_EQ(own.system.parameter_names[5], "A.I_xx");
  for (int k = 0; k < shared.system.num_parameters(); ++k) {
    EXPECT_EQ(own.solution.chi[k], shared.solution.chi[k]) << own.system.parameter_names[k];
    EXPECT_EQ(own.solution.std[k], shared.solution.std[k]) << own.system.parameter_names[k];
    EXPECT_EQ(own.solution.essential[k], shared.solution.essential[k]) << own.system.parameter_names[k];
  }
}

// The segments of one log are one flight: they share the label of their log.
TEST(FirstMomentLabels, SegmentsOfOneLogShareTheirFirstMoment) {
  std::vector<ProcessedFlight> flights(5);
  const int logs[] = {0, 0, 1, -1, 1};
  const char* names[] = {"A", "A", "A", "A", "B"};
  for (int i = 0; i < 5; ++i) {
    flights[i].log_index = logs[i];
    flights[i].vehicle.name = names[i];
  }
  LabelFirstMoments(FirstMoment::kPerFlight, &flights);
  const char* expected[] = {"flight1", "flight1", "flight2", "flight3", "flight1"};
  for (int i = 0; i < 5; ++i) EXPECT_EQ(flights[i].first_moment_label, expected[i]) << i;
  EXPECT_EQ(BodyParameterName(flights[2], 0), "A.flight2.ms_x");
  EXPECT_EQ(BodyParameterName(flights[2], 3), "A.I_xx");
  LabelFirstMoments(FirstMoment::kShared, &flights);
  EXPECT_EQ(BodyParameterName(flights[2], 0), "A.ms_x");
}

// A flight the parameters were not identified on gets its own first moment fitted, close to its truth.
TEST_F(FirstMomentTest, AHeldOutFlightsFirstMomentIsFitted) {
  const IdentificationResult r = IdentifyAll(FirstMoment::kPerFlight);
  std::map<std::string, double> values = NamedParameters(r.system, r.solution.chi);
  const ShiftedFlight held_out = SimulateShifted({0.01, 0.025, 0.0}, 21, 30.0);
  std::vector<ProcessedFlight> flights = ProcessFlights({{held_out.sim.vehicle, held_out.sim.log, 1.0}}, {});
  const std::vector<std::string> added = FitHeldOutFirstMoments(&flights, &values);
  ASSERT_EQ(added.size(), 3u);
  EXPECT_EQ(added[0], "A.held_out1.ms_x");
  const double mass = held_out.sim.vehicle.mass_kg;
  for (int a = 0; a < 2; ++a)  // within 1 mm of the true centre of mass (the shift is 10 and 25 mm)
    EXPECT_NEAR(values.at(added[a]) / mass, held_out.first_moment[a] / mass, 1e-3) << added[a];
  // The fit is what makes the flight's Table III: at the mean first moment it is worse.
  const auto fitted = FitFlight(flights[0], values).relative_error_pct;
  std::map<std::string, double> mean = values;
  for (int a = 0; a < 3; ++a) {
    mean[added[a]] = 0.0;
    for (int k = 1; k <= 3; ++k)
      mean[added[a]] += values.at("A.flight" + std::to_string(k) + "." + kBodyParameterNames[a]) / 3.0;
  }
  const auto at_mean = FitFlight(flights[0], mean).relative_error_pct;
  EXPECT_LT(*fitted[3], 0.8 * *at_mean[3]);
}

// The refinement uses the same layout: with a delay estimated, each flight's first moment stays on
// its truth.
TEST_F(FirstMomentTest, RefinementKeepsEachFlightsFirstMoment) {
  const IdentificationResult linear = IdentifyAll(FirstMoment::kPerFlight);
  RefineOptions options;
  options.effects = ParseEffectList("delay");
  const RefineResult refined = Refine(linear, options);
  for (size_t k = 0; k < flights_->size(); ++k)
    for (int a = 0; a < 2; ++a) {
      const int column = linear.system.Column("A.flight" + std::to_string(k + 1) + "." + kBodyParameterNames[a]);
      EXPECT_NEAR(refined.refined.chi[column], (*flights_)[k].first_moment[a], 3.0 * linear.solution.std[column])
          << linear.system.parameter_names[column];
    }
}

}  // namespace
}  // namespace rotorid

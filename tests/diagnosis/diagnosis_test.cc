// The diagnosis on simulated flights whose effect is withheld: it must name the effect first, mark
// it significant and recover its size; on a clean flight it must flag nothing.

#include "rotorid/diagnosis/diagnosis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "diagnosis/unexplained.h"
#include "rotorid/core/error.h"
#include "rotorid/core/units.h"
#include "rotorid/diagnosis/diagnosis_checks.h"
#include "rotorid/diagnosis/diagnosis_json.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/model/rotation.h"
#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

// Configuration B (asymmetric: kd and I_zz identifiable), pixhawk-level noise by default.
ProcessedFlight SimulatedFlight(double seconds, std::uint64_t seed, const Effects& effects) {
  const SimulationResult sim = testing::SimulatePreset("B", seconds, seed, effects);
  return ProcessFlights({{sim.vehicle, sim.log, 1.0}}, ObservationOptions{}).front();
}

// Few folds keep the test fast in sanitizer builds; the benchmark runs the defaults.
DiagnosisOptions TestOptions() {
  DiagnosisOptions options;
  options.folds = 3;
  return options;
}

const EffectVerdict& VerdictOf(const Diagnosis& d, EffectKind kind) {
  for (const EffectVerdict& v : d.ranking)
    if (v.kind == kind) return v;
  throw Error("no verdict");
}

TEST(DiagnosisTest, WithheldDelayIsRankedFirstAndItsSizeRecovered) {
  Effects withheld;
  withheld.Set("delay_s", 0.018);
  struct Call {
    std::string batch;
    int done, total;
  };
  std::vector<Call> calls;
  const Diagnosis d = Diagnose({SimulatedFlight(45.0, 21, withheld)}, {}, TestOptions(),
                               [&calls](const std::string& batch, int done, int total) {
                                 calls.push_back({batch, done, total});
                               });
  // Progress: each batch of fold refinements counts from 0 to its total, models x 3 folds, and the
  // batches add up to every refinement made.
  int refinements = 0;
  for (size_t k = 0; k < calls.size(); ++k) {
    const bool starts = calls[k].done == 0;
    if (starts) {
      EXPECT_EQ(calls[k].total % 3, 0) << calls[k].batch;
      EXPECT_NE(calls[k].batch.find("in 3 folds"), std::string::npos) << calls[k].batch;
    } else {
      EXPECT_EQ(calls[k].done, calls[k - 1].done + 1) << calls[k].batch;
    }
    if (k + 1 == calls.size() || calls[k + 1].done == 0) {
      EXPECT_EQ(calls[k].done, calls[k].total) << calls[k].batch;
      refinements += calls[k].total;
    }
  }
  EXPECT_GT(refinements, 0);
  EXPECT_EQ(refinements, d.refinements);
  ASSERT_FALSE(d.selected.empty()) << DiagnosisVerdict(d);
  EXPECT_EQ(d.selected.front(), ParseEffectKind("delay")) << DiagnosisVerdict(d);
  const EffectVerdict& first = d.ranking.front();
  EXPECT_EQ(first.kind, ParseEffectKind("delay"));
  EXPECT_TRUE(first.significant);
  EXPECT_EQ(first.status, "selected");
  EXPECT_NEAR(first.value[0], withheld.Scalar("delay_s"), 1e-3);  // the refinement issue's tolerance
  EXPECT_GT(first.std[0], 0.0);
  EXPECT_GT(first.test.shrink_pct, 10.0);
  // Its screening (the best in-sample shrink over the delay grid) is a share of the criterion, on
  // the same scale as the first-order screening of the other candidates.
  EXPECT_GT(first.screening.shrink_pct, 10.0);
  EXPECT_LE(first.screening.shrink_pct, 100.0);
  // The held-out gap of the rotor-driven components shrinks.
  for (int j : {2, 3, 4}) EXPECT_LT(*d.final_gap.relative_error_pct[j], *d.baseline.relative_error_pct[j]) << j;
  EXPECT_EQ(d.selected.size(), 1u) << DiagnosisVerdict(d);
  // The baseline lies far above the noise floor; the delay explains it, and nothing is left.
  EXPECT_FALSE(internal::FindUnexplained(d.baseline, d.baseline, d.where, TestOptions()).empty());
  EXPECT_TRUE(d.unexplained.empty()) << DiagnosisVerdict(d);
}

TEST(DiagnosisTest, WithheldAccBiasIsRankedFirstWithinThreeStd) {
  Effects withheld;
  withheld.Set("acc_bias", Eigen::Vector3d(0.3, -0.2, 0.25));
  const Diagnosis d = Diagnose({SimulatedFlight(45.0, 22, withheld)}, {}, TestOptions());
  ASSERT_FALSE(d.selected.empty()) << DiagnosisVerdict(d);
  EXPECT_EQ(d.selected.front(), ParseEffectKind("acc_bias")) << DiagnosisVerdict(d);
  const EffectVerdict& first = d.ranking.front();
  EXPECT_TRUE(first.significant);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(std::abs(first.value[a] - withheld.Get("acc_bias")[a]), 3.0 * first.std[a] + 1e-9)
        << "axis " << a << ": " << first.value[a] << " +- " << first.std[a];
    EXPECT_LT(first.std[a], 0.05);
  }
  EXPECT_EQ(d.selected.size(), 1u) << DiagnosisVerdict(d);
}

// A delay and a lag of similar equivalent size are one effect to first order: held-out shrinks
// within a hair of each other must be reported as confounded, with what the data do fix (about the
// sum, 25 ms), even when a paired t statistic on many rows is large (issue 11).
TEST(DiagnosisTest, DelayPlusLagIsReportedAsConfoundedWithWhatTheDataFix) {
  Effects withheld;
  withheld.Set("delay_s", 0.005);
  withheld.Set("motor_tau_s", 0.020);
  const EffectKind delay = ParseEffectKind("delay"), lag = ParseEffectKind("motor_lag");
  DiagnosisOptions options = TestOptions();
  options.candidates = {delay, lag};
  const Diagnosis d = Diagnose({SimulatedFlight(45.0, 29, withheld)}, {}, options);
  ASSERT_EQ(d.selected.size(), 1u) << DiagnosisVerdict(d);
  ASSERT_EQ(d.confounded.size(), 1u) << DiagnosisVerdict(d);
  const ConfoundedEffects& c = d.confounded.front();
  EXPECT_FALSE(c.distinguishable) << c.note;
  EXPECT_NE(c.note.find("cannot tell"), std::string::npos) << c.note;
  EXPECT_NE(c.note.find("fit as well"), std::string::npos) << c.note;
  const EffectKind other = d.selected.front() == delay ? lag : delay;
  EXPECT_EQ(VerdictOf(d, other).status, "confounded") << DiagnosisVerdict(d);
  // Whichever is selected carries the shared 25 ms.
  const double value = d.final_effects.Scalar(d.selected.front());
  EXPECT_NEAR(value, 0.025, 0.004) << DiagnosisVerdict(d);
}

// An accelerometer bias beyond the effect's physical range (3 m/s^2 on z, bound 2) ends the final
// fit with its z coordinate on the bound: a clipped value, not an estimate, so the effect is reported
// implausible (naming the bound) and not selected.
TEST(DiagnosisTest, EffectOnItsBoundIsImplausibleNotSelected) {
  Effects withheld;
  withheld.Set("acc_bias", Eigen::Vector3d(0.1, -0.1, 3.0));
  const EffectKind acc_bias = ParseEffectKind("acc_bias");
  DiagnosisOptions options = TestOptions();
  options.candidates = {acc_bias};
  const Diagnosis d = Diagnose({SimulatedFlight(45.0, 5, withheld)}, {}, options);
  EXPECT_TRUE(d.selected.empty()) << DiagnosisVerdict(d);
  const EffectVerdict& v = VerdictOf(d, acc_bias);
  EXPECT_EQ(v.status, "implausible") << v.note;
  EXPECT_EQ(v.implausible,
            "acc_bias_z = 2 m/s^2 is on its upper bound (2 m/s^2): the data push it further (refined on all "
            "identification data)");
  EXPECT_EQ(v.note.rfind("implausible: absorbs something else; " + v.implausible, 0), 0u) << v.note;
  EXPECT_NE(DiagnosisVerdict(d).find("acc_bias: implausible"), std::string::npos) << DiagnosisVerdict(d);
}

// Per-rotor thrust scales of a realistic size (a few %) are a default candidate of the diagnosis
// (DiagnosisCandidates, issue 41): selected among all of them, each within the 0.01, their sum
// pinned at zero, and nothing left unexplained.
TEST(DiagnosisTest, PerRotorThrustScalesOfRealisticSizeAreSelected) {
  const EffectKind scale = ParseEffectKind("rotor_thrust_scale");
  Effects withheld;
  withheld.Set(scale, Eigen::Vector4d(0.03, -0.02, -0.03, 0.02));
  const DiagnosisOptions options = TestOptions();
  ASSERT_NE(std::find(options.candidates.begin(), options.candidates.end(), scale), options.candidates.end());
  const Diagnosis d = Diagnose({SimulatedFlight(30.0, 31, withheld)}, {}, options);
  ASSERT_EQ(d.selected, std::vector<EffectKind>{scale}) << DiagnosisVerdict(d);
  const EffectVerdict& v = VerdictOf(d, scale);
  EXPECT_EQ(v.status, "selected");
  ASSERT_EQ(v.value.size(), 4);
  ASSERT_EQ(v.std.size(), 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(v.value[i], withheld.Get(scale)[i], 0.01) << DiagnosisVerdict(d);
    EXPECT_GT(v.std[i], 0.0);
  }
  EXPECT_NEAR(v.value.sum(), 0.0, 1e-3);
  EXPECT_EQ(v.test.added_parameters, 3);  // four scales, their sum pinned
  EXPECT_TRUE(d.unexplained.empty()) << DiagnosisVerdict(d);
}

// An effect acting where nothing is scored: a rotor inertia of J = 5e-5 kg m^2 on a 30 s flight of
// A makes the linear fit discard kd, so the held-out score leaves Mz out. The scale-free test of Mz
// (the yaw row alone, as ratios to kd) finds it, ranks it first and recovers J / kd within 15 %
// (987 +- 27 for 980 when it was written); kd itself is not fixed, so J is not reported in SI.
// Before the test the rotor inertia was "not refined" with "this data cannot rule it out".
TEST(DiagnosisTest, EffectActingWhereNothingIsScoredIsFoundByTheScaleFreeTest) {
  const EffectKind inertia = ParseEffectKind("rotor_inertia");
  Effects withheld;
  withheld.Set(inertia, 5e-5);
  const SimulationResult sim = testing::SimulatePreset("A", 30.0, 1, withheld);
  DiagnosisOptions options = TestOptions();
  options.candidates = {inertia, ParseEffectKind("acc_bias")};
  options.identify.allow_partial = true;
  const Diagnosis d = Diagnose(ProcessFlights({{sim.vehicle, sim.log, 1.0}}, ObservationOptions{}), {}, options);
  ASSERT_FALSE(d.baseline.relative_error_pct[5].has_value()) << DiagnosisVerdict(d);  // Mz not scored
  const EffectVerdict& v = VerdictOf(d, inertia);
  ASSERT_TRUE(v.selected) << DiagnosisVerdict(d);
  EXPECT_EQ(d.ranking.front().kind, inertia) << DiagnosisVerdict(d);
  EXPECT_EQ(d.selected_scale_free, std::vector<EffectKind>{inertia});
  ASSERT_TRUE(v.scale_free.has_value());
  const ScaleFreeTest& t = *v.scale_free;
  EXPECT_EQ(t.component, 5);
  EXPECT_EQ(t.rotor_coefficient, "kd");
  EXPECT_TRUE(t.test.significant);
  EXPECT_LT(t.relative_error_after_pct, 0.6 * t.relative_error_before_pct) << v.note;
  ASSERT_EQ(t.ratio.size(), 1);
  ASSERT_EQ(t.labels, std::vector<std::string>{"rotor_inertia_kgm2 / kd"});
  const double truth = 5e-5 / sim.truth.rotor.kd;
  RecordProperty("scale_free_note", v.note);  // --gtest_output=xml shows the numbers
  EXPECT_NEAR(t.ratio[0], truth, 0.15 * truth) << v.note;
  EXPECT_GT(t.ratio_std[0], 0.0);
  EXPECT_LT(t.ratio_std[0], 0.1 * truth);
  EXPECT_EQ(v.value.size(), 0) << "kd is not fixed: no SI value";
  EXPECT_NE(v.note.find("so rotor_inertia_kgm2 itself is not"), std::string::npos) << v.note;
  EXPECT_NE(DiagnosisVerdict(d).find("which: rotor_inertia: the scale-free test of Mz"), std::string::npos)
      << DiagnosisVerdict(d);
  EXPECT_EQ(VerdictOf(d, ParseEffectKind("acc_bias")).unscored, "");  // acts on the forces
  // Not in the final model: its scale is not known. The JSON gives the ratio and no SI value.
  EXPECT_EQ(std::count(d.final_model.begin(), d.final_model.end(), inertia), 0);
  const nlohmann::json j = DiagnosisJson(d);
  EXPECT_EQ(j["selected"].front(), "rotor_inertia");
  EXPECT_FALSE(j["final"]["effects"].contains("rotor_inertia_kgm2"));
  EXPECT_TRUE(j["ranking"].front()["magnitude"]["rotor_inertia_kgm2"]["value"].is_null());
  EXPECT_NEAR(j["ranking"].front()["scale_free"]["values"]["rotor_inertia_kgm2 / kd"]["value"].get<double>(), truth,
              0.15 * truth);
  // identify says why Mz is missing, and what can cause it; not on the clean flight of the same seed.
  auto kd_warning = [](const IdentificationResult& r) {
    for (const std::string& w : r.warnings)
      if (w.rfind("kd is not identified (", 0) == 0) return w;
    return std::string();
  };
  const std::string warning = kd_warning(testing::IdentifySimulated(sim));
  EXPECT_NE(warning.find("left out of Table III and of the diagnosis's held-out score"), std::string::npos) << warning;
  EXPECT_NE(warning.find("a rotor inertia)"), std::string::npos) << warning;
  EXPECT_EQ(kd_warning(testing::IdentifySimulated(testing::SimulatePreset("A", 30.0, 1, Effects{}))), "");
}

// The scale-free test does not invent a rotor inertia: a 20 ms motor lag also makes the linear fit
// discard kd (the bundled demo's case), so Mz is unscored and the rotor inertia, acting mostly there,
// gets the test; with no rotor inertia in the flight it must not pass.
TEST(DiagnosisTest, ScaleFreeTestSelectsNoRotorInertiaThatIsNotThere) {
  const EffectKind inertia = ParseEffectKind("rotor_inertia"), lag = ParseEffectKind("motor_lag");
  Effects withheld;
  withheld.Set(lag, 0.02);
  const SimulationResult sim = testing::SimulatePreset("A", 30.0, 1, withheld);
  DiagnosisOptions options = TestOptions();
  options.candidates = {inertia, lag};
  options.identify.allow_partial = true;
  const Diagnosis d = Diagnose(ProcessFlights({{sim.vehicle, sim.log, 1.0}}, ObservationOptions{}), {}, options);
  const EffectVerdict& v = VerdictOf(d, inertia);
  EXPECT_FALSE(v.selected) << DiagnosisVerdict(d);
  EXPECT_TRUE(d.selected_scale_free.empty()) << DiagnosisVerdict(d);
  RecordProperty("rotor_inertia_note", v.note);
  ASSERT_FALSE(d.baseline.relative_error_pct[5].has_value()) << DiagnosisVerdict(d);  // Mz not scored
  ASSERT_TRUE(v.scale_free.has_value()) << v.note;                                    // so it was tested
  EXPECT_FALSE(v.scale_free->test.significant && v.scale_free->implausible.empty()) << v.note;
}

// A wrong candidate that fits only with absurd values is reported as absorbing something else and is
// not selected: per-rotor thrust scales of +-25 % (beyond the +-10 % propellers of a batch show) are
// forced into the flight; the true effect of the same flight, a delay of a realistic size, is still
// selected.
TEST(DiagnosisTest, ThrustScalesOfTensOfPercentAreImplausibleAndNotSelected) {
  const EffectKind scale = ParseEffectKind("rotor_thrust_scale"), delay = ParseEffectKind("delay");
  Effects withheld;
  withheld.Set(delay, 0.015);
  withheld.Set(scale, Eigen::Vector4d(0.25, -0.25, 0.0, 0.0));
  DiagnosisOptions options = TestOptions();
  options.candidates = {delay, scale};
  const Diagnosis d = Diagnose({SimulatedFlight(30.0, 32, withheld)}, {}, options);
  const EffectVerdict& v = VerdictOf(d, scale);
  EXPECT_EQ(v.status, "implausible") << DiagnosisVerdict(d);
  EXPECT_FALSE(v.selected);
  EXPECT_TRUE(v.test.significant) << DiagnosisVerdict(d);
  EXPECT_GT(v.value.cwiseAbs().maxCoeff(), 0.15) << DiagnosisVerdict(d);
  EXPECT_EQ(v.note.rfind("implausible: absorbs something else; rotor_thrust_scale_1 = ", 0), 0u) << v.note;
  EXPECT_NE(v.note.find("is outside its physical range [-10 %, 10 %]"), std::string::npos) << v.note;
  EXPECT_NE(DiagnosisVerdict(d).find("rotor_thrust_scale: implausible: absorbs something else"), std::string::npos)
      << DiagnosisVerdict(d);
  ASSERT_EQ(d.selected, std::vector<EffectKind>{delay}) << DiagnosisVerdict(d);
  EXPECT_NEAR(d.final_effects.Scalar(delay), 0.015, 1e-3) << DiagnosisVerdict(d);
  const nlohmann::json j = DiagnosisJson(d);
  bool found = false;
  for (const nlohmann::json& entry : j["ranking"])
    if (entry["effect"] == "rotor_thrust_scale") {
      found = true;
      EXPECT_EQ(entry["status"], "implausible");
      EXPECT_EQ(entry["magnitude"]["rotor_thrust_scale"]["value"].size(), 4u);
    }
  EXPECT_TRUE(found);
}

// An IMU lever arm standing in for part of an accelerometer bias (issue 10: r_z ran to its 300 mm
// bound and was selected second; then dropped by the final model's plausibility check) is not
// selected: its z is now held at the vehicle file's value, and what is left (x, y) explains nothing
// the bias does not. Release only (scripts/test.sh).
TEST(DiagnosisTest, LeverArmAbsorbingAnAccBiasIsNotSelected) {
  Effects withheld;
  withheld.Set("acc_bias", Eigen::Vector3d(0.3, -0.2, 0.25));
  DiagnosisOptions options = TestOptions();
  const EffectKind lever_arm = ParseEffectKind("imu_lever_arm");
  options.candidates = {ParseEffectKind("acc_bias"), lever_arm};
  const Diagnosis d = Diagnose({SimulatedFlight(45.0, 22, withheld)}, {}, options);
  EXPECT_EQ(d.selected, std::vector<EffectKind>{ParseEffectKind("acc_bias")}) << DiagnosisVerdict(d);
  const EffectVerdict& v = VerdictOf(d, lever_arm);
  EXPECT_EQ(v.status, "not significant") << DiagnosisVerdict(d);
  EXPECT_EQ(v.value[2], 0.0) << "r_z is held";
}

// A lever arm of (20, 10) mm in x, y is a default candidate (DiagnosisCandidates, issue 41) and, on a
// paper-like flight with angular acceleration, told apart from a misalignment and an acc bias: named
// alone, within 2 mm, r_z held. Before, without it among the candidates, a misalignment, an acc delay
// and an acc bias were selected in its place.
TEST(DiagnosisTest, LeverArmIsNamedAmongTheDefaultCandidates) {
  const EffectKind lever_arm = ParseEffectKind("imu_lever_arm");
  Effects withheld;
  withheld.Set(lever_arm, Eigen::Vector3d(0.02, 0.01, -0.03));
  const Diagnosis d = Diagnose({SimulatedFlight(30.0, 24, withheld)}, {}, TestOptions());
  ASSERT_EQ(d.selected, std::vector<EffectKind>{lever_arm}) << DiagnosisVerdict(d);
  const EffectVerdict& v = VerdictOf(d, lever_arm);
  EXPECT_NEAR(v.value[0], 0.02, 2e-3) << DiagnosisVerdict(d);
  EXPECT_NEAR(v.value[1], 0.01, 2e-3) << DiagnosisVerdict(d);
  EXPECT_NEAR(v.value[2], 0.0, 1e-6) << "r_z is held";
  EXPECT_TRUE(d.unexplained.empty()) << DiagnosisVerdict(d);
}

// On a Crazyflie-like flight (CF preset, 40 s at 500 Hz) whose accelerometer lags by 4 ms and
// whose IMU sits at O_d, the lever arm's z took the place of the first moment ms_z (CF's centre of
// mass is 2 mm below O_d): r_z = 2.16 +- 0.11 mm, held-out shrink 3.6 %, selected second. Held at
// the vehicle file's value, what is left of the lever arm (x, y) explains nothing. Release only
// (scripts/test.sh): 500 Hz flights are slow under the sanitizers.
TEST(DiagnosisTest, LeverArmDoesNotTakeTheFirstMomentsPlaceAlongZ) {
  Effects withheld;
  withheld.Set("acc_delay_s", 0.004);
  const SimulationResult sim = testing::SimulatePreset("CF", 40.0, 1, withheld);
  const ProcessedFlight flight = ProcessFlights({{sim.vehicle, sim.log, 1.0}}, ObservationOptions{}).front();
  DiagnosisOptions options;
  const EffectKind lever_arm = ParseEffectKind("imu_lever_arm");
  options.candidates = {ParseEffectKind("acc_delay"), lever_arm};
  const Diagnosis d = Diagnose({flight}, {}, options);
  EXPECT_EQ(d.selected, std::vector<EffectKind>{ParseEffectKind("acc_delay")}) << DiagnosisVerdict(d);
  EXPECT_NEAR(VerdictOf(d, ParseEffectKind("acc_delay")).value[0], 0.004, 1e-3);
  const EffectVerdict& v = VerdictOf(d, lever_arm);
  EXPECT_FALSE(v.significant) << DiagnosisVerdict(d);
  // It still says what it would reveal, in x and y only.
  ASSERT_EQ(v.detectable_above.size(), 3);
  EXPECT_GT(v.detectable_above[0], 0.0);
}

// The independent simulator's take-off / low hover / landing flight (ground_effect_coefficient 1):
// the ground effect alone is selected. Before the held-out score left the static part of Mx and My out
// of its divisor, per-rotor thrust scales (1.1, -0.3, -0.9, 0.1) % and then a lever arm (-8.8, 0.3) mm
// were selected beside it: the scales, with a first moment moved to cancel them, inflated the rotor
// moment the score divides by (held-out "shrink" 6.0 %) while the residual did not fall. Release only
// (scripts/test.sh): HeldOutScoreTest.AStaticMomentThatAFirstMomentBalancesDoesNotPay runs its path.
TEST(DiagnosisTest, IndependentGroundEffectFlightSelectsTheGroundEffectAlone) {
  const auto dir = testing::SharedDataPath("independent-sim");
  if (!dir) GTEST_SKIP() << "../shared/data/independent-sim is absent";
  const std::string base = *dir + "/A_ground_effect";
  const Vehicle vehicle = ReadVehicleYaml(base + ".yaml");
  const FlightLog log = ReadFlightCsv(base + ".csv", vehicle.num_rotors());
  IdentifyOptions identify;
  identify.allow_partial = true;
  DiagnosisOptions options;
  options.identify = identify;
  const EffectKind ground = ParseEffectKind("ground_effect");
  options.candidates = {ground, ParseEffectKind("rotor_thrust_scale"), ParseEffectKind("imu_lever_arm")};
  const Diagnosis d = Diagnose(ProcessFlights({{vehicle, log, 1.0}}, ObservationOptions{}), {}, options);
  EXPECT_EQ(d.selected, std::vector<EffectKind>{ground}) << DiagnosisVerdict(d);
  EXPECT_NEAR(VerdictOf(d, ground).value[0], 1.0, 0.03) << DiagnosisVerdict(d);
}

// The controller's reply to gyro noise makes the rotor signal follow the noise of w' above the
// pilot's band (0.15-2.5 Hz, scaled down near the ground): on a clean take-off-and-landing flight of A
// a delay reads 1.06 +- 0.13 ms at the 10 Hz cut-off (12 ms at 20 Hz), removed 1.2 % of the held-out
// residual and was selected; at 5 Hz it reads 0.14 +- 0.07 ms. A true 10 ms delay on the same flight
// holds there (11.0 ms at 10 Hz, 10.2 at 5 Hz) and stays selected.
TEST(DiagnosisTest, DelayThatTheControllersReplyToNoiseFakesIsImplausible) {
  const EffectKind delay = ParseEffectKind("delay");
  auto diagnose = [&](double delay_s) {
    const SimulationVehicle preset = PresetVehicle("A");
    SimulationOptions sim;
    sim.duration_s = 60.0;
    sim.seed = 2;
    sim.profile = FlightProfile::kTakeoffLanding;
    sim.effects.Set(delay, delay_s);
    const SimulationResult flight = Simulate(preset.vehicle, preset.parameters, sim);
    DiagnosisOptions options;
    options.candidates = {delay, ParseEffectKind("motor_lag")};
    return Diagnose(ProcessFlights({{flight.vehicle, flight.log, 1.0}}, ObservationOptions{}), {}, options);
  };
  const Diagnosis clean = diagnose(0.0);
  EXPECT_TRUE(clean.selected.empty()) << DiagnosisVerdict(clean);
  const EffectVerdict& faked = VerdictOf(clean, delay);
  EXPECT_EQ(faked.status, "implausible") << faked.note;
  EXPECT_NE(faked.implausible.find("at the 10 Hz cut-off"), std::string::npos) << faked.implausible;
  EXPECT_NE(faked.implausible.find("at 5 Hz"), std::string::npos) << faked.implausible;

  const Diagnosis delayed = diagnose(0.010);
  ASSERT_FALSE(delayed.selected.empty()) << DiagnosisVerdict(delayed);
  EXPECT_EQ(delayed.selected.front(), delay) << DiagnosisVerdict(delayed);
  EXPECT_NEAR(VerdictOf(delayed, delay).value[0], 0.010, 1.5e-3) << DiagnosisVerdict(delayed);
  EXPECT_NE(VerdictOf(delayed, delay).note.find("holds at half the low-pass cut-off"), std::string::npos)
      << VerdictOf(delayed, delay).note;
}

// A 20 ms motor lag behind a battery-driven command: on the held-out rows a 19.7 ms delay removes as
// much residual as the lag (34.2 % and 33.9 % on this flight) and was selected in its place, "confounded".
// Refined together with the battery at half the cut-off, the lag keeps the timing (delay 0.0 +- 0.2
// ms, lag 20 ms), and the final model takes the lag.
TEST(DiagnosisTest, LagTiedWithADelayIsSeparatedAtHalfTheCutoff) {
  const EffectKind delay = ParseEffectKind("delay"), lag = ParseEffectKind("motor_lag"),
                   battery = ParseEffectKind("battery");
  const SimulationVehicle preset = PresetVehicle("A");
  SimulationOptions sim;
  sim.duration_s = 30.0;
  sim.seed = 3;
  sim.battery.enabled = true;
  sim.effects.Set(battery, 1.0);
  sim.effects.Set(lag, 0.020);
  SimulationResult flight = Simulate(preset.vehicle, preset.parameters, sim);
  ApplyCommandToSpeed(*flight.vehicle.command_to_speed, &flight.log);  // as `diagnose --log` reads it
  DiagnosisOptions options;
  options.candidates = {delay, lag, battery};
  const Diagnosis d = Diagnose(ProcessFlights({{flight.vehicle, flight.log, 1.0}}, ObservationOptions{}), {}, options);

  ASSERT_EQ(d.selected, (std::vector<EffectKind>{lag, battery})) << DiagnosisVerdict(d);
  EXPECT_NEAR(VerdictOf(d, lag).value[0], 0.020, 1e-3);
  ASSERT_EQ(d.confounded.size(), 1u) << DiagnosisVerdict(d);
  const ConfoundedEffects& tie = d.confounded.front();
  EXPECT_EQ(tie.selected, lag);
  EXPECT_EQ(tie.other, delay);
  // The held-out rows preferred the delay, by a hair.
  EXPECT_GT(tie.other_shrink_pct, tie.selected_shrink_pct);
  EXPECT_LT(tie.other_shrink_pct - tie.selected_shrink_pct, 0.1 * tie.other_shrink_pct);
  EXPECT_TRUE(tie.distinguishable);
  EXPECT_NE(tie.note.find("refined together at half the low-pass cut-off (5.0 Hz)"), std::string::npos) << tie.note;
  EXPECT_NE(tie.note.find("motor_lag carries the timing"), std::string::npos) << tie.note;
  EXPECT_EQ(VerdictOf(d, delay).status, "not significant") << VerdictOf(d, delay).note;
}

TEST(DiagnosisTest, CleanFlightFlagsNothing) {
  const Diagnosis d = Diagnose({SimulatedFlight(45.0, 23, Effects{})}, {}, TestOptions());
  EXPECT_TRUE(d.selected.empty()) << DiagnosisVerdict(d);
  ASSERT_EQ(d.ranking.size(), DiagnosisCandidates().size());
  for (const EffectVerdict& v : d.ranking) {
    EXPECT_FALSE(v.significant) << EffectName(v.kind);
    // rotor_drag needs the velocity and battery a command log with a voltage, which an IMU-only
    // log of rotor speeds lacks.
    if (!v.kind->info().inputs.empty() && v.status == "unavailable") {
      const std::string needs = v.kind->name() == "battery" ? "voltage" : "velocity";
      EXPECT_NE(v.note.find(needs), std::string::npos) << v.note;
      continue;
    }
    EXPECT_EQ(v.status, "not significant") << EffectName(v.kind);
    EXPECT_EQ(v.unscored, "") << EffectName(v.kind);  // kd identified: every component scored
    // Absent effects come with the smallest size this flight would reveal (a held coordinate, the
    // lever arm's z, has none).
    ASSERT_EQ(v.detectable_above.size(), v.kind->Dimension(PresetVehicle("B").vehicle));
    const std::vector<int>& held = v.kind->info().held_coordinates;
    for (int k = 0; k < v.detectable_above.size(); ++k) {
      if (std::find(held.begin(), held.end(), k) != held.end()) continue;
      EXPECT_GT(v.detectable_above[k], 0.0) << EffectName(v.kind) << " " << k;
    }
  }
  // A gyro bias of realistic size (<= 0.03 rad/s) is below what these equations reveal on 45 s.
  EXPECT_GT(VerdictOf(d, ParseEffectKind("gyro_bias")).detectable_above.maxCoeff(), 0.03);
  // Delay would show from well below a millisecond.
  EXPECT_LT(VerdictOf(d, ParseEffectKind("delay")).detectable_above[0], 1e-3);
  // Held-out equals final; every contract key is there.
  const nlohmann::json j = DiagnosisJson(d);
  for (const char* c : {"Fx", "Fy", "Fz", "Mx", "My", "Mz"}) {
    EXPECT_TRUE(j["baseline"]["relative_error_pct"].contains(c)) << c;
    EXPECT_TRUE(j["final"]["relative_error_pct"].contains(c)) << c;
  }
  EXPECT_TRUE(j["baseline"]["relative_error_pct"]["Fx"].is_null());
  EXPECT_TRUE(j["where"]["component"].is_string());
  EXPECT_TRUE(j["selected"].is_array() && j["selected"].empty());
  EXPECT_EQ(j["ranking"].size(), DiagnosisCandidates().size());
  // Nothing left far above the noise floor: the contract's list is there, and empty.
  EXPECT_TRUE(d.unexplained.empty()) << DiagnosisVerdict(d);
  EXPECT_TRUE(j["unexplained"].is_array() && j["unexplained"].empty());
  EXPECT_NE(DiagnosisVerdict(d).find("unexplained: nothing far above the noise floor"), std::string::npos);
}

// A force rotorid does not model (4 % of the weight, at O_d, turning in the world once per 12 s, like a
// payload's pull or a drifting wind) reaches the accelerometer as a horizontal force no candidate
// reproduces: the diagnosis says so in Fx and Fy, rather than naming rotor drag (a candidate here:
// the log has motion capture) or a sensor effect with confidence.
TEST(DiagnosisTest, ExternalForceIsCalledUnexplained) {
  const SimulationVehicle b = PresetVehicle("B");
  SimulationOptions options;
  options.duration_s = 40.0;
  options.seed = 27;
  options.mocap = true;
  options.external_force.world_n = Eigen::Vector3d(0.04 * b.parameters.mass_kg * kStandardGravity, 0.0, 0.0);
  options.external_force.turn_period_s = 12.0;
  const SimulationResult sim = Simulate(b.vehicle, b.parameters, options);
  const ProcessedFlight flight = ProcessFlights({{sim.vehicle, sim.log, 1.0}}, ObservationOptions{}).front();
  const Diagnosis d = Diagnose({flight}, {}, TestOptions());
  ASSERT_FALSE(d.unexplained.empty()) << DiagnosisVerdict(d);
  std::vector<std::string> components;
  for (const UnexplainedResidual& u : d.unexplained) {
    components.push_back(kWrenchComponentNames[u.component]);
    EXPECT_GT(u.gap_pct, 3.0 * u.noise_floor_pct);
    EXPECT_GT(u.share_pct, 89.0);
    EXPECT_GT(u.band_share_pct, 0.0);
  }
  // 4 % of the weight against the thrust: a held-out gap of about 4 % in the horizontal plane.
  for (const char* c : {"Fx", "Fy"})
    EXPECT_NE(std::find(components.begin(), components.end(), c), components.end()) << c << "\n" << DiagnosisVerdict(d);
  EXPECT_NE(d.unexplained.front().note.find("a force off the thrust axis"), std::string::npos);
  EXPECT_NE(d.unexplained.front().note.find("external force"), std::string::npos);
  EXPECT_NE(DiagnosisVerdict(d).find("unexplained: F"), std::string::npos) << DiagnosisVerdict(d);
  const nlohmann::json j = DiagnosisJson(d);
  ASSERT_TRUE(j["unexplained"].is_array());
  ASSERT_EQ(j["unexplained"].size(), d.unexplained.size());
  for (const char* key : {"component", "share_pct", "band", "note"}) EXPECT_TRUE(j["unexplained"][0].contains(key));
}

TEST(DiagnosisTest, HeldOutFlightsReplaceFoldsAndFindMisalignment) {
  Effects withheld;
  withheld.Set("misalignment_rad", Eigen::Vector3d(0.6, -1.5, 0.5) * M_PI / 180.0);
  const Diagnosis d =
      Diagnose({SimulatedFlight(40.0, 24, withheld)}, {SimulatedFlight(40.0, 25, withheld)}, TestOptions());
  EXPECT_NE(d.validation.find("held-out flight"), std::string::npos) << d.validation;
  ASSERT_FALSE(d.selected.empty()) << DiagnosisVerdict(d);
  EXPECT_EQ(d.selected.front(), ParseEffectKind("misalignment")) << DiagnosisVerdict(d);
  const EffectVerdict& first = d.ranking.front();
  const Eigen::Matrix3d difference =
      ExpSO3<double>(first.value).transpose() * ExpSO3<double>(withheld.Get("misalignment_rad"));
  const double angle_deg = std::acos(std::clamp(0.5 * (difference.trace() - 1.0), -1.0, 1.0)) * 180.0 / M_PI;
  EXPECT_LT(angle_deg, 0.2);
}

TEST(DiagnosisTest, RejectsInvalidOptionsAndForeignHeldOutFlights) {
  DiagnosisOptions options;
  options.folds = 1;
  EXPECT_FALSE(options.Validate().empty());
  options = DiagnosisOptions{};
  options.candidates = {ParseEffectKind("delay"), ParseEffectKind("delay")};
  EXPECT_FALSE(options.Validate().empty());
  options = DiagnosisOptions{};
  options.alpha = 0.0;
  EXPECT_THROW(Diagnose({}, {}, options), Error);
  EXPECT_THROW(Diagnose({}, {}, DiagnosisOptions{}), Error);
  ProcessedFlight flight = SimulatedFlight(20.0, 26, Effects{});
  ProcessedFlight foreign = flight;
  foreign.vehicle.name = "C";
  DiagnosisOptions fast;
  fast.candidates = {ParseEffectKind("acc_bias")};
  EXPECT_THROW(Diagnose({flight}, {foreign}, fast), Error);
}

// identify's hint: the linear model's residual names the effect a flight carries (to first order,
// in sample), the strongest first, and stays quiet on a clean flight.
TEST(ResidualSignatureTest, NamesTheEffectAFlightCarriesAndNothingOnACleanOne) {
  auto check_of = [](const Effects& effects) {
    const SimulationResult sim = testing::SimulatePreset("B", 30.0, 41, effects);
    return CheckResidualSignature(testing::IdentifySimulated(sim));
  };
  const Check clean = check_of(Effects{});
  EXPECT_EQ(clean.status, CheckStatus::kOk) << clean.message;
  Effects lag;
  lag.Set("motor_tau_s", 0.04);
  const Check with_lag = check_of(lag);
  EXPECT_EQ(with_lag.status, CheckStatus::kWarning);
  // The lag first; a delay fits it as well (the diagnosis's held-out test tells them apart).
  EXPECT_EQ(with_lag.message.find("the residual shows the signature of motor_lag ("), 0u) << with_lag.message;
  EXPECT_NE(with_lag.message.find("--effects motor_lag` estimates it"), std::string::npos) << with_lag.message;
  Effects bias;
  bias.Set("acc_bias", Eigen::Vector3d(0.3, -0.2, 0.2));
  const Check with_bias = check_of(bias);
  EXPECT_EQ(with_bias.status, CheckStatus::kWarning);
  EXPECT_EQ(with_bias.message.find("the residual shows the signature of acc_bias ("), 0u) << with_bias.message;
}

}  // namespace
}  // namespace rotorid

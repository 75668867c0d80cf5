#include "rotorid/io/segmentation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/io/column_map.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = kStandardGravity;

// A synthetic flight at 500 Hz: on the ground (motors off, at rest) until take-off, flying with
// hover commands and some rotation, then on the ground again.
struct FlightShape {
  double duration_s = 20.0;
  double takeoff_s = 3.0;   // <= 0: airborne from the start
  double landing_s = 17.0;  // >= duration: airborne to the end
};

FlightLog Synthetic(const FlightShape& shape = {}) {
  const double dt = 0.002;
  const int n = static_cast<int>(std::lround(shape.duration_s / dt));
  FlightLog log;
  log.source = "synthetic";
  log.t_s.resize(n);
  log.gyro_radps.setZero(n, 3);
  log.acc_mps2.setZero(n, 3);
  log.rotor_radps.setZero(n, 4);
  log.metadata["rotor_signal"] = "command";
  for (int i = 0; i < n; ++i) {
    const double t = 100.0 + i * dt;
    log.t_s[i] = t;
    const double s = t - 100.0;
    const bool flying = s >= shape.takeoff_s && s < shape.landing_s;
    if (flying) {
      log.gyro_radps.row(i) << 0.5 * std::sin(2 * kPi * 1.3 * s), 0.4 * std::cos(2 * kPi * 0.7 * s), 0.2;
      log.acc_mps2.row(i) << 0.3 * std::sin(s), 0.2 * std::cos(s), kG + 1.0 * std::sin(2 * kPi * 0.5 * s);
      for (int r = 0; r < 4; ++r) log.rotor_radps(i, r) = 0.6 + 0.05 * std::sin(2 * kPi * 0.9 * s + r);
    } else {
      log.acc_mps2.row(i) << 0.001 * std::sin(37.0 * i), 0.0, kG;
    }
  }
  return log;
}

int IndexAt(const FlightLog& log, double t) {
  return static_cast<int>(std::lower_bound(log.t_s.data(), log.t_s.data() + log.num_samples(), t) - log.t_s.data());
}

const ExcludedSpan* Find(const Segmentation& s, ExclusionReason reason, double around_t) {
  for (const ExcludedSpan& span : s.excluded) {
    if (span.reason == reason && span.t_begin_s - 0.2 <= around_t && around_t <= span.t_end_s + 0.2) return &span;
  }
  return nullptr;
}

TEST(Segmentation, KeepsTheAirbornePartAndSaysWhy) {
  FlightLog log = Synthetic();
  // A single-sample gyro spike at 108 s, a saturated rotor 111.0..111.3 s.
  log.gyro_radps(IndexAt(log, 108.0), 0) += 5.0;
  for (int i = IndexAt(log, 111.0); i < IndexAt(log, 111.3); ++i) log.rotor_radps(i, 1) = 1.0;
  const Segmentation s = SegmentFlight(log);
  std::cout << s.Report(log) << "\n";

  ASSERT_EQ(s.kept.size(), 3u);
  EXPECT_NEAR(log.t_s[s.kept[0].begin], 104.0, 0.1);
  EXPECT_NEAR(log.t_s[s.kept[0].end - 1], 107.9, 0.01);
  EXPECT_NEAR(log.t_s[s.kept[1].begin], 108.1, 0.01);
  EXPECT_NEAR(log.t_s[s.kept[1].end - 1], 110.95, 0.01);
  EXPECT_NEAR(log.t_s[s.kept[2].begin], 111.35, 0.01);
  EXPECT_NEAR(log.t_s[s.kept[2].end - 1], 116.0, 0.1);

  const ExcludedSpan* ground = Find(s, ExclusionReason::kOnGround, 101.0);
  ASSERT_NE(ground, nullptr);
  EXPECT_EQ(ground->begin, 0);
  EXPECT_NEAR(ground->t_end_s, 103.0, 0.1);
  EXPECT_NE(ground->detail.find("at rest with the rotors below 50% of hover thrust"), std::string::npos);
  EXPECT_NE(Find(s, ExclusionReason::kTakeoff, 103.5), nullptr);
  const ExcludedSpan* spike = Find(s, ExclusionReason::kImpact, 108.0);
  ASSERT_NE(spike, nullptr);
  EXPECT_NEAR(spike->t_begin_s, 107.9, 0.003);
  EXPECT_NEAR(spike->t_end_s, 108.1, 0.003);
  EXPECT_NE(spike->detail.find("peak angular acceleration 25"), std::string::npos) << spike->detail;
  const ExcludedSpan* saturation = Find(s, ExclusionReason::kMotorSaturation, 111.1);
  ASSERT_NE(saturation, nullptr);
  EXPECT_EQ(saturation->detail, "rotor 2 at full command");
  EXPECT_NE(Find(s, ExclusionReason::kLanding, 116.5), nullptr);
  const ExcludedSpan* ground_after = Find(s, ExclusionReason::kOnGround, 119.0);
  ASSERT_NE(ground_after, nullptr);
  EXPECT_EQ(ground_after->end, log.num_samples());

  // Every sample is either kept or in exactly one excluded span.
  std::vector<int> covered(log.num_samples(), 0);
  for (const SampleRange& r : s.kept)
    for (int i = r.begin; i < r.end; ++i) ++covered[i];
  for (const ExcludedSpan& e : s.excluded)
    for (int i = e.begin; i < e.end; ++i) ++covered[i];
  EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; }));

  const std::vector<FlightLog> pieces = KeptSegments(log, s);
  ASSERT_EQ(pieces.size(), 3u);
  EXPECT_EQ(pieces[1].num_samples(), s.kept[1].size());
  EXPECT_EQ(pieces[1].t_s[0], log.t_s[s.kept[1].begin]);
}

TEST(Segmentation, AirborneFromStartToEndKeepsEverything) {
  FlightShape shape;
  shape.takeoff_s = -1;
  shape.landing_s = 1e9;
  const FlightLog log = Synthetic(shape);
  const Segmentation s = SegmentFlight(log);
  ASSERT_EQ(s.kept.size(), 1u);
  EXPECT_EQ(s.kept[0].begin, 0);
  EXPECT_EQ(s.kept[0].end, log.num_samples());
  EXPECT_TRUE(s.excluded.empty());
}

TEST(Segmentation, FreeFallWithMotorsOffIsNotGround) {
  FlightLog log = Synthetic();
  // Motors cut for 0.3 s in flight: the vehicle falls (specific force about 0) and rotates.
  for (int i = IndexAt(log, 109.0); i < IndexAt(log, 109.3); ++i) {
    log.rotor_radps.row(i).setZero();
    log.acc_mps2.row(i) << 0.0, 0.0, 0.5;
  }
  const Segmentation s = SegmentFlight(log);
  EXPECT_EQ(Find(s, ExclusionReason::kOnGround, 109.1), nullptr);
  EXPECT_EQ(s.kept.size(), 1u);
}

TEST(Segmentation, GapsSplitKeptRanges) {
  FlightLog full = Synthetic();
  // Drop 0.2 s of samples at 110 s.
  const int a = IndexAt(full, 110.0), b = IndexAt(full, 110.2);
  FlightLog log = full.Slice(0, a);
  const FlightLog tail = full.Slice(b, full.num_samples());
  const int n = log.num_samples() + tail.num_samples();
  auto cat = [&](auto first, auto second, int cols) {
    Eigen::MatrixXd out(n, cols);
    out << first, second;
    return out;
  };
  log.t_s = cat(log.t_s, tail.t_s, 1);
  log.gyro_radps = cat(log.gyro_radps, tail.gyro_radps, 3);
  log.acc_mps2 = cat(log.acc_mps2, tail.acc_mps2, 3);
  log.rotor_radps = cat(log.rotor_radps, tail.rotor_radps, 4);
  const Segmentation s = SegmentFlight(log);
  ASSERT_EQ(s.kept.size(), 2u);
  const ExcludedSpan* gap = Find(s, ExclusionReason::kLoggingGap, 110.1);
  ASSERT_NE(gap, nullptr);
  EXPECT_EQ(gap->begin, gap->end);
  EXPECT_EQ(gap->detail, "no samples for 0.202 s");
  EXPECT_EQ(s.kept[0].end, gap->begin);
  EXPECT_EQ(s.kept[1].begin, gap->begin);
}

TEST(Segmentation, MocapHeightMarksGroundContactWithMotorsRunning) {
  FlightLog log = Synthetic();
  MocapTrack mocap;
  mocap.position_w_m.setZero(log.num_samples(), 3);
  mocap.bryant_rad.setZero(log.num_samples(), 3);
  for (int i = 0; i < log.num_samples(); ++i) {
    const double s = log.t_s[i] - 100.0;
    // Spinning up on the floor 3..5 s (the IMU already shows motion), then climbing to 1 m.
    mocap.position_w_m(i, 2) = 0.05 + (s < 5.0 ? 0.0 : std::min(1.0, s - 5.0));
    if (s > 16.0) mocap.position_w_m(i, 2) = 0.05 + std::max(0.0, 17.0 - s);
  }
  log.mocap = mocap;
  const Segmentation s = SegmentFlight(log);
  const ExcludedSpan* ground = Find(s, ExclusionReason::kOnGround, 102.0);
  ASSERT_NE(ground, nullptr);
  EXPECT_NEAR(ground->t_end_s, 105.1, 0.01);  // 0.1 m clearance above the resting 0.05 m
  EXPECT_NE(ground->detail.find("motion capture"), std::string::npos);
  ASSERT_FALSE(s.kept.empty());
  EXPECT_NEAR(log.t_s[s.kept[0].begin], 106.1, 0.01);
}

TEST(Segmentation, OptionsAreValidated) {
  SegmentationOptions o;
  EXPECT_EQ(o.Validate(), "");
  o.ground_thrust_fraction = 2.0;
  EXPECT_NE(o.Validate(), "");
  EXPECT_THROW(SegmentFlight(Synthetic(), o), Error);
  EXPECT_EQ(SegmentFlight(FlightLog{}).kept.size(), 0u);
}

// ---- Real flights (through column maps, the decoded CSVs are those of the raw logs) ----

const char* kArplMap = R"(time: {column: t_us, unit: us}
gyro: {columns: [gyro.x, gyro.y, gyro.z], unit: deg/s}
acc: {columns: [acc.x, acc.y, acc.z], unit: g}
rotors: {columns: [motor.m1, motor.m2, motor.m3, motor.m4], unit: pwm}
)";

FlightLog LoadArpl(const std::string& dir, const std::string& name) {
  return ReadMappedCsv(dir + "/csv/" + name + ".csv", ParseColumnMap(kArplMap, "arpl.yaml"), 4);
}

TEST(SegmentationRealData, ArplFlights) {
  const auto dir = testing::SharedDataPath("real/crazyflie-arpl-sysid");
  if (!dir) GTEST_SKIP() << "shared ARPL data not present";

  const FlightLog log10 = LoadArpl(*dir, "log10");
  const Segmentation s10 = SegmentFlight(log10);
  std::cout << "log10: " << s10.Report(log10) << "\n";
  ASSERT_FALSE(s10.kept.empty());
  // Motors start at 31.44 s; the landing impact comes after 68.9 s.
  EXPECT_GE(log10.t_s[s10.kept.front().begin], 32.4);
  EXPECT_LT(log10.t_s[s10.kept.back().end - 1], 68.9);
  EXPECT_GT(s10.kept_duration_s(log10), 34.0);
  EXPECT_NE(Find(s10, ExclusionReason::kImpact, 69.03), nullptr);
  EXPECT_NE(Find(s10, ExclusionReason::kOnGround, 30.0), nullptr);
  EXPECT_NE(Find(s10, ExclusionReason::kOnGround, 75.0), nullptr);

  // log15: the gyro passes 600 deg/s at 74.85 s in a smooth, motor-driven roll oscillation
  // (up to 759 deg/s, angular acceleration below 200 rad/s^2): kept by default, left out with a
  // 600 deg/s gyro limit.
  const FlightLog log15 = LoadArpl(*dir, "log15");
  const Segmentation s15 = SegmentFlight(log15);
  std::cout << "log15: " << s15.Report(log15) << "\n";
  EXPECT_GE(log15.t_s[s15.kept.front().begin], 51.7);
  EXPECT_LT(log15.t_s[s15.kept.back().end - 1], 93.6);
  EXPECT_NE(Find(s15, ExclusionReason::kImpact, 93.7), nullptr);
  const int at_7485 = IndexAt(log15, 74.86);
  EXPECT_TRUE(std::any_of(s15.kept.begin(), s15.kept.end(),
                          [&](const SampleRange& r) { return r.begin <= at_7485 && at_7485 < r.end; }));
  SegmentationOptions strict;
  strict.gyro_limit_radps = 600.0 * kPi / 180.0;
  const Segmentation s15_strict = SegmentFlight(log15, strict);
  std::cout << "log15 (gyro limit 600 deg/s): " << s15_strict.Report(log15) << "\n";
  const ExcludedSpan* limit = Find(s15_strict, ExclusionReason::kGyroLimit, 74.86);
  ASSERT_NE(limit, nullptr);
  EXPECT_LE(limit->t_begin_s, 74.76);

  // log16: a crash at 39.35 s, on the ground until about 44 s, then a second flight.
  const FlightLog log16 = LoadArpl(*dir, "log16");
  const Segmentation s16 = SegmentFlight(log16);
  std::cout << "log16: " << s16.Report(log16) << "\n";
  EXPECT_NE(Find(s16, ExclusionReason::kImpact, 39.36), nullptr);
  EXPECT_NE(Find(s16, ExclusionReason::kOnGround, 42.0), nullptr);
  for (const SampleRange& r : s16.kept) {
    EXPECT_FALSE(log16.t_s[r.begin] < 39.5 && log16.t_s[r.end - 1] > 39.2) << "kept range spans the crash";
  }
}

TEST(SegmentationRealData, NanobenchFlightsWithSaturatedMotors) {
  const auto dir = testing::SharedDataPath("real/nanobench-cf21");
  if (!dir) GTEST_SKIP() << "shared NanoBench data not present";
  const ColumnMap map = ReadColumnMap(testing::SourceDir() + "/data/column_maps/nanobench_cf21.yaml");
  for (const std::string name : {"B2_circle_fast_rep2", "B3_figure8_fast_rep2", "B5_helix_fast_rep1",
                                 "B8_star_fast_rep1", "B10_lissajous_fast_rep1"}) {
    SCOPED_TRACE(name);
    const FlightLog log = ReadMappedCsv(*dir + "/" + name + ".csv", map, 4);
    const Segmentation s = SegmentFlight(log);
    int saturated_spans = 0, saturated_samples = 0;
    for (const ExcludedSpan& e : s.excluded) {
      if (e.reason == ExclusionReason::kMotorSaturation) {
        ++saturated_spans;
        saturated_samples += e.end - e.begin;
      }
    }
    int full_scale = 0;  // samples where a kept sample has a motor at 65535
    for (const SampleRange& r : s.kept) {
      for (int i = r.begin; i < r.end; ++i) full_scale += log.rotor_radps.row(i).maxCoeff() >= 1.0 ? 1 : 0;
    }
    const double t0 = log.t_s[0];
    std::cout << name << " (t from " << t0 << "): " << s.Report(log) << "\n";
    EXPECT_EQ(full_scale, 0);
    EXPECT_NE(Find(s, ExclusionReason::kOnGround, t0 + 1.0), nullptr);
    EXPECT_NE(Find(s, ExclusionReason::kOnGround, log.t_s[log.num_samples() - 1] - 1.0), nullptr);
    EXPECT_GT(s.kept_duration_s(log), name == "B3_figure8_fast_rep2" ? 5.0 : 20.0);
    // B5 never reaches full scale in flight (SOURCE.md: 0 samples at 65535); a bounce at
    // touch-down reaches 65490. B3 saturates heavily (1125 samples at 65535).
    if (name == "B5_helix_fast_rep1") {
      EXPECT_LE(saturated_samples, 5);
    }
    if (name == "B3_figure8_fast_rep2") {
      EXPECT_GT(saturated_samples, 1000);
    }
    (void)saturated_spans;
  }
}

TEST(SegmentationRealData, ImrcFlightsAreAirborneThroughout) {
  const auto dir = testing::SharedDataPath("real/crazyflie-imrc-rpm");
  if (!dir) GTEST_SKIP() << "shared IMRC data not present";
  const ColumnMap map = ParseColumnMap(R"(time: {column: t_us, unit: us}
gyro: {columns: [gyro.x, gyro.y, gyro.z], unit: deg/s}
acc: {columns: [acc.x, acc.y, acc.z], unit: g}
rotors: {columns: [rpm.m1, rpm.m2, rpm.m3, rpm.m4], unit: rpm}
)",
                                       "imrc.yaml");
  for (const std::string name : {"brushed/csv/jana01", "brushed/csv/jana04", "brushless/csv/eckart34"}) {
    SCOPED_TRACE(name);
    const FlightLog log = ReadMappedCsv(*dir + "/" + name + ".csv", map, 4);
    const Segmentation s = SegmentFlight(log);
    std::cout << name << ": " << s.Report(log) << "\n";
    EXPECT_GT(s.kept_samples(), 0.98 * log.num_samples());
  }
}

}  // namespace
}  // namespace rotorid

// The pieces of the diagnosis' effect selection on hand-made held-out gaps and residuals: which
// candidates are refined, which kept effects the backward pass drops, and which rivals the data
// cannot tell from a kept effect.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "diagnosis/candidate_kinds.h"
#include "diagnosis/confounding.h"
#include "diagnosis/selection.h"
#include "diagnosis/verdicts.h"
#include "rotorid/model/parameters.h"

namespace rotorid::internal {
namespace {

using rotorid::testing::kAccBias;
using rotorid::testing::kDelay;
using rotorid::testing::kGyroBias;
using rotorid::testing::kMisalignment;
using rotorid::testing::kMotorLag;

constexpr int kEntries = 6000;  // held-out residual entries of every hand-made gap

HeldOutGap GapWithSsr(double whitened_ssr) {
  HeldOutGap gap;
  gap.whitened_ssr = whitened_ssr;
  gap.entries = kEntries;
  gap.autocorrelation_factor = 1.0;
  return gap;
}

ModelRecord RecordOf(std::vector<EffectKind> kinds, double whitened_ssr) {
  ModelRecord record;
  record.mask = MaskOf(kinds);
  record.gap = GapWithSsr(whitened_ssr);
  return record;
}

// Refines the models of a table (by whitened SSR, fold starts kept as the fold fits) and fails
// the others; remembers what it was asked.
class TableFitter : public ModelFitter {
 public:
  explicit TableFitter(std::map<EffectMask, double> ssr) : ssr_(std::move(ssr)) {}

  std::vector<ModelRecord> Fit(const std::vector<EffectMask>& masks,
                               const std::vector<std::vector<Effects>>& initial) override {
    std::vector<ModelRecord> records;
    for (size_t m = 0; m < masks.size(); ++m) {
      requested.push_back(masks[m]);
      starts.push_back(initial[m]);
      ModelRecord record;
      record.mask = masks[m];
      const auto found = ssr_.find(masks[m]);
      if (found == ssr_.end()) {
        record.ok = false;
        record.error = "no convergence";
      } else {
        record.gap = GapWithSsr(found->second);
        record.fold_effects = initial[m];
      }
      records.push_back(std::move(record));
    }
    return records;
  }

  std::vector<EffectMask> requested;
  std::vector<std::vector<Effects>> starts;

 private:
  std::map<EffectMask, double> ssr_;
};

// F of an added effect with q parameters on the hand-made gaps (autocorrelation factor 1).
double FStatistic(double without, double with, int q) { return ((without - with) / q) / (with / (kEntries - q)); }

struct SelectionFixture {
  explicit SelectionFixture(std::map<EffectMask, double> fittable) : fitter(std::move(fittable)) {}
  DiagnosisOptions options;  // alpha 1e-3, shrink floor 0.3 %
  TableFitter fitter;
  std::vector<std::string> warnings;
  Vehicle vehicle;
  SelectionContext context{options, fitter, warnings, {}, vehicle};

  void Add(ModelRecord record) { context.records[record.mask] = std::move(record); }
};

TEST(BackwardEliminationTest, DropsAnEarlyEffectThatLaterOnesMadeRedundant) {
  // acc_bias went in first (6000 -> 5400), the delay on top of it (-> 4000); the delay alone
  // reaches 4001, so the acc bias adds 1 of 4001 (0.025 %, F = 0.5) on top of it.
  SelectionFixture f({{MaskOf({kDelay}), 4001.0}});
  f.Add(RecordOf({}, 6000.0));
  f.Add(RecordOf({kAccBias}, 5400.0));
  ModelRecord both = RecordOf({kAccBias, kDelay}, 4000.0);
  for (double delay_s : {0.02, 0.03}) {
    Effects fold;
    fold.Set(kAccBias, Eigen::Vector3d(0.1, 0.2, 0.3));
    fold.Set(kDelay, Eigen::VectorXd::Constant(1, delay_s));
    both.fold_effects.push_back(fold);
  }
  f.Add(both);

  const BackwardElimination result = EliminateBackward(&f.context, {kAccBias, kDelay});

  EXPECT_EQ(result.kept, std::vector<EffectKind>{kDelay});
  ASSERT_EQ(result.dropped.size(), 1u);
  const DroppedEffect& dropped = result.dropped.front();
  EXPECT_EQ(dropped.kind, kAccBias);
  EXPECT_EQ(dropped.others, MaskOf({kDelay}));
  EXPECT_FALSE(dropped.test.significant);
  EXPECT_EQ(dropped.test.added_parameters, 3);
  EXPECT_NEAR(dropped.test.shrink_pct, 100.0 / 4001.0, 1e-12);
  EXPECT_NEAR(dropped.test.f_statistic, FStatistic(4001.0, 4000.0, 3), 1e-9);
  EXPECT_GT(dropped.test.p_value, 0.5);
  // The delay-only model was refined once, warm-started from the joint fit without the acc bias.
  ASSERT_EQ(f.fitter.requested, std::vector<EffectMask>{MaskOf({kDelay})});
  ASSERT_EQ(f.fitter.starts.front().size(), 2u);
  EXPECT_EQ(f.fitter.starts.front()[0].Scalar(kDelay), 0.02);
  EXPECT_EQ(f.fitter.starts.front()[1].Scalar(kDelay), 0.03);
  EXPECT_EQ(f.fitter.starts.front()[0].Get(kAccBias).norm(), 0.0);
  EXPECT_TRUE(f.warnings.empty());
}

TEST(BackwardEliminationTest, KeepsEffectsThatRemainSignificantOnTopOfTheOthers) {
  // Without the acc bias the residual is 4500: it removes 11 % on top of the delay; without the
  // delay 5400: the delay removes 26 % on top of the acc bias.
  SelectionFixture f({{MaskOf({kDelay}), 4500.0}});
  f.Add(RecordOf({}, 6000.0));
  f.Add(RecordOf({kAccBias}, 5400.0));
  f.Add(RecordOf({kAccBias, kDelay}, 4000.0));

  const BackwardElimination result = EliminateBackward(&f.context, {kAccBias, kDelay});

  EXPECT_EQ(result.kept, (std::vector<EffectKind>{kAccBias, kDelay}));
  EXPECT_TRUE(result.dropped.empty());
  EXPECT_EQ(f.fitter.requested, std::vector<EffectMask>{MaskOf({kDelay})});
}

TEST(BackwardEliminationTest, RestartsAfterADropAndSkipsModelsThatFailed) {
  // Three kept effects. Without acc_bias the model fails to refine (a warning; acc_bias stays
  // untested in that pass); without gyro_bias the residual barely grows: dropped. The pass restarts:
  // on top of the delay alone acc_bias removes 100 of 4100 (2.4 %), and the delay on top of acc_bias
  // 1399.8 of 5400: both stay.
  SelectionFixture f({{MaskOf({kAccBias, kDelay}), 4000.2}, {MaskOf({kDelay}), 4100.0}});
  f.Add(RecordOf({}, 6000.0));
  f.Add(RecordOf({kAccBias}, 5400.0));
  f.Add(RecordOf({kAccBias, kGyroBias, kDelay}, 4000.0));

  const BackwardElimination result = EliminateBackward(&f.context, {kAccBias, kGyroBias, kDelay});

  EXPECT_EQ(result.kept, (std::vector<EffectKind>{kAccBias, kDelay}));
  ASSERT_EQ(result.dropped.size(), 1u);
  EXPECT_EQ(result.dropped.front().kind, kGyroBias);
  EXPECT_EQ(result.dropped.front().others, MaskOf({kAccBias, kDelay}));
  EXPECT_NEAR(result.dropped.front().test.shrink_pct, 100.0 * 0.2 / 4000.2, 1e-12);
  EXPECT_EQ(f.fitter.requested,
            (std::vector<EffectMask>{MaskOf({kGyroBias, kDelay}), MaskOf({kAccBias, kDelay}), MaskOf({kDelay})}));
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_EQ(f.warnings.front(), "model delay, gyro_bias: refinement failed (no convergence)");
}

TEST(CandidatesWorthRefiningTest, ShrinkFloorAndRivalFractionOfTheBest) {
  // Floor: 0.5 x 0.3 % = 0.15 %; rivals: 0.7 x 10 % = 7 %.
  DiagnosisOptions options;
  TestedCandidates tested;
  tested[kDelay].screening.shrink_pct = 10.0;
  tested[kMotorLag].screening.shrink_pct = 7.0;
  tested[kAccBias].screening.shrink_pct = 6.9;
  tested[kGyroBias].screening.shrink_pct = 0.1;
  EXPECT_EQ(CandidatesWorthRefining({kGyroBias, kAccBias, kMotorLag, kDelay}, tested, options),
            (std::vector<EffectKind>{kMotorLag, kDelay}));
  // Without a strong leader the floor decides: 0.15 % passes, 0.1 % does not.
  tested[kDelay].screening.shrink_pct = 0.15;
  EXPECT_EQ(CandidatesWorthRefining({kGyroBias, kDelay}, tested, options), std::vector<EffectKind>{kDelay});
}

EffectTest Significant(double shrink_pct) {
  EffectTest test;
  test.shrink_pct = shrink_pct;
  test.significant = true;
  return test;
}

ForwardStep StepOf(EffectKind added, std::vector<std::pair<EffectKind, EffectTest>> refined) {
  ForwardStep step;
  step.selection.added = added;
  for (const auto& [kind, test] : refined)
    if (kind == added) step.selection.test = test;
  step.refined = std::move(refined);
  return step;
}

TEST(ConfoundingTest, RivalsAreSignificantWithHalfTheShrinkOfAKeptEffect) {
  EffectTest not_significant = Significant(15.0);
  not_significant.significant = false;
  // Step 1 selected acc_bias (dropped later); step 2 the delay on top of it.
  const std::vector<ForwardStep> steps = {
      StepOf(kAccBias, {{kAccBias, Significant(10.0)}, {kGyroBias, Significant(9.0)}}),
      StepOf(kDelay, {{kMotorLag, Significant(10.0)},
                      {kDelay, Significant(20.0)},
                      {kGyroBias, Significant(9.9)},
                      {kMisalignment, not_significant}})};
  const std::vector<Rival> rivals = FindRivals(steps, MaskOf({kDelay}));
  ASSERT_EQ(rivals.size(), 1u);
  EXPECT_EQ(rivals[0].selected, kDelay);
  EXPECT_EQ(rivals[0].other, kMotorLag);
  EXPECT_EQ(rivals[0].base, MaskOf({kAccBias}));  // the dropped effect was in the model at that step
  EXPECT_EQ(rivals[0].selected_test.shrink_pct, 20.0);
  EXPECT_EQ(rivals[0].other_test.shrink_pct, 10.0);
  // A rival that is kept itself is none.
  EXPECT_TRUE(FindRivals(steps, MaskOf({kDelay, kMotorLag})).empty());
}

// One held-out segment of flight 0, every component scored, with residual `per_row[r]` in every
// component of row r.
HeldOutResidual UniformResidual(const Eigen::VectorXd& per_row) {
  HeldOutResidual residual;
  residual.flight = {0};
  FlightResidual segment;
  segment.residual = per_row.replicate(1, kNumWrenchComponents);
  segment.rotor_wrench = Eigen::MatrixXd::Zero(per_row.size(), kNumWrenchComponents);
  residual.segments = {segment};
  residual.scored = {{true, true, true, true, true, true}};
  return residual;
}

// Two scalar models whose held-out residuals differ by 0.02 in every entry (`other` worse, by a
// consistent amount: a large paired t), with fold fits delay 20 and 30 ms, motor lag 30 and 50 ms.
struct RivalFixture {
  RivalFixture() {
    Eigen::VectorXd rows(400);
    for (Eigen::Index r = 0; r < rows.size(); ++r) rows[r] = 1.0 + 0.05 * static_cast<double>(r % 3);
    with_delay = ModelRecord{MaskOf({kDelay}), true, "", {}, {}, UniformResidual(rows), {}};
    with_lag = ModelRecord{MaskOf({kMotorLag}), true, "", {}, {}, UniformResidual((rows.array() + 0.02).matrix()), {}};
    for (const auto& [delay_s, tau_s] : {std::pair{0.02, 0.03}, std::pair{0.03, 0.05}}) {
      with_delay.fold_effects.emplace_back().Set(kDelay, Eigen::VectorXd::Constant(1, delay_s));
      with_lag.fold_effects.emplace_back().Set(kMotorLag, Eigen::VectorXd::Constant(1, tau_s));
    }
  }
  Rival RivalWithShrinks(double delay_pct, double lag_pct) const {
    return {kDelay, kMotorLag, 0, Significant(delay_pct), Significant(lag_pct), std::nullopt};
  }
  ModelRecord with_delay, with_lag;
  // Unit residual RMS, no rotor wrench: the residuals enter the comparison as they are.
  const HeldOutScales scales{Eigen::MatrixXd::Ones(1, kNumWrenchComponents),
                             Eigen::MatrixXd::Zero(1, kNumWrenchComponents)};
  const double alpha = 1e-3;
};

std::string Alone(EffectKind kind, double value) { return kind->Format(Eigen::VectorXd::Constant(1, value), {}); }

TEST(ConfoundingTest, SignificantButPracticallyEqualShrinksCannotTellThemApart) {
  const RivalFixture f;
  // 20 % and 18.5 %: closer than a tenth of the larger.
  const ConfoundedEffects c = CompareRival(f.RivalWithShrinks(20.0, 18.5), f.with_delay, f.with_lag, f.scales, f.alpha);
  EXPECT_EQ(c.selected, kDelay);
  EXPECT_EQ(c.other, kMotorLag);
  EXPECT_EQ(c.selected_shrink_pct, 20.0);
  EXPECT_EQ(c.other_shrink_pct, 18.5);
  EXPECT_GT(c.t_statistic, 10.0);
  EXPECT_LT(c.p_value, f.alpha);
  EXPECT_FALSE(c.distinguishable);
  EXPECT_EQ(c.note.rfind("motor_lag alone removes 18.5 % of the held-out residual, delay 20.0 %; they differ by less "
                         "than 10 % of that (t = ",
                         0),
            0u)
      << c.note;
  // What each fits alone: the mean of its fold fits.
  const std::string alone =
      "; alone, delay = " + Alone(kDelay, 0.025) + " and motor_lag = " + Alone(kMotorLag, 0.04) + " fit as well";
  EXPECT_NE(c.note.find(alone), std::string::npos) << c.note;
}

TEST(ConfoundingTest, SignificantAndPracticallyDifferentShrinksTellThemApart) {
  const RivalFixture f;
  // 20 % and 17.9 %: just beyond a tenth of the larger.
  const ConfoundedEffects c = CompareRival(f.RivalWithShrinks(20.0, 17.9), f.with_delay, f.with_lag, f.scales, f.alpha);
  EXPECT_TRUE(c.distinguishable);
  EXPECT_NE(c.note.find("; delay fits the held-out rows significantly better (t = "), std::string::npos) << c.note;
  EXPECT_EQ(c.note.find("alone,"), std::string::npos) << c.note;
  // The same residuals the other way round: the rival fits better, t < 0, not significant.
  const ConfoundedEffects reversed =
      CompareRival(f.RivalWithShrinks(20.0, 17.9), f.with_lag, f.with_delay, f.scales, f.alpha);
  EXPECT_NEAR(reversed.t_statistic, -c.t_statistic, 1e-9 * c.t_statistic);
  EXPECT_GT(reversed.p_value, 0.5);
  EXPECT_FALSE(reversed.distinguishable);
  EXPECT_NE(reversed.note.find("; the difference is not significant (t = -"), std::string::npos) << reversed.note;
}

TEST(ConfoundingTest, TwinsTheJointFitAtHalfTheCutoffSeparatesAreDistinguishable) {
  const RivalFixture f;
  Rival rival = f.RivalWithShrinks(20.0, 18.5);  // practically equal on the held-out rows
  rival.separation = TimingSeparation{kDelay, "delay = 10 +- 0.2 ms, motor_lag = 0.1 +- 0.2 ms", 5.0};
  const ConfoundedEffects separated = CompareRival(rival, f.with_delay, f.with_lag, f.scales, f.alpha);
  EXPECT_TRUE(separated.distinguishable);
  EXPECT_NE(separated.note.find("; the held-out rows cannot tell them apart (t = "), std::string::npos)
      << separated.note;
  EXPECT_NE(separated.note.find("refined together at half the low-pass cut-off (5.0 Hz), below the controller's "
                                "reply to sensor noise, delay = 10 +- 0.2 ms, motor_lag = 0.1 +- 0.2 ms: delay "
                                "carries the timing"),
            std::string::npos)
      << separated.note;

  // Both keep a share: still confounded, with the joint values.
  rival.separation->decided = nullptr;
  const ConfoundedEffects mixed = CompareRival(rival, f.with_delay, f.with_lag, f.scales, f.alpha);
  EXPECT_FALSE(mixed.distinguishable);
  EXPECT_NE(mixed.note.find("these flights cannot tell delay and motor_lag apart"), std::string::npos) << mixed.note;
  EXPECT_NE(mixed.note.find("(5.0 Hz), delay = 10 +- 0.2 ms, motor_lag = 0.1 +- 0.2 ms: both carry a share"),
            std::string::npos)
      << mixed.note;
}

TEST(ConfoundingTest, LargestCorrelationIsBetweenTheTwoEffectsOnly) {
  EffectSubsetFit fit;
  fit.labels = {"delay_s", "acc_bias_x", "acc_bias_y", "acc_bias_z"};
  fit.column_kind = {kDelay, kAccBias, kAccBias, kAccBias};
  fit.correlation = Eigen::MatrixXd::Identity(4, 4);
  fit.correlation(1, 0) = fit.correlation(0, 1) = 0.5;
  fit.correlation(2, 0) = fit.correlation(0, 2) = -0.8;
  fit.correlation(1, 2) = fit.correlation(2, 1) = 0.95;  // within acc_bias: not a confounding
  ConfoundedEffects c;
  c.selected = kAccBias;
  c.other = kDelay;
  SetLargestCorrelation(fit, &c);
  ASSERT_TRUE(c.correlation.has_value());
  EXPECT_EQ(*c.correlation, -0.8);
  EXPECT_EQ(c.correlated_labels, "acc_bias_y / delay_s");
}

TEST(ConfoundingTest, OnlyIndistinguishableRivalsBecomeConfounded) {
  std::vector<EffectVerdict> verdicts(3);
  verdicts[0].kind = kDelay;
  verdicts[0].status = "selected";
  verdicts[1].kind = kMotorLag;
  verdicts[2].kind = kGyroBias;
  verdicts[1].status = verdicts[2].status = "not significant";
  ConfoundedEffects lag, gyro;
  lag.selected = gyro.selected = kDelay;
  lag.other = kMotorLag;
  gyro.other = kGyroBias;
  gyro.distinguishable = true;
  MarkConfounded({lag, gyro}, &verdicts);
  EXPECT_EQ(verdicts[0].status, "selected");
  EXPECT_EQ(verdicts[0].confounded_with, (std::vector<EffectKind>{kMotorLag, kGyroBias}));
  EXPECT_EQ(verdicts[1].status, "confounded");
  EXPECT_EQ(verdicts[1].confounded_with, std::vector<EffectKind>{kDelay});
  EXPECT_EQ(verdicts[2].status, "not significant");
  EXPECT_EQ(verdicts[2].confounded_with, std::vector<EffectKind>{kDelay});
}

}  // namespace
}  // namespace rotorid::internal

// The verdict text on hand-made verdicts: a kept effect whose final fit ended on a bound is named
// with the bound, in its note and on its own line of the verdict.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "diagnosis/candidate_kinds.h"
#include "diagnosis/verdict_text.h"
#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {
namespace {

using rotorid::testing::kAccBias;
using rotorid::testing::kDelay;
using rotorid::testing::kGyroBias;
using rotorid::testing::kMotorLag;

Eigen::VectorXd Scalar(double value) { return Eigen::VectorXd::Constant(1, value); }

TEST(OnBoundStatementTest, NamesTheEffectOrCoordinateAndItsBound) {
  EXPECT_EQ(OnBoundStatement(kMotorLag, Scalar(0.3)),
            "motor_lag = 300 ms is on its upper bound (300 ms): the data push it further; treat it as absorbing "
            "something else");
  EXPECT_EQ(OnBoundStatement(kDelay, Scalar(-0.1)),
            "delay = -100 ms is on its lower bound (-100 ms): the data push it further; treat it as absorbing "
            "something else");
  // Bounds of +-2 m/s^2: only the coordinate on one is named.
  EXPECT_EQ(OnBoundStatement(kAccBias, Eigen::Vector3d(0.1, 2.0, -0.3)),
            "acc_bias_y = 2 m/s^2 is on its upper bound (2 m/s^2): the data push it further; treat it as absorbing "
            "something else");
  EXPECT_EQ(OnBoundStatement(kAccBias, Eigen::Vector3d(-2.0, 2.0, 0.5)),
            "acc_bias_x = -2 m/s^2 is on its lower bound (-2 m/s^2), acc_bias_y = 2 m/s^2 is on its upper bound "
            "(2 m/s^2): the data push them further; treat them as absorbing something else");
}

// The detectable size of an absent effect is computed with the selected effects in the model; the
// note says so, since they may hide part of it.
TEST(VerdictNoteTest, DetectableSizeIsStatedGivenTheSelectedEffects) {
  EffectVerdict v;
  v.kind = kGyroBias;
  v.status = "not significant";
  v.value = Eigen::Vector3d(0.001, 0.0, 0.0);
  v.detectable_above = Eigen::Vector3d(0.06, 0.06, 0.03);
  const DiagnosisOptions options;
  const std::string alone = VerdictNote(v, options, {});
  EXPECT_NE(alone.find("not detected; this data would reveal it above"), std::string::npos) << alone;
  EXPECT_EQ(alone.find("in the model"), std::string::npos) << alone;
  const std::string given = VerdictNote(v, options, {kMotorLag, kAccBias});
  EXPECT_NE(given.find("(with motor_lag, acc_bias in the model)"), std::string::npos) << given;
  v.test.screened = true;  // not refined: the screening's note carries the same condition
  EXPECT_NE(VerdictNote(v, options, {kDelay}).find("(with delay in the model)"), std::string::npos);
}

EffectVerdict Verdict(EffectKind kind, bool selected, const Eigen::VectorXd& value, const std::string& note) {
  EffectVerdict v;
  v.kind = kind;
  v.selected = selected;
  v.status = selected ? "selected" : "not significant";
  v.value = value;
  v.note = note;
  return v;
}

TEST(AddBoundNotesTest, OnlyKeptEffectsOnABoundGetTheStatement) {
  std::vector<EffectVerdict> verdicts = {
      Verdict(kMotorLag, true, Scalar(0.3), "held-out gap shrinks 58.9 %"),
      Verdict(kDelay, true, Scalar(0.008), "held-out gap shrinks 0.2 %"),
      Verdict(kAccBias, false, Eigen::Vector3d(0.0, 2.0, 0.0), "not significant"),
  };
  AddBoundNotes({kMotorLag, kAccBias}, &verdicts);
  EXPECT_EQ(verdicts[0].note,
            "held-out gap shrinks 58.9 %; motor_lag = 300 ms is on its upper bound (300 ms): the data push it "
            "further; treat it as absorbing something else");
  EXPECT_EQ(verdicts[1].note, "held-out gap shrinks 0.2 %");
  EXPECT_EQ(verdicts[0].bound_note, verdicts[0].note.substr(verdicts[0].note.find("; ") + 2));
  EXPECT_EQ(verdicts[1].bound_note, "");
  EXPECT_EQ(verdicts[2].note, "not significant");
}

TEST(WhichTextTest, KeptEffectOnABoundHasItsOwnLine) {
  Diagnosis d;
  d.selected = {kMotorLag, kDelay};
  d.ranking = {
      Verdict(kMotorLag, true, Scalar(0.3), "held-out gap shrinks 58.9 %"),
      Verdict(kDelay, true, Scalar(0.008), "held-out gap shrinks 0.2 %"),
      Verdict(kGyroBias, false, Eigen::Vector3d::Zero(), "not refined"),
  };
  AddBoundNotes({kMotorLag}, &d.ranking);
  d.ranking[0].std = Scalar(1e-4);
  d.ranking[0].test.f_statistic = 52.04;
  d.ranking[0].test.p_value = 1e-5;
  d.ranking[0].test.shrink_pct = 58.91;
  d.ranking[1].std = Scalar(4e-4);
  d.ranking[1].test.f_statistic = 7.3;
  d.ranking[1].test.p_value = 6.9e-3;
  d.ranking[1].test.shrink_pct = 0.2;
  EXPECT_EQ(WhichText(d),
            "which: motor_lag = 300 +- 0.1 ms (F = 52.0, p = 1.0e-05; held-out gap shrinks 58.9 %)\n"
            "       motor_lag = 300 ms is on its upper bound (300 ms): the data push it further; treat it as "
            "absorbing something else\n"
            "     + delay = 8 +- 0.4 ms (F = 7.3, p = 6.9e-03; held-out gap shrinks 0.2 %)\n"
            "       gyro_bias: not refined\n");
}

}  // namespace
}  // namespace rotorid::internal

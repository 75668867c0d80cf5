// The verdict text on hand-made verdicts: an effect whose final fit ended on a bound is named with
// the bound in its "implausible" note; the detectable size is stated given the selected effects.

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "diagnosis/candidate_kinds.h"
#include "diagnosis/verdict_text.h"
#include "diagnosis/verdicts.h"
#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {
namespace {

using rotorid::testing::kAccBias;
using rotorid::testing::kDelay;
using rotorid::testing::kGyroBias;
using rotorid::testing::kMisalignment;
using rotorid::testing::kMotorLag;

Eigen::VectorXd Scalar(double value) { return Eigen::VectorXd::Constant(1, value); }

TEST(OnBoundStatementTest, NamesTheEffectOrCoordinateAndItsBound) {
  EXPECT_EQ(OnBoundStatement(kMotorLag, Scalar(0.3)),
            "motor_lag = 300 ms is on its upper bound (300 ms): the data push it further");
  EXPECT_EQ(OnBoundStatement(kDelay, Scalar(-0.1)),
            "delay = -100 ms is on its lower bound (-100 ms): the data push it further");
  // Bounds of +-2 m/s^2: only the coordinate on one is named.
  EXPECT_EQ(OnBoundStatement(kAccBias, Eigen::Vector3d(0.1, 2.0, -0.3)),
            "acc_bias_y = 2 m/s^2 is on its upper bound (2 m/s^2): the data push it further");
  EXPECT_EQ(OnBoundStatement(kAccBias, Eigen::Vector3d(-2.0, 2.0, 0.5)),
            "acc_bias_x = -2 m/s^2 is on its lower bound (-2 m/s^2), acc_bias_y = 2 m/s^2 is on its upper bound "
            "(2 m/s^2): the data push them further");
  // A delay on the bound of a narrower search range than its descriptor's: the effect is named.
  EXPECT_EQ(OnBoundStatement(kDelay, Scalar(0.04)),
            "delay ended on a bound of its search range: the data push it further");
}

// A misalignment about z beyond 3 std beside a discarded I_xy is said to be possibly that product of
// inertia (the independent simulator's A flights); about x, with I_yz estimated, or within 3 std: nothing.
TEST(DiscardedProductStatementTest, NamesTheProductOfInertiaAMisalignmentMayStandFor) {
  EffectVerdict v;
  v.kind = kMisalignment;
  v.value = Eigen::Vector3d(0.0, 0.001, -0.0042);
  v.std = Eigen::Vector3d(1e-4, 1e-4, 5e-4);
  DiscardedParameter product;
  product.name = "A.I_xy";
  product.value = 9.93e-5;
  product.std = 1.13e-5;
  product.rel_std_pct = 11.4;
  const std::string statement = DiscardedProductStatement(v, {product});
  EXPECT_EQ(statement,
            "its z coordinate (-0.241 +- 0.029 deg) mixes the rows the discarded A.I_xy couples (9.93e-05 +- 1.1e-05 "
            "kg m^2 when dropped at 11.4 % std, held at 0): it may be that product of inertia rather than an IMU "
            "rotation");
  v.value[2] = -0.001;  // within 3 std
  EXPECT_EQ(DiscardedProductStatement(v, {product}), "");
  v.value[2] = -0.0042;
  product.name = "A.I_yz";  // the y coordinate (10 std) mixes x and z: I_xz, not discarded here
  EXPECT_EQ(DiscardedProductStatement(v, {product}), "");
  v.kind = kAccBias;
  product.name = "A.I_xy";
  EXPECT_EQ(DiscardedProductStatement(v, {product}), "");
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
  // A coordinate without a column in the scored rows is revealed by no size (not "above 0").
  v.detectable_above[0] = std::numeric_limits<double>::infinity();
  EXPECT_NE(VerdictNote(v, options, {}).find("would reveal it above (unobservable, 0.06, 0.03) rad/s"),
            std::string::npos)
      << VerdictNote(v, options, {});
}

// With nothing selected, the "which" line qualifies "the model explains these flights as well as the
// candidates can" when a candidate acts mostly where nothing is scored, and the note says why.
TEST(VerdictNoteTest, NothingSelectedNamesTheCandidatesActingWhereNothingIsScored) {
  Diagnosis d;
  EffectVerdict v;
  v.kind = kGyroBias;
  v.status = "not significant";
  v.value = Eigen::Vector3d::Zero();
  v.detectable_above = Eigen::Vector3d(0.06, 0.06, 0.03);
  v.note = VerdictNote(v, DiagnosisOptions(), {});
  d.ranking.push_back(v);
  const std::string plain = WhichText(d);
  EXPECT_NE(plain.find("as well as the candidates can\n"), std::string::npos) << plain;
  v.unscored = "but 61 % of gyro_bias_y's signature lies in Mz, which no test here scores";
  v.note = VerdictNote(v, DiagnosisOptions(), {});
  EXPECT_NE(v.note.find("rad/s; but 61 % of gyro_bias_y's signature lies in Mz"), std::string::npos) << v.note;
  d.ranking = {v};
  const std::string qualified = WhichText(d);
  EXPECT_NE(qualified.find("as well as the candidates can in the components it scores (gyro_bias: mostly in one "
                           "it does not score, below)"),
            std::string::npos)
      << qualified;
}

// A selected effect whose every estimated coordinate is within 2 std of zero says that its size is
// not determined (ARPL log10's thrust scales); a determined one, or a held coordinate, does not.
TEST(VerdictNoteTest, ASelectedEffectOfUndeterminedSizeSaysSo) {
  EffectVerdict v;
  v.kind = kAccBias;
  v.status = "selected";
  v.test.shrink_pct = 8.0;
  v.value = Eigen::Vector3d(0.038, -0.059, 0.009);
  v.std = Eigen::Vector3d(0.082, 0.078, 0.080);
  EXPECT_EQ(VerdictNote(v, DiagnosisOptions(), {}),
            "held-out gap shrinks 8.0 %; its size is not determined (every coordinate within 2 std of zero): the "
            "flights fix what it removes, not its value");
  v.value[1] = -0.2;  // one coordinate determined
  EXPECT_EQ(VerdictNote(v, DiagnosisOptions(), {}), "held-out gap shrinks 8.0 %");
  v.value = Eigen::Vector3d(0.01, 0.01, 0.5);
  v.std = Eigen::Vector3d(0.1, 0.1, 0.0);  // z held: only x, y count
  EXPECT_NE(VerdictNote(v, DiagnosisOptions(), {}).find("not determined"), std::string::npos);
}

// An effect the final fit left on its bound is not selected: its note says implausible, with the
// bound, and the verdict's "which" lists it with the other rejected candidates.
TEST(VerdictNoteTest, AnEffectOnItsBoundIsImplausible) {
  EffectVerdict v;
  v.kind = kAccBias;
  v.status = "implausible";
  v.value = Eigen::Vector3d(-0.01, -0.18, 2.0);
  v.implausible = OnBoundStatement(kAccBias, v.value) + " (refined on all identification data)";
  v.test.shrink_pct = 8.66;
  v.tested_on_top_of = {kMotorLag};
  EXPECT_EQ(VerdictNote(v, DiagnosisOptions(), {kMotorLag}),
            "implausible: absorbs something else; acc_bias_z = 2 m/s^2 is on its upper bound (2 m/s^2): the data "
            "push it further (refined on all identification data) (its held-out shrink of 8.7 % on top of "
            "motor_lag is bought with that value: not selected)");
}

// Real jana06: the lever arm removes 14.4 % of the pooled held-out residual (Fy, Mx) and adds to My.
TEST(VerdictNoteTest, AnEffectThatWorsensAComponentSaysWhichAndIsNotSelected) {
  EffectVerdict v;
  v.kind = kMisalignment;
  v.status = "worsens a component";
  v.worsens = "My: residual 4.04e-05 -> 4.87e-05 N m (+20.6 % against its rotor moment, t = 1.9) over none";
  v.test.shrink_pct = 14.4;
  EXPECT_EQ(VerdictNote(v, DiagnosisOptions(), {}),
            "worsens a component held out: My: residual 4.04e-05 -> 4.87e-05 N m (+20.6 % against its rotor moment, "
            "t = 1.9) over none (its held-out shrink of 14.4 % on top of none trades that component for others "
            "rather than explaining the gap: not selected)");
}

}  // namespace
}  // namespace rotorid::internal

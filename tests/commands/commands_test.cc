// The analysing commands as library calls (rotorid/commands): every model they draw or validate
// with predicts with what its JSON says (a discarded inertia at its predicts_with, never at 0, the
// drift of issue 40), and delay's search range under the key refine writes.

#include <gtest/gtest.h>

#include <string>

#include "report/html_answer.h"
#include "rotorid/commands/ablate_command.h"
#include "rotorid/commands/delay_command.h"
#include "rotorid/commands/diagnose_command.h"
#include "rotorid/commands/identify_command.h"
#include "rotorid/commands/validate_command.h"
#include "rotorid/core/text.h"
#include "rotorid/io/blackbox_flight.h"
#include "rotorid/io/crazyflie_flight.h"
#include "rotorid/io/rotor_signal.h"
#include "rotorid/report/json.h"
#include "rotorid/report/predicted_parameters.h"
#include "rotorid/report/refine_json.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::MakeTempDir;
using testing::SourceDir;

std::string Sim(const std::string& file) { return SourceDir() + "/data/sim/" + file; }

CommandInputOptions BundledB(const std::string& log) {
  CommandInputOptions input;
  input.training.vehicle_paths = {Sim("B.yaml")};
  input.training.log_paths = {Sim(log)};
  input.quiet = true;
  return input;
}

// The discarded inertia of a linear JSON block that the model predicts with a non-zero value.
std::string PredictedDiscardedParameter(const nlohmann::json& block) {
  for (const auto& [name, entry] : block["parameters"].items())
    if (entry.contains("predicts_with") && entry["value"].get<double>() == 0.0 &&
        entry["predicts_with"].get<double>() != 0.0)
      return name;
  return {};
}

TEST(CommandInputTest, ValidateNamesUnpairedOptionsAndABadRotorSignalOnce) {
  CommandInputOptions input = BundledB("B_train.csv");
  EXPECT_EQ(input.Validate(), "");
  input.held_out.log_paths = {Sim("B_val.csv")};
  EXPECT_EQ(input.Validate(), "got 0 vehicle files for 1 --validate-log; give one per log, in the same order");
  input.held_out.vehicle_paths = {Sim("B.yaml")};
  input.training.weights = {1.0, 2.0};
  EXPECT_EQ(input.Validate(), "got 2 --weight values for 1 --log; give one per log, in the same order");
  input.training.weights = {0.0};
  EXPECT_EQ(input.Validate(), "--weight must be positive, got 0.000000");
  input.training.weights = {};
  // One check of the rotor signal, the same message from every reader's options.
  const std::string expected = "rotor signal must be auto, rpm or command, got 'pwm'";
  input.source.rotor_signal = "pwm";
  EXPECT_EQ(input.Validate(), expected);
  CrazyflieFlightOptions crazyflie;
  crazyflie.rotor_signal = "pwm";
  EXPECT_EQ(crazyflie.Validate(), expected);
  BlackboxFlightOptions blackbox;
  blackbox.rotor_signal = "pwm";
  EXPECT_EQ(blackbox.Validate(), expected);
  for (const char* valid : {"auto", "rpm", "command"}) EXPECT_EQ(RotorSignalProblem(valid), "") << valid;
}

TEST(PredictedParametersTest, ASavedReportPredictsWithItsRefinedBlockElseLinear) {
  const nlohmann::json linear_only = {
      {"linear", {{"parameters", {{"kt", {{"value", 2.0}}}, {"B.I_zz", {{"value", 0.0}, {"predicts_with", 5e-3}}}}}}}};
  const PredictedModel linear = PredictedParameters(linear_only, "r.json");
  EXPECT_EQ(linear.block, "linear");
  EXPECT_EQ(linear.values.at("B.I_zz"), 5e-3);
  EXPECT_EQ(linear.values.at("kt"), 2.0);
  nlohmann::json both = linear_only;
  both["refined"] = {{"parameters", {{"kt", {{"value", 3.0}}}, {"B.I_zz", {{"value", 0.0}, {"predicts_with", 6e-3}}}}},
                     {"effects", {{"delay_s", {{"value", 0.02}, {"std", 0.001}}}}}};
  const PredictedModel refined = PredictedParameters(both, "r.json");
  EXPECT_EQ(refined.block, "refined");
  EXPECT_EQ(refined.values.at("B.I_zz"), 6e-3);
  EXPECT_DOUBLE_EQ(refined.effects.Get(ParseEffectList("delay").front())[0], 0.02);
  EXPECT_EQ(PredictedParameters(both, "r.json", "linear").values.at("kt"), 2.0);
  // The HTML report's sets of a saved report (validate's) hold the same values: I_zz was drawn at 0.
  const std::vector<ParameterSet> sets = ParameterSetsFromReport(both, "r.json");
  ASSERT_EQ(sets.size(), 2u);
  EXPECT_EQ(sets[0].values.at("B.I_zz"), 5e-3);
  EXPECT_EQ(sets[1].values.at("B.I_zz"), 6e-3);
}

class CommandsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    IdentifyCommandOptions options;
    options.input = BundledB("B_train.csv");
    identify_ = new IdentifyCommandResult(RunIdentify(options));
  }
  static void TearDownTestSuite() { delete identify_; }
  static IdentifyCommandResult* identify_;
};
IdentifyCommandResult* CommandsTest::identify_ = nullptr;

TEST_F(CommandsTest, IdentifyDrawsWhatItsJsonPredictsWith) {
  const nlohmann::json report = IdentifyJson(*identify_);
  const std::string name = PredictedDiscardedParameter(report["linear"]);
  ASSERT_FALSE(name.empty()) << "the bundled B flight should leave an inertia discarded but predicted";
  EXPECT_EQ(IdentifyReportInput(*identify_).parameter_sets.at(0).values.at(name),
            report["linear"]["parameters"][name]["predicts_with"].get<double>());
}

TEST_F(CommandsTest, ValidatePredictsInJsonAndHtmlWithTheSavedPredictsWith) {
  const std::string dir = MakeTempDir("commands_validate");
  const nlohmann::json saved = IdentifyJson(*identify_);
  WriteJsonFile(dir + "/identify.json", saved);
  const std::string name = PredictedDiscardedParameter(saved["linear"]);
  ASSERT_FALSE(name.empty());
  ValidateCommandOptions options;
  options.input = BundledB("B_val.csv");
  options.params_path = dir + "/identify.json";
  const ValidateCommandResult result = RunValidate(options);
  const double predicted = saved["linear"]["parameters"][name]["predicts_with"].get<double>();
  EXPECT_EQ(result.model.values.at(name), predicted);
  // Before: the JSON's Table III predicted with it, the HTML drew the same model with 0.
  EXPECT_EQ(ValidateReportInput(result).parameter_sets.at(0).values.at(name), predicted);
  EXPECT_EQ(ValidateJson(result)["block"], "linear");
}

TEST(IdentifyCommandTest, TheAnswerGivesTheValueADiscardedInertiaIsPredictedWith) {
  IdentifyCommandOptions options;
  options.input.training = {
      {Sim("A.yaml"), Sim("B.yaml")}, {Sim("A_train.csv"), Sim("B_train.csv")}, {1.0, 2.0}, {}, "--log"};
  options.input.quiet = true;
  const IdentifyCommandResult result = RunIdentify(options);
  const nlohmann::json entry = IdentifyJson(result)["linear"]["parameters"]["A.I_zz"];
  ASSERT_TRUE(entry.contains("predicts_with")) << entry;
  // Before: "not fixed by these flights" alone, while the JSON predicts with 0.01799 (a value a body allows).
  const std::string expected = "<code>A.I_zz</code></td><td>not fixed by these flights (predicted with " +
                               ShortNumber(entry["predicts_with"].get<double>()) + " kg m&sup2;)";
  EXPECT_NE(internal::AnswerHtml(IdentifyReportInput(result)).find(expected), std::string::npos) << expected;
}

TEST(IdentifyCommandTest, AnInertiaPredictedOnlyWithinTheRangeABodyAllowsIsMarkedPredictedWith) {
  IdentifyCommandOptions options;
  options.input.training = {{Sim("A.yaml"), Sim("A.yaml")}, {Sim("A_train.csv"), Sim("A_val.csv")}, {}, {}, "--log"};
  options.input.quiet = true;
  options.identify.first_moment = FirstMoment::kPerFlight;
  IdentifyCommandResult result = RunIdentify(options);
  TlsSolution& solution = result.linear.solution;
  int within = -1;
  for (int k = 0; k < solution.chi.size(); ++k)
    if (solution.PredictsWithinRange(k)) within = k;
  ASSERT_GE(within, 0) << "A alone, per-flight first moments: I_zz is predicted within its range";
  // As for a discarded inertia whose profiled estimate is negative (jana04's I_xx) or absent: the model
  // predicts with a value a body allows, not with an estimate.
  solution.profiled[static_cast<size_t>(within)] = false;
  ASSERT_FALSE(PredictsWithProfiled(solution, within));
  const std::string& name = result.linear.system.parameter_names[static_cast<size_t>(within)];
  const nlohmann::json entry = IdentifyJson(result)["linear"]["parameters"][name];
  EXPECT_TRUE(entry["predicts_within_range"].get<bool>());
  EXPECT_EQ(entry["predicts_with"], PredictionChi(solution)[within]);
  EXPECT_NE(IdentifyBrief(result).find("predicted with"), std::string::npos);
}

TEST(DelayCommandTest, DrawsDiscardedInertiaAtItsPredictedValueAndWritesDelaySearchS) {
  DelayCommandOptions options;
  options.input = BundledB("B_train.csv");
  options.delay.num_threads = 1;
  const DelayCommandResult result = RunDelay(options);
  const nlohmann::json report = DelayJson(result);
  EXPECT_EQ(report["settings"]["delay_search_s"], nlohmann::json({-0.1, 0.2, 0.004}));
  EXPECT_FALSE(report["settings"].contains("search_s"));
  const std::string name = PredictedDiscardedParameter(report["linear"]);
  ASSERT_FALSE(name.empty());
  const ReportInput input = DelayReportInput(result);
  // Before: 0 (raw chi) for the value linear.parameters.<name>.predicts_with gives.
  EXPECT_EQ(input.parameter_sets.at(0).values.at(name), report["linear"]["parameters"][name]["predicts_with"]);
  EXPECT_EQ(input.parameter_sets.at(1).values,
            PredictedParameters(result.linear.system, result.estimate.refined.refined));
}

TEST(AblateCommandTest, DrawsDiscardedInertiaAtItsPredictedValue) {
  AblateCommandOptions options;
  options.input = BundledB("B_train.csv");
  options.effects = "delay";
  options.threads = 1;
  const AblateCommandResult result = RunAblate(options);
  ASSERT_EQ(result.ablation.entries.size(), 2u);
  const nlohmann::json report = AblateJson(result);
  const std::string name = PredictedDiscardedParameter(report["linear"]);
  ASSERT_FALSE(name.empty());
  const ReportInput input = AblateReportInput(result);
  ASSERT_EQ(input.parameter_sets.size(), 2u);
  EXPECT_EQ(input.parameter_sets[0].values.at(name), report["linear"]["parameters"][name]["predicts_with"]);
  EXPECT_NE(input.parameter_sets[0].values.at(name), 0.0);
}

TEST(DiagnoseCommandTest, DrawsEachModelWithWhatItPredictsWith) {
  DiagnoseCommandResult result;
  result.diagnosis.linear_parameters = {{"kt", 1e-5}, {"B.I_zz", 0.0}};
  result.diagnosis.linear_predicts_with = {{"B.I_zz", 5.4e-3}};
  result.diagnosis.final_model = {ParseEffectList("motor_lag").front()};
  result.diagnosis.final_parameters = {{"kt", 1.1e-5}, {"B.I_zz", 0.0}};
  result.diagnosis.final_predicts_with = {{"B.I_zz", 5.5e-3}};
  const ReportInput input = DiagnoseReportInput(result);
  ASSERT_EQ(input.parameter_sets.size(), 2u);
  // Before: both drawn with I_zz = 0.
  EXPECT_EQ(input.parameter_sets[0].values.at("B.I_zz"), 5.4e-3);
  EXPECT_EQ(input.parameter_sets[1].values.at("B.I_zz"), 5.5e-3);
  EXPECT_EQ(input.parameter_sets[1].values.at("kt"), 1.1e-5);
}

TEST(DiagnoseCommandTest, WritesRotorDragAsRefineDoes) {
  const EffectKind drag = ParseEffectList("rotor_drag").front();
  DiagnoseCommandResult result;
  for (HeldOutGap* gap : {&result.diagnosis.baseline, &result.diagnosis.final_gap})
    for (auto* values : {&gap->relative_error_pct, &gap->gap_pct, &gap->noise_floor_pct, &gap->model_error_pct})
      values->assign(kNumWrenchComponents, 1.0);
  result.diagnosis.final_model = {drag};
  result.diagnosis.final_effects.Set(drag, Eigen::Vector2d(0.012, 3e-4));
  result.diagnosis.final_effects_std.Set(drag, Eigen::Vector2d(1e-3, 2e-5));
  EffectVerdict verdict;
  verdict.kind = drag;
  verdict.value = Eigen::Vector2d(0.012, 3e-4);
  verdict.std = Eigen::Vector2d(1e-3, 2e-5);
  verdict.detectable_above = Eigen::Vector2d(1e-3, 1e-5);
  result.diagnosis.ranking = {verdict};
  const nlohmann::json report = DiagnoseJson(result);
  // Before: one key, rotor_drag_coefficient, holding [k_d, k_f]; refine writes two.
  const nlohmann::json& effects = report["final"]["effects"];
  EXPECT_EQ(effects["rotor_drag_coefficient"]["value"], 0.012);
  EXPECT_EQ(effects["flapping_moment_coefficient"]["value"], 3e-4);
  EXPECT_EQ(effects["flapping_moment_coefficient"]["std"], 2e-5);
  const nlohmann::json& magnitude = report["ranking"][0]["magnitude"];
  EXPECT_EQ(magnitude["rotor_drag_coefficient"]["std"], 1e-3);
  EXPECT_EQ(magnitude["flapping_moment_coefficient"]["value"], 3e-4);
  EXPECT_EQ(report["ranking"][0]["detectable_above"]["flapping_moment_coefficient"], 1e-5);
  Effects std_dev;
  std_dev.Set(drag, Eigen::Vector2d(1e-3, 2e-5));
  const nlohmann::json refined = EffectsJson(result.diagnosis.final_effects, std_dev, {drag});
  for (const char* name : {"rotor_drag_coefficient", "flapping_moment_coefficient"})
    EXPECT_EQ(refined[name]["value"], effects[name]["value"]) << name;
}

}  // namespace
}  // namespace rotorid

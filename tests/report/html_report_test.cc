#include "rotorid/report/html_report.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "report/svg_check.h"
#include "report/synthetic_flight.h"
#include "rotorid/core/error.h"
#include "rotorid/diagnosis/diagnosis.h"
#include "rotorid/diagnosis/diagnosis_json.h"
#include "rotorid/ident/identify.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/refine/refine.h"
#include "rotorid/core/text.h"
#include "rotorid/report/checks_json.h"
#include "rotorid/report/input_json.h"
#include "rotorid/report/json.h"
#include "rotorid/report/refine_json.h"
#include "rotorid/report/wrench_split.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The text of every cell of the table with this id, row by row (header rows left out), tags
// stripped and the report's entities made plain.
std::vector<std::vector<std::string>> TableCells(const std::string& html, const std::string& id) {
  std::vector<std::vector<std::string>> rows;
  const size_t start = html.find("<table id=\"" + id + "\"");
  if (start == std::string::npos) return rows;
  const size_t body = html.find("<tbody>", start), end = html.find("</table>", start);
  const std::string table = html.substr(body, end - body);
  const std::regex row_pattern("<tr[^>]*>(.*?)</tr>"), cell_pattern("<td[^>]*>(.*?)</td>");
  for (auto r = std::sregex_iterator(table.begin(), table.end(), row_pattern); r != std::sregex_iterator(); ++r) {
    const std::string row = (*r)[1];
    std::vector<std::string> cells;
    for (auto c = std::sregex_iterator(row.begin(), row.end(), cell_pattern); c != std::sregex_iterator(); ++c) {
      std::string text = std::regex_replace(std::string((*c)[1]), std::regex("<br/>"), "\n");
      text = std::regex_replace(text, std::regex("<[^>]*>"), "");
      text = std::regex_replace(text, std::regex("&ndash;"), "-");
      text = std::regex_replace(text, std::regex("&plusmn;"), "+-");
      cells.push_back(text);
    }
    rows.push_back(cells);
  }
  return rows;
}

// The number a cell starts with (NaN for a dash or text).
double CellNumber(const std::string& cell) {
  try {
    size_t used = 0;
    const double v = std::stod(cell, &used);
    return used ? v : NAN;
  } catch (const std::exception&) {
    return NAN;
  }
}

int CountOccurrences(const std::string& text, const std::string& what) {
  int count = 0;
  for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + what.size())) ++count;
  return count;
}

// The wrench split the figures draw, on a synthetic flight that satisfies the IDIM exactly: one
// identification flight and one held-out flight of configuration A whose logs carry a 20 ms delay.
class WrenchSplitTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const Vehicle vehicle = testing::PaperVehicleA();
    const VehicleParameters truth = testing::PaperParametersA();
    testing::SyntheticFlightOptions options;
    options.delay_s = 0.02;
    options.duration_s = 30.0;
    ObservationOptions observation;
    std::vector<ProcessedFlight> identification = {
        ProcessFlight(testing::SyntheticFlight(vehicle, truth, options, "ident.csv"), vehicle, 1.0, observation)};
    options.seed = 2;
    options.duration_s = 20.0;
    held_out_ = new ProcessedFlight(
        ProcessFlight(testing::SyntheticFlight(vehicle, truth, options, "held_out.csv"), vehicle, 1.0, observation));
    IdentifyOptions identify;
    identify.observation = observation;
    result_ = new IdentificationResult(IdentifyProcessed(std::move(identification), identify));
  }
  static void TearDownTestSuite() {
    delete result_;
    delete held_out_;
    result_ = nullptr;
    held_out_ = nullptr;
  }

  static std::map<std::string, double> LinearValues() {
    std::map<std::string, double> values;
    for (int k = 0; k < result_->system.num_parameters(); ++k)
      values[result_->system.parameter_names[k]] = result_->solution.chi[k];
    return values;
  }

  static IdentificationResult* result_;
  static ProcessedFlight* held_out_;
};

IdentificationResult* WrenchSplitTest::result_ = nullptr;
ProcessedFlight* WrenchSplitTest::held_out_ = nullptr;

TEST_F(WrenchSplitTest, WrenchSplitSidesDifferByTheEquationError) {
  const ProcessedFlight& flight = result_->flights[0];
  const WrenchSplit split = ComputeWrenchSplit(flight, LinearValues(), Effects());
  ASSERT_EQ(split.t_s.size(), flight.num_rows_samples());
  const Eigen::MatrixXd w = BuildIdimMatrix(flight);
  const Eigen::VectorXd rho = w * FlightChiT(flight, LinearValues());
  for (int r = 0; r < split.t_s.size(); r += 97)
    for (int c = 0; c < 6; ++c) EXPECT_NEAR(split.error(r, c), rho[6 * r + c], 1e-9 * (1.0 + std::abs(rho[6 * r + c])));
  // The rotor model makes no lateral force; the thrust is about m g.
  EXPECT_EQ(split.rotor_model.col(0).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_NEAR(split.rotor_model.col(2).mean(), flight.vehicle.mass_kg * kStandardGravity, 1.0);
  // The logs carry a delay, so the linear fit leaves a clear moment error; Table III agrees with FitFlight.
  const FlightFit fit = FitFlight(flight, LinearValues());
  for (int c = 2; c < 5; ++c) {
    ASSERT_TRUE(split.relative_error_pct[c].has_value());
    EXPECT_NEAR(*split.relative_error_pct[c], *fit.relative_error_pct[c], 1e-9);
  }
  // Missing parameters of the flight's configuration are an error, not a crash.
  std::map<std::string, double> partial = {{"kt", 1e-6}, {"kd", 0.0}};
  EXPECT_THROW(ComputeWrenchSplit(flight, partial, Effects()), Error);
}

TEST_F(WrenchSplitTest, RefinedEffectsShrinkTheErrorOfADelayedLog) {
  Effects delay;
  delay.Set("delay_s", 0.02);
  const WrenchSplit linear = ComputeWrenchSplit(*held_out_, LinearValues(), Effects());
  const WrenchSplit with_delay = ComputeWrenchSplit(*held_out_, LinearValues(), delay);
  EXPECT_LT(*with_delay.relative_error_pct[3], *linear.relative_error_pct[3]);
}

// The report of real results: a simulated flight of configuration B with a 20 ms delay and a
// held-out flight, identified, refined and diagnosed, the report inputs assembled as the commands
// assemble them. Its tables are compared with what the JSON writers (LinearJson, RefinedJson,
// DiagnosisJson) emit for the same results: when the report and a writer show a result
// differently, these tests fail.
class HtmlReportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    Effects truth;
    truth.Set("delay_s", 0.02);
    SimulationResult train = testing::SimulatePreset("B", 30.0, 31, truth);
    SimulationResult held = testing::SimulatePreset("B", 20.0, 32, truth);
    // Named as logs are: the report finds a stretch's flight by its log.
    train.log.source = "B_train.csv";
    held.log.source = "B_val.csv";
    linear_ = new IdentificationResult(testing::IdentifySimulated(train));
    held_out_ = new std::vector<ProcessedFlight>(ProcessFlights({{held.vehicle, held.log, 1.0}}, ObservationOptions{}));
    RefineOptions refine;
    refine.effects = {ParseEffectKind("delay")};
    refined_ = new RefineResult(Refine(*linear_, refine));
    DiagnosisOptions diagnosis;
    diagnosis.identify.allow_partial = true;
    diagnosis.candidates = {ParseEffectKind("delay"), ParseEffectKind("acc_bias")};
    diagnosis_ = new Diagnosis(Diagnose(linear_->flights, *held_out_, diagnosis));
    settings_ = new json({{"observation", ObservationOptionsJson(ObservationOptions{})},
                          {"tls", TlsOptionsJson(TlsOptions{})},
                          {"diagnosis", DiagnosisOptionsJson(diagnosis)}});
  }
  static void TearDownTestSuite() {
    delete linear_;
    delete held_out_;
    delete refined_;
    delete diagnosis_;
    delete settings_;
  }

  void SetUp() override {
    dir_ = testing::MakeTempDir("rotorid-report-test");
    options_.print_warnings = false;
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::map<std::string, double> LinearValues() {
    return NamedParameters(linear_->system, linear_->solution.chi);
  }

  // As `rotorid identify` writes it.
  static ReportInput IdentifyInput() {
    ReportInput input;
    input.title = "rotorid identify";
    input.command = "identify";
    input.rotorid_version = kRotoridVersion;
    input.observation = ObservationOptions{};
    input.settings = SettingsRows({{"observation", (*settings_)["observation"]}, {"tls", (*settings_)["tls"]}});
    input.linear = linear_;
    input.flights = ReportFlights(linear_->flights, false);
    input.parameter_sets = {{"linear", LinearValues(), Effects()}};
    return input;
  }

  // As `rotorid refine --validate-log` writes it.
  static ReportInput RefineInput() {
    ReportInput input = IdentifyInput();
    input.title = "rotorid refine";
    input.command = "refine";
    input.refined = refined_;
    const std::map<std::string, double> refined_values = NamedParameters(linear_->system, refined_->refined.chi);
    input.relative_errors = {
        {"held-out flights", "linear", CombinedRelativeErrorPct(*held_out_, LinearValues())},
        {"held-out flights", "refined", RelativeErrorWithEffects(*held_out_, refined_values, refined_->effects)}};
    for (const ReportFlight& f : ReportFlights(*held_out_, true)) input.flights.push_back(f);
    input.parameter_sets.push_back({"refined", refined_values, refined_->effects});
    return input;
  }

  // As `rotorid diagnose --validate-log` writes it.
  static ReportInput DiagnoseInput() {
    ReportInput input;
    input.title = "rotorid diagnose";
    input.command = "diagnose";
    input.rotorid_version = kRotoridVersion;
    input.observation = ObservationOptions{};
    input.settings = SettingsRows(*settings_);
    input.diagnosis = diagnosis_;
    input.flights = ReportFlights(linear_->flights, false);
    for (const ReportFlight& f : ReportFlights(*held_out_, true)) input.flights.push_back(f);
    input.parameter_sets = {{"linear", diagnosis_->linear_parameters, Effects()}};
    if (!diagnosis_->selected.empty())
      input.parameter_sets.push_back(
          {"with selected effects", diagnosis_->final_parameters, diagnosis_->final_effects});
    return input;
  }

  std::string Write(const ReportInput& input) {
    summary_ = WriteHtmlReport(dir_, input, options_);
    return ReadFile(dir_ + "/report.html");
  }

  std::vector<std::string> FigureNames() const {
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("fig_", 0) == 0 && entry.path().extension() == ".svg") files.push_back(name);
    }
    std::sort(files.begin(), files.end());
    return files;
  }

  // Every figure file parses as SVG and draws data; the page inlines each of them.
  void ExpectWellFormedFigures(const std::string& html) {
    EXPECT_TRUE(summary_.figures_drawn) << (summary_.warnings.empty() ? "" : summary_.warnings[0]);
    EXPECT_EQ(CountOccurrences(html, "<svg"), static_cast<int>(FigureNames().size()));
    const testing::SvgCheck page = testing::CheckSvg(html.substr(html.find("<html")));
    EXPECT_TRUE(page.well_formed) << page.error;
    for (const std::string& name : FigureNames()) {
      SCOPED_TRACE(name);
      const testing::SvgCheck check = testing::CheckSvg(ReadFile(dir_ + "/" + name));
      ASSERT_TRUE(check.well_formed) << check.error;
      EXPECT_EQ(check.root, "svg");
      EXPECT_GE(check.paths, 20);
      // Beside every full-length wrench plot, its zoom.
      if (name.rfind("fig_wrench_", 0) == 0) {
        EXPECT_EQ(CountOccurrences(ReadFile(dir_ + "/" + name), " s zoom at "), 6);
      }
    }
  }

  static IdentificationResult* linear_;
  static std::vector<ProcessedFlight>* held_out_;
  static RefineResult* refined_;
  static Diagnosis* diagnosis_;
  static json* settings_;
  std::string dir_;
  ReportOptions options_;
  ReportSummary summary_;
};

IdentificationResult* HtmlReportTest::linear_ = nullptr;
std::vector<ProcessedFlight>* HtmlReportTest::held_out_ = nullptr;
RefineResult* HtmlReportTest::refined_ = nullptr;
Diagnosis* HtmlReportTest::diagnosis_ = nullptr;
json* HtmlReportTest::settings_ = nullptr;

// The value shown for a parameter (4 significant digits) is the JSON's.
void ExpectParameterTableMatches(const std::vector<std::vector<std::string>>& rows, const json& parameters,
                                 size_t value_column) {
  ASSERT_EQ(rows.size(), parameters.size());
  for (const auto& row : rows) {
    ASSERT_GT(row.size(), value_column);
    const std::string& name = row[0];
    ASSERT_TRUE(parameters.contains(name)) << name;
    const double value = parameters[name]["value"].get<double>();
    EXPECT_NEAR(CellNumber(row[value_column]), value, 1e-4 * std::abs(value) + 1e-300) << name;
  }
}

TEST_F(HtmlReportTest, IdentifyReportShowsTheLinearJsonValues) {
  const ReportInput input = IdentifyInput();
  const std::string html = Write(input);
  const json linear = LinearJson(*input.linear);
  ExpectParameterTableMatches(TableCells(html, "parameters_table"), linear["parameters"], 1);
  // Table III over all flights equals linear.relative_error_pct.
  const auto table3 = TableCells(html, "table3_combined");
  ASSERT_EQ(table3.size(), 1u);
  for (int c = 2; c < 6; ++c) {
    const json& v = linear["relative_error_pct"][kWrenchComponentNames[c]];
    if (v.is_null())
      EXPECT_EQ(table3[0][c], "-");
    else
      EXPECT_NEAR(CellNumber(table3[0][c]), v.get<double>(), 0.0051) << kWrenchComponentNames[c];
  }
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
  EXPECT_EQ(FigureNames(),
            (std::vector<std::string>{"fig_parameters.svg", "fig_spectrum_identification.svg", "fig_wrench_1.svg"}));
  ExpectWellFormedFigures(html);
}

TEST_F(HtmlReportTest, RefineReportShowsTheEffectsInTheirUnitsAndTheHeldOutErrors) {
  const ReportInput input = RefineInput();
  const std::string html = Write(input);
  const json refined = RefinedJson(*input.linear, *input.refined);
  ExpectParameterTableMatches(TableCells(html, "parameters_table"), refined["parameters"], 5);
  // delay_s is shown in ms: 1000 x the JSON value, with its std.
  const auto effects = TableCells(html, "effects_table");
  ASSERT_EQ(effects.size(), refined["effects"].size());
  bool found = false;
  for (const auto& row : effects) {
    if (row[0] != "delay_s") continue;
    found = true;
    const json& delay = refined["effects"]["delay_s"];
    EXPECT_NEAR(CellNumber(row[1]), 1e3 * delay["value"].get<double>(), 1e-3 * 1e3 * delay["value"].get<double>());
    EXPECT_NEAR(1e-3 * CellNumber(row[1]), 0.02, 0.002);  // and the simulator's truth
    EXPECT_NE(row[1].find(" ms"), std::string::npos) << row[1];
    EXPECT_EQ(row[2], "estimated");
  }
  EXPECT_TRUE(found);
  const auto combined = TableCells(html, "table3_combined");
  ASSERT_EQ(combined.size(), 4u);  // identification and held-out, linear and refined
  EXPECT_EQ(combined[3][0], "held-out flights");
  // As `rotorid refine` writes held_out.refined.relative_error_pct.
  EXPECT_NEAR(CellNumber(combined[3][3]),
              ComponentsJson(input.relative_errors[1].relative_error_pct)["Mx"].get<double>(), 0.0051);
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
  EXPECT_EQ(FigureNames(),
            (std::vector<std::string>{"fig_parameters.svg", "fig_spectrum_held_out.svg",
                                      "fig_spectrum_identification.svg", "fig_wrench_1.svg", "fig_wrench_2.svg"}));
  ExpectWellFormedFigures(html);
}

TEST_F(HtmlReportTest, DiagnoseReportGivesTheVerdictFirstAndTablesEqualToTheJson) {
  const ReportInput input = DiagnoseInput();
  const json report = DiagnosisJson(*input.diagnosis);
  const std::string html = Write(input);
  // The verdict, verbatim, before every other section.
  const size_t verdict = html.find("id=\"diagnosis_verdict\"");
  ASSERT_NE(verdict, std::string::npos);
  EXPECT_LT(verdict, html.find("id=\"flights\""));
  std::string verdict_text = report["verdict"].get<std::string>();
  verdict_text = std::regex_replace(verdict_text, std::regex("&"), "&amp;");
  verdict_text = std::regex_replace(verdict_text, std::regex("<"), "&lt;");
  verdict_text = std::regex_replace(verdict_text, std::regex(">"), "&gt;");
  verdict_text = std::regex_replace(verdict_text, std::regex("'"), "&#39;");
  verdict_text = std::regex_replace(verdict_text, std::regex("\""), "&quot;");
  EXPECT_NE(html.find(verdict_text), std::string::npos);
  // The simulated delay is found and selected.
  ASSERT_FALSE(report["selected"].empty());
  EXPECT_EQ(report["selected"][0], "delay");

  // Which: the ranking in the JSON's order, with status, shrink and magnitude in ms.
  const auto ranking = TableCells(html, "diagnosis_ranking");
  ASSERT_EQ(ranking.size(), report["ranking"].size());
  for (size_t k = 0; k < ranking.size(); ++k) {
    const json& entry = report["ranking"][k];
    EXPECT_EQ(ranking[k][1], entry["effect"].get<std::string>());
    EXPECT_EQ(ranking[k][2], entry["status"].get<std::string>());
    EXPECT_NEAR(CellNumber(ranking[k][3]), entry["shrink_pct"].get<double>(), 0.0051);
    if (entry["effect"] == "delay") {
      const double value_ms = 1e3 * entry["magnitude"]["delay_s"]["value"].get<double>();
      EXPECT_NEAR(CellNumber(ranking[k][4].substr(ranking[k][4].find('\n') + 1)), value_ms, 1e-3 * value_ms);
      EXPECT_NE(ranking[k][4].find("ms"), std::string::npos);
    }
  }
  // How far: baseline, one row per kept effect, final.
  const auto gap = TableCells(html, "diagnosis_gap");
  ASSERT_EQ(gap.size(), 2 + report["steps"].size());
  auto expect_row = [](const std::vector<std::string>& row, const json& values) {
    for (int c = 2; c < 6; ++c) {
      const json& v = values[kWrenchComponentNames[c]];
      if (v.is_null())
        EXPECT_EQ(row[c - 1], "-");
      else
        EXPECT_NEAR(CellNumber(row[c - 1]), v.get<double>(), 0.0051) << kWrenchComponentNames[c];
    }
  };
  expect_row(gap.front(), report["baseline"]["relative_error_pct"]);
  expect_row(gap[1], report["steps"][0]["after"]["relative_error_pct"]);
  expect_row(gap.back(), report["final"]["relative_error_pct"]);
  // The held-out residual in physical units after each step too: the comparison no divisor moves.
  const auto rms = TableCells(html, "diagnosis_rms");
  ASSERT_EQ(rms.size(), gap.size());
  auto expect_rms = [](const std::vector<std::string>& row, const json& values) {
    for (int c = 0; c < 6; ++c) {
      const double v = values[kWrenchComponentNames[c]].get<double>();
      EXPECT_NEAR(CellNumber(row[c + 1]), v, 1e-3 * v) << kWrenchComponentNames[c];
    }
  };
  expect_rms(rms.front(), report["baseline"]["residual_rms"]);
  expect_rms(rms[1], report["steps"][0]["after"]["residual_rms"]);
  expect_rms(rms.back(), report["final"]["residual_rms"]);
  // Where: one row per band with the where-component's residual before and after, in its unit.
  const std::string component = report["where"]["component"].get<std::string>();
  const auto bands = TableCells(html, "diagnosis_bands");
  ASSERT_EQ(bands.size(), report["where"]["bands"].size());
  for (size_t b = 0; b < bands.size(); ++b) {
    const json& band = report["where"]["bands"][b];
    const double before = band["residual_rms"][component].get<double>();
    const double after = band["final_residual_rms"][component].get<double>();
    EXPECT_NEAR(CellNumber(bands[b][1]), before, 1e-3 * before);
    EXPECT_NEAR(CellNumber(bands[b][2]), after, 1e-3 * after);
    EXPECT_NEAR(CellNumber(bands[b][4]), band["share_pct"][component].get<double>(), 0.051);
  }
  const auto stretches = TableCells(html, "diagnosis_stretches");
  ASSERT_EQ(stretches.size(), report["where"]["worst_stretches"].size());
  ASSERT_FALSE(stretches.empty());
  EXPECT_NEAR(CellNumber(stretches[0][1]), report["where"]["worst_stretches"][0]["start_s"].get<double>(), 0.051);
  EXPECT_NEAR(CellNumber(stretches[0][2]), report["where"]["worst_stretches"][0]["end_s"].get<double>(), 0.051);
  // No raw JSON anywhere in the page.
  EXPECT_EQ(html.find("{\""), std::string::npos);
  EXPECT_EQ(html.find("\":"), std::string::npos);

  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
  const std::vector<std::string> figures = FigureNames();
  for (const char* name : {"fig_diagnosis.svg", "fig_diagnosis_bands.svg", "fig_diagnosis_signatures.svg"})
    EXPECT_NE(std::find(figures.begin(), figures.end(), name), figures.end()) << name;
  ExpectWellFormedFigures(html);
  // The worst stretches lie on the identification flight: shaded in its wrench figure only.
  const std::string shade = "rgb(253, 226, 225)";
  EXPECT_GT(CountOccurrences(ReadFile(dir_ + "/fig_wrench_1.svg"), shade), 0);
  EXPECT_EQ(CountOccurrences(ReadFile(dir_ + "/fig_wrench_2.svg"), shade), 0);
}

// As `rotorid validate --params refine.json --report` writes it: the saved parameter sets, read
// back from the writers' JSON, applied to other flights.
TEST_F(HtmlReportTest, ValidateReportShowsTheSavedParametersOnTheGivenFlights) {
  const json saved = {{"linear", LinearJson(*linear_)}, {"refined", RefinedJson(*linear_, *refined_)}};
  ReportInput input;
  input.title = "rotorid validate";
  input.command = "validate";
  input.observation = ObservationOptions{};
  input.flights = ReportFlights(*held_out_, true);
  input.parameter_sets = ParameterSetsFromReport(saved, "refine.json");
  ASSERT_EQ(input.parameter_sets.size(), 2u);
  const ParameterSet& refined = input.parameter_sets[1];
  EXPECT_EQ(refined.label, "refined");
  EXPECT_NEAR(refined.effects.Get(ParseEffectKind("delay"))[0], refined_->effects.Get(ParseEffectKind("delay"))[0],
              1e-12);
  const std::vector<std::optional<double>> combined =
      RelativeErrorWithEffects(*held_out_, refined.values, refined.effects);
  input.relative_errors = {{"given flights", "refined parameters of refine.json", combined}};
  const std::string html = Write(input);
  // The refined values (the second set's value column) are the saved ones.
  ExpectParameterTableMatches(TableCells(html, "parameters_table"), saved["refined"]["parameters"], 5);
  EXPECT_EQ(TableCells(html, "table3_flights").size(), 2u);  // one held-out flight, two sets
  const auto given = TableCells(html, "table3_combined");
  ASSERT_EQ(given.size(), 1u);
  EXPECT_EQ(given[0][0], "given flights");
  EXPECT_NEAR(CellNumber(given[0][3]), *combined[3], 0.0051);
  // A saved report without a parameter's value names the file.
  json broken = saved;
  broken["linear"]["parameters"]["kt"].erase("value");
  try {
    ParameterSetsFromReport(broken, "refine.json");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("refine.json"), std::string::npos) << e.what();
  }
}

TEST_F(HtmlReportTest, AResultTheCommandDidNotGiveIsNotShown) {
  std::string html = Write(IdentifyInput());
  for (const char* id : {"id=\"diagnosis\"", "id=\"effects_table\"", "id=\"ablation\"", "id=\"checks\""})
    EXPECT_EQ(html.find(id), std::string::npos) << id;
  // Without the linear result the parameter table has the set's values and no statistics.
  ReportInput input = IdentifyInput();
  input.linear = nullptr;
  html = Write(input);
  const auto parameters = TableCells(html, "parameters_table");
  ASSERT_FALSE(parameters.empty());
  for (const auto& row : parameters) {
    EXPECT_FALSE(std::isnan(CellNumber(row[1]))) << row[0];
    EXPECT_EQ(row[2], "-") << row[0];
  }
  EXPECT_EQ(TableCells(html, "table3_combined").size(), 0u);
}

// The first screen of a refine report: the refined kt and inertia with their std, the centre of mass
// as ms / m in mm, the gap on the identification and held-out flights, and the next step.
TEST_F(HtmlReportTest, TheAnswerGivesTheRefinedParametersWithTheirStdAndTheGap) {
  const std::string html = Write(RefineInput());
  const auto rows = TableCells(html, "answer_parameters");
  ASSERT_GE(rows.size(), 5u);
  const std::vector<std::string>& names = linear_->system.parameter_names;
  const auto at = [&](const std::string& name) {
    return static_cast<int>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const TlsSolution& refined = refined_->refined;
  EXPECT_EQ(
      rows[0][1].rfind(FormatValue("%.4g", refined.chi[at("kt")]) + " +- " + ShortNumber(refined.std[at("kt")]), 0), 0u)
      << rows[0][1];
  const std::string config = linear_->flights[0].vehicle.name;
  const double mass = linear_->flights[0].vehicle.mass_kg;
  const auto com =
      std::find_if(rows.begin(), rows.end(), [](const auto& r) { return r[0].find("centre of mass") == 0; });
  ASSERT_NE(com, rows.end());
  EXPECT_NE((*com)[1].find("z: " + FormatValue("%.4g", refined.chi[at(config + ".ms_z")] * 1e3 / mass)),
            std::string::npos)
      << (*com)[1];
  EXPECT_NE(html.find("On the identification flights (refined, the paper's Table III): Fz"), std::string::npos);
  EXPECT_NE(html.find("On the held-out flights (refined): Fz"), std::string::npos);
  EXPECT_NE(html.find("<strong>Next step.</strong> Check the refined model"), std::string::npos);
  EXPECT_LT(html.find("id=\"answer\""), html.find("id=\"parameters\""));
}

TEST_F(HtmlReportTest, TheAnswerComesFirstNamingFailedChecksAndWhatWasReadIsTabulated) {
  // checks[] and input.flights[] (INTERFACE.md section 5, v2), from the typed results their writers take.
  ReportInput input = IdentifyInput();
  input.checks = std::vector<Check>{{"gravity_magnitude", CheckStatus::kOk, "9.79 m/s^2 in hover"},
                                    {"rotor_order", CheckStatus::kError, "rotors 1 and 2 swapped"}};
  FlightInputSummary train;
  train.file = "B_train.csv";
  train.format = "csv";
  train.log_end_s = 30.0;
  train.rotor_signal = "rpm";
  train.kept = {{0.0, 30.0}};
  FlightInputSummary held = train;
  held.file = "B_val.csv";
  held.window = TimeWindow{2.0, 18.0};
  input.inputs = {train};
  input.validate_inputs = {held};
  std::string html = Write(input);
  // The first screen: what was found, the failed check named in it, before any other section.
  ASSERT_NE(html.find("id=\"answer\""), std::string::npos);
  EXPECT_LT(html.find("id=\"answer\""), html.find("id=\"flights\""));
  const size_t named = html.find("<code>rotor_order</code> error: rotors 1 and 2 swapped");
  ASSERT_NE(named, std::string::npos);
  EXPECT_LT(named, html.find("id=\"flights\""));
  EXPECT_NE(html.find("1 of 2 plausibility checks did not pass"), std::string::npos);
  // The full table further down, failures first, each row as checks[] has it.
  ASSERT_NE(html.find("id=\"checks\""), std::string::npos);
  EXPECT_GT(html.find("id=\"checks\""), html.find("id=\"parameters\""));
  const auto checks = TableCells(html, "checks_table");
  const json checks_json = ChecksJson(*input.checks);
  ASSERT_EQ(checks.size(), checks_json.size());
  EXPECT_EQ(checks[0][0], "rotor_order");
  EXPECT_EQ(checks[0][1], "error");
  EXPECT_EQ(checks[1][0], checks_json[0]["name"]);
  EXPECT_EQ(checks[1][1], checks_json[0]["status"]);
  EXPECT_EQ(checks[1][2], checks_json[0]["message"]);
  // One column per key of input.flights[] entries, in the JSON's order: file first, window_s last.
  const auto read = TableCells(html, "input_flights");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0][0], "identification");
  EXPECT_EQ(read[1][0], "held-out");
  const json train_json = InputJson({train}, {held});
  ASSERT_EQ(read[0].size(), 1 + train_json["flights"][0].size());
  EXPECT_EQ(read[0][1], "B_train.csv");
  EXPECT_EQ(read[1][1], "B_val.csv");
  EXPECT_NE(std::find(read[0].begin(), read[0].end(), "0, 30"), read[0].end());  // log_span_s
  EXPECT_EQ(read[0].back(), "-");                                                // no window
  EXPECT_EQ(read[1].back(), "2, 18");
  // All checks passing: one line says so.
  (*input.checks)[1].status = CheckStatus::kOk;
  html = Write(input);
  EXPECT_NE(html.find("Every one of the 2 plausibility checks passed"), std::string::npos);
  EXPECT_LT(html.find("Every one of the 2"), html.find("id=\"flights\""));
}

TEST_F(HtmlReportTest, WithoutGnuplotTheTablesAreStillWrittenAndTheReasonGiven) {
  options_.gnuplot = "/nonexistent/bin/gnuplot";
  const std::string html = Write(RefineInput());
  EXPECT_FALSE(summary_.figures_drawn);
  EXPECT_TRUE(summary_.figure_paths.empty());
  ASSERT_FALSE(summary_.warnings.empty());
  EXPECT_NE(summary_.warnings[0].find("gnuplot"), std::string::npos);
  EXPECT_TRUE(FigureNames().empty());
  EXPECT_NE(html.find("gnuplot was not found"), std::string::npos);
  EXPECT_FALSE(TableCells(html, "parameters_table").empty());
  EXPECT_EQ(html.find("<svg"), std::string::npos);
}

TEST_F(HtmlReportTest, RemovesOnlyFiguresAnEarlierReportWroteThere) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
  // The user's own files, even ones named like figures, survive every run.
  WriteFileAtomically(dir_ + "/fig_mine.svg", "<svg/>");
  WriteFileAtomically(dir_ + "/notes.txt", "x");
  Write(RefineInput());
  EXPECT_TRUE(fs::exists(dir_ + "/fig_wrench_2.svg"));
  EXPECT_TRUE(fs::exists(dir_ + "/fig_spectrum_held_out.svg"));
  // An identify report into the same folder: the refine report's held-out figures are its own
  // earlier output and go; the user's files stay.
  Write(IdentifyInput());
  EXPECT_FALSE(fs::exists(dir_ + "/fig_wrench_2.svg"));
  EXPECT_FALSE(fs::exists(dir_ + "/fig_spectrum_held_out.svg"));
  EXPECT_TRUE(fs::exists(dir_ + "/fig_wrench_1.svg"));
  EXPECT_EQ(ReadFile(dir_ + "/fig_mine.svg"), "<svg/>");
  EXPECT_EQ(ReadFile(dir_ + "/notes.txt"), "x");
  // A manifest naming something that is not a figure of ours deletes nothing.
  fs::create_directories(dir_ + "/sub");
  WriteFileAtomically(dir_ + "/sub/fig_a.svg", "<svg/>");
  WriteFileAtomically(dir_ + "/.rotorid_report_figures", "notes.txt\nsub/fig_a.svg\n");
  options_.gnuplot = "";  // no figures this time
  Write(IdentifyInput());
  EXPECT_TRUE(fs::exists(dir_ + "/notes.txt"));
  EXPECT_TRUE(fs::exists(dir_ + "/sub/fig_a.svg"));
  EXPECT_TRUE(fs::exists(dir_ + "/fig_mine.svg"));
}

TEST_F(HtmlReportTest, EscapesTextAndCreatesTheFolder) {
  ReportInput input = IdentifyInput();
  input.title = "odd <report> & 'quotes'";
  input.flights[0].label = "flight `rm -rf` $(x) @macro 'q'\nnext";
  const std::string nested = dir_ + "/a/b";
  const ReportSummary summary = WriteHtmlReport(nested, input, options_);
  const std::string html = ReadFile(nested + "/report.html");
  EXPECT_NE(html.find("odd &lt;report&gt; &amp; &#39;quotes&#39;"), std::string::npos);
  for (const std::string& path : summary.figure_paths)
    EXPECT_TRUE(testing::CheckSvg(ReadFile(path)).well_formed) << path;
}

TEST_F(HtmlReportTest, RejectsBadInput) {
  ReportInput input;
  input.flights = {{"nothing", nullptr, false}};
  EXPECT_THROW(WriteHtmlReport(dir_, input), Error);
  // A refined result without the linear one it refines (whose parameters it names).
  input = RefineInput();
  input.linear = nullptr;
  EXPECT_THROW(WriteHtmlReport(dir_, input), Error);
  ReportOptions options;
  options.max_spectrum_segment = 100;
  EXPECT_FALSE(options.Validate().empty());
  EXPECT_THROW(WriteHtmlReport(dir_, ReportInput(), options), Error);
  EXPECT_THROW(WriteHtmlReport("", ReportInput()), Error);
  // A folder that cannot be created (a file is in the way).
  WriteFileAtomically(dir_ + "/file", "x");
  EXPECT_THROW(WriteHtmlReport(dir_ + "/file/sub", ReportInput()), Error);
}

}  // namespace
}  // namespace rotorid

#include "rotorid/report/html_report.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "report/svg_check.h"
#include "report/synthetic_flight.h"
#include "rotorid/core/error.h"
#include "rotorid/ident/identify.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/report/json.h"
#include "rotorid/report/wrench_split.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

int CountOccurrences(const std::string& text, const std::string& what) {
  int count = 0;
  for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + what.size())) ++count;
  return count;
}

// One identification flight and one held-out flight of configuration A whose logs carry a 20 ms
// delay, the linear identification, and a refine/diagnose/ablate-like JSON report around it.
class HtmlReportTest : public ::testing::Test {
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

  void SetUp() override { dir_ = rotorid::testing::MakeTempDir("rotorid-report-test"); }
  void TearDown() override { fs::remove_all(dir_); }

  static std::map<std::string, double> LinearValues() {
    std::map<std::string, double> values;
    for (int k = 0; k < result_->system.num_parameters(); ++k)
      values[result_->system.parameter_names[k]] = result_->solution.chi[k];
    return values;
  }

  // Everything a refine + diagnose + ablate report may carry, with the refined set made up from
  // the linear one (the report does not judge the numbers).
  static ReportInput FullInput() {
    ReportInput input;
    input.title = "rotorid test report";
    json linear = LinearJson(*result_);
    json refined = {{"parameters", linear["parameters"]},
                    {"effects",
                     {{"delay_s", {{"value", 0.02}, {"std", 0.001}}},
                      {"acc_bias", {{"value", {0.01, -0.02, 0.0}}, {"std", {0.001, 0.001, 0.001}}}}}},
                    {"relative_error_pct",
                     {{"Fx", nullptr}, {"Fy", nullptr}, {"Fz", 1.0}, {"Mx", 5.0}, {"My", 6.0}, {"Mz", nullptr}}}};
    for (auto& [name, entry] : refined["parameters"].items())
      if (entry["value"].is_number()) entry["value"] = entry["value"].get<double>() * 1.01;
    input.report = {{"rotorid_version", kRotoridVersion},
                    {"command", "refine"},
                    {"settings", {{"observation", ObservationOptionsJson(ObservationOptions())}}},
                    {"linear", linear},
                    {"refined", refined},
                    {"baseline", {{"relative_error_pct", {{"Fz", 4.0}, {"Mx", 30.0}, {"My", 28.0}, {"Mz", nullptr}}}}},
                    {"final", {{"relative_error_pct", {{"Fz", 1.5}, {"Mx", 6.0}, {"My", 7.0}, {"Mz", nullptr}}}}},
                    {"where",
                     {{"component", "Mx"},
                      {"stretches",
                       {{{"start_s", 5.0}, {"end_s", 7.5}, {"component", "Mx"}},
                        {{"start_s", 12.0}, {"end_s", 13.0}, {"flight", "held_out.csv"}}}},
                      {"bands", {{{"low_hz", 0.0}, {"high_hz", 1.0}}, {{"low_hz", 1.0}, {"high_hz", 3.0}}}},
                      {"worst_bands", {{{"low_hz", 0.5}, {"high_hz", 2.0}}}}}},
                    {"ranking",
                     {{{"effect", "delay"},
                       {"significant", true},
                       {"shrink_pct", 75.0},
                       {"magnitude", {{"delay_s", {{"value", 0.0201}, {"std", 0.0004}}}}},
                       {"held_out_relative_error_pct", {{"Fz", 1.6}, {"Mx", 6.5}, {"My", 7.5}}}},
                      {{"effect", "gyro_bias"},
                       {"significant", false},
                       {"shrink_pct", 0.4},
                       {"magnitude", {{"value", {0.0, 0.001, 0.0}}, {"std", {0.001, 0.001, 0.001}}}}}}},
                    {"selected", {"delay"}},
                    {"ablation",
                     {{{"effects", json::array()},
                       {"num_parameters", 13},
                       {"aic", 1200.0},
                       {"bic", 1250.0},
                       {"relative_error_pct", {{"Fz", 4.0}, {"Mx", 30.0}, {"My", 28.0}}},
                       {"held_out_relative_error_pct", {{"Fz", 4.2}, {"Mx", 31.0}, {"My", 29.0}}}},
                      {{"effects", {"delay"}},
                       {"num_parameters", 14},
                       {"aic", 900.0},
                       {"bic", 955.0},
                       {"relative_error_pct", {{"Fz", 1.5}, {"Mx", 6.0}, {"My", 7.0}}},
                       {"held_out_relative_error_pct", {{"Fz", 1.6}, {"Mx", 6.5}, {"My", 7.5}}}},
                      {{"effects", {"delay", "motor_lag"}},
                       {"num_parameters", 15},
                       {"aic", 899.0},
                       {"relative_error_pct", {{"Fz", 1.4}, {"Mx", 5.9}, {"My", 6.9}}}}}}};
    input.flights = {{"identification flight", &result_->flights[0], false}, {"held-out flight", held_out_, true}};
    Effects delay;
    delay.Set("delay_s", 0.02);
    std::map<std::string, double> refined_values;
    for (const auto& [name, entry] : refined["parameters"].items()) refined_values[name] = entry["value"].get<double>();
    input.parameter_sets = {{"linear", LinearValues(), Effects()}, {"refined", refined_values, delay}};
    return input;
  }

  std::vector<std::string> FigureFiles() const {
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("fig_", 0) == 0 && entry.path().extension() == ".svg") files.push_back(entry.path().string());
    }
    std::sort(files.begin(), files.end());
    return files;
  }

  static IdentificationResult* result_;
  static ProcessedFlight* held_out_;
  std::string dir_;
};

IdentificationResult* HtmlReportTest::result_ = nullptr;
ProcessedFlight* HtmlReportTest::held_out_ = nullptr;

TEST_F(HtmlReportTest, WrenchSplitSidesDifferByTheEquationError) {
  const ProcessedFlight& flight = result_->flights[0];
  const WrenchSplit split = ComputeWrenchSplit(flight, LinearValues(), Effects());
  ASSERT_EQ(split.t_s.size(), flight.num_rows_samples());
  const Eigen::MatrixXd w = BuildIdimMatrix(flight);
  const Eigen::VectorXd rho = w * FlightChiT(flight.vehicle, LinearValues());
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

TEST_F(HtmlReportTest, RefinedEffectsShrinkTheErrorOfADelayedLog) {
  Effects delay;
  delay.Set("delay_s", 0.02);
  const WrenchSplit linear = ComputeWrenchSplit(*held_out_, LinearValues(), Effects());
  const WrenchSplit with_delay = ComputeWrenchSplit(*held_out_, LinearValues(), delay);
  EXPECT_LT(*with_delay.relative_error_pct[3], *linear.relative_error_pct[3]);
}

TEST_F(HtmlReportTest, RendersEveryFigureAsWellFormedSvgWithData) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
  const ReportInput input = FullInput();
  ReportOptions options;
  options.print_warnings = false;
  const ReportSummary summary = WriteHtmlReport(dir_, input, options);
  EXPECT_TRUE(summary.figures_drawn) << (summary.warnings.empty() ? "" : summary.warnings[0]);
  EXPECT_TRUE(summary.warnings.empty()) << summary.warnings[0];

  const std::vector<std::string> files = FigureFiles();
  // Fig. 3/4 for both flights, spectra for both groups, parameters, diagnosis, ablation.
  const std::vector<std::string> expected = {"fig_ablation.svg",
                                             "fig_diagnosis.svg",
                                             "fig_parameters.svg",
                                             "fig_spectrum_held_out.svg",
                                             "fig_spectrum_identification.svg",
                                             "fig_wrench_1.svg",
                                             "fig_wrench_2.svg"};
  ASSERT_EQ(files.size(), expected.size());
  for (size_t k = 0; k < files.size(); ++k) EXPECT_EQ(fs::path(files[k]).filename().string(), expected[k]);
  EXPECT_EQ(summary.figure_paths.size(), files.size());

  for (const std::string& file : files) {
    SCOPED_TRACE(file);
    const std::string svg = ReadFile(file);
    const testing::SvgCheck check = testing::CheckSvg(svg);
    ASSERT_TRUE(check.well_formed) << check.error;
    EXPECT_EQ(check.root, "svg");
    EXPECT_NE(svg.find("viewBox"), std::string::npos);
    const std::string name = fs::path(file).filename().string();
    if (name.rfind("fig_wrench_", 0) == 0) {
      // 6 components x 2 parameter sets x 3 curves, each a curve of hundreds of points.
      EXPECT_GE(check.max_path_vertices, 300);
      EXPECT_GE(check.total_vertices, 36 * 300);
    } else if (name.rfind("fig_spectrum_", 0) == 0) {
      // 6 components x 2 sets, each a spectrum over > 100 frequency bins.
      EXPECT_GE(check.max_path_vertices, 100);
      EXPECT_GE(check.total_vertices, 12 * 100);
    } else {
      // Bars and error bars: many small paths beyond the frame and the tics.
      EXPECT_GE(check.paths, 30);
    }
  }
  // The diagnosis's stretches are shaded on the time axes (filled rectangles in the wrench figures):
  // the stretch without a flight on both flights, the one naming held_out.csv on that flight only.
  const std::string shade = "rgb(253, 226, 225)";
  EXPECT_EQ(CountOccurrences(ReadFile(dir_ + "/fig_wrench_1.svg"), shade), 12 * 1);
  EXPECT_EQ(CountOccurrences(ReadFile(dir_ + "/fig_wrench_2.svg"), shade), 12 * 2);
  // Only the worst band is shaded on the spectra, not the partition of all bands.
  EXPECT_EQ(CountOccurrences(ReadFile(dir_ + "/fig_spectrum_held_out.svg"), shade), 6);
}

TEST_F(HtmlReportTest, HtmlHoldsTheTablesAndInlinesEveryFigure) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
  ReportOptions options;
  options.print_warnings = false;
  WriteHtmlReport(dir_, FullInput(), options);
  const std::string html = ReadFile(dir_ + "/report.html");
  const testing::SvgCheck document = testing::CheckSvg(html.substr(html.find("<html")));
  EXPECT_TRUE(document.well_formed) << document.error;  // the page is also well-formed XML
  EXPECT_EQ(CountOccurrences(html, "<svg"), static_cast<int>(FigureFiles().size()));
  EXPECT_EQ(html.find("<?xml"), std::string::npos);
  // Self-contained: no scripts, stylesheets or images fetched from anywhere.
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("src=\""), std::string::npos);
  EXPECT_FALSE(std::regex_search(html, std::regex("href=[\"']https?:")));
  // Ids of different figures do not collide.
  EXPECT_NE(html.find("id='fig_wrench_1_gpPt0'"), std::string::npos);
  EXPECT_NE(html.find("id='fig_wrench_2_gpPt0'"), std::string::npos);
  // Tables.
  for (const char* needle :
       {"id=\"parameters\"", "id=\"table3\"", "id=\"settings\"", "id=\"diagnosis\"", "id=\"ablation\"",
        "id=\"flights\"", "<code>kt</code>", "<code>A.I_xx</code>", "change/&sigma;", "<code>delay_s</code>",
        "Selected effects:", "delay + motor_lag", "observation.filter.cutoff_hz", "held-out flights", "stretches"})
    EXPECT_NE(html.find(needle), std::string::npos) << needle;
  // Non-essential parameters keep their row, flagged.
  EXPECT_NE(html.find("discarded"), std::string::npos);
}

TEST_F(HtmlReportTest, WithoutGnuplotTheTablesAreStillWrittenAndTheReasonGiven) {
  ReportOptions options;
  options.gnuplot = "/nonexistent/bin/gnuplot";
  options.print_warnings = false;
  // A figure of an earlier run must not survive as if it belonged to this one.
  WriteFileAtomically(dir_ + "/fig_wrench_9.svg", "<svg/>");
  const ReportSummary summary = WriteHtmlReport(dir_, FullInput(), options);
  EXPECT_FALSE(summary.figures_drawn);
  EXPECT_TRUE(summary.figure_paths.empty());
  ASSERT_FALSE(summary.warnings.empty());
  EXPECT_NE(summary.warnings[0].find("gnuplot"), std::string::npos);
  EXPECT_TRUE(FigureFiles().empty());
  const std::string html = ReadFile(dir_ + "/report.html");
  EXPECT_NE(html.find("gnuplot was not found"), std::string::npos);
  EXPECT_NE(html.find("id=\"parameters\""), std::string::npos);
  EXPECT_NE(html.find("id=\"table3\""), std::string::npos);
  EXPECT_EQ(html.find("<svg"), std::string::npos);
}

TEST_F(HtmlReportTest, CreatesTheFolderAndToleratesStrangeJson) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot is not installed";
  ReportInput input;
  input.title = "odd <report> & 'quotes'";
  input.report = {
      {"ranking", "not an array"},
      {"ablation", 3},
      {"where", {{"stretches", {1, "x", {{"start_s", "soon"}}}}}},
      {"baseline", {{"relative_error_pct", {{"Fz", "high"}}}}},
      {"linear", {{"parameters", {{"kt", 3.6e-6}, {"kd", {{"value", nullptr}}}}}, {"warnings", {"scale lost"}}}},
      {"settings", {{"a", {{"b", {1, 2}}}}}}};
  input.flights = {{"flight `rm -rf` $(x) @macro 'q'\nnext", &result_->flights[0], false}};
  input.parameter_sets = {{"linear", LinearValues(), Effects()}};
  ReportOptions options;
  options.print_warnings = false;
  const std::string nested = dir_ + "/a/b";
  const ReportSummary summary = WriteHtmlReport(nested, input, options);
  EXPECT_TRUE(summary.figures_drawn) << (summary.warnings.empty() ? "" : summary.warnings[0]);
  const std::string html = ReadFile(nested + "/report.html");
  EXPECT_NE(html.find("odd &lt;report&gt; &amp; &#39;quotes&#39;"), std::string::npos);
  EXPECT_NE(html.find("scale lost"), std::string::npos);
  for (const std::string& path : summary.figure_paths)
    EXPECT_TRUE(testing::CheckSvg(ReadFile(path)).well_formed) << path;
}

TEST_F(HtmlReportTest, RejectsBadInput) {
  ReportInput input;
  input.flights = {{"nothing", nullptr, false}};
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

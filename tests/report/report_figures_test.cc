#include "report/report_figures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <regex>
#include <sstream>

#include "report/gnuplot.h"
#include "report/svg_check.h"
#include "rotorid/io/atomic_file.h"

namespace rotorid::internal {
namespace {

// Draws a figure with gnuplot into an SVG string ("" without gnuplot).
std::string Render(const FigureSpec& spec) {
  const std::string gnuplot = FindExecutable("gnuplot");
  if (gnuplot.empty()) return "";
  TempDir dir("rotorid-figure-test");
  const std::string base = dir.path() + "/" + spec.name;
  WriteFileAtomically(base + ".dat", spec.data);
  std::string body = spec.body;
  for (size_t pos = 0; (pos = body.find("$DATA", pos)) != std::string::npos;)
    body.replace(pos, 5, GnuplotPath(base + ".dat"));
  WriteFileAtomically(base + ".gp", ScriptHead(spec, GnuplotPath(base + ".svg")) + body);
  const ProcessResult run = RunGnuplotScript(gnuplot, base + ".gp", base + ".err", 60.0);
  EXPECT_TRUE(run.ok) << run.error_text;
  return run.ok ? ReadFile(base + ".svg") : "";
}

// Ten parameters within a few percent of the reference, one refined estimate 33 times it.
std::vector<ParameterPoint> PointsWithOneOutlier() {
  std::vector<ParameterPoint> points;
  for (int i = 0; i < 10; ++i) {
    const double reference = std::pow(10.0, -i);  // scales from 1 to 1e-9: ratios do not care
    const double refined = reference * (i == 6 ? 33.0 : 1.0 + 0.01 * (i - 5));
    points.push_back({"p" + std::to_string(i), {reference, refined}, {0.01 * reference, 0.012 * reference}});
  }
  return points;
}

TEST(ParameterFigureTest, AnOutlierIsMarkedAtTheEdgeInsteadOfSquashingTheRest) {
  const std::vector<ParameterPoint> points = PointsWithOneOutlier();
  const double half_width = ParameterAxisHalfWidth(points);
  // The axis holds the bulk (deviations up to 5 %, error bars 3.6 %) and not the 33x point.
  EXPECT_GT(half_width, 0.05);
  EXPECT_LT(half_width, 0.2);
  const FigureSpec f = ParameterFigure("fig_parameters", {"linear", "refined"}, points);
  EXPECT_NE(f.body.find("set yrange ["), std::string::npos);
  // Exactly one marker label, with the outlier's ratio.
  const std::regex marker("\"[0-9.]+x\"");
  EXPECT_EQ(std::distance(std::sregex_iterator(f.data.begin(), f.data.end(), marker), std::sregex_iterator()), 1);
  EXPECT_NE(f.data.find("\"33x\""), std::string::npos);
  // Without the outlier the axis just holds the largest deviation (5 %, with a margin), and nothing
  // is marked.
  std::vector<ParameterPoint> tame = points;
  tame[6].value[1] = tame[6].value[0];
  EXPECT_NEAR(ParameterAxisHalfWidth(tame), 1.15 * 0.05, 1e-9);
  EXPECT_EQ(ParameterFigure("fig_parameters", {"linear", "refined"}, tame).data.find("x\""), std::string::npos);

  const std::string svg = Render(f);
  if (svg.empty()) GTEST_SKIP() << "gnuplot is not installed";
  const testing::SvgCheck check = testing::CheckSvg(svg);
  ASSERT_TRUE(check.well_formed) << check.error;
  EXPECT_NE(svg.find(">33x<"), std::string::npos);
}

// 30 s at 100 Hz: a steady hover with one burst of fast moment changes at 12-15 s, and the
// rigid body lagging the rotor model by 20 ms.
WrenchSplit BurstFlight() {
  const int n = 3000;
  WrenchSplit split;
  split.t_s = Eigen::VectorXd::LinSpaced(n, 0.0, 29.99);
  split.rotor_model = Eigen::MatrixXd::Zero(n, 6);
  split.rigid_body = Eigen::MatrixXd::Zero(n, 6);
  auto moment = [](double t) {
    return t > 12.0 && t < 15.0 ? 0.3 * std::sin(2.0 * M_PI * 2.0 * t) : 0.01 * std::sin(t);
  };
  for (int i = 0; i < n; ++i) {
    const double t = split.t_s[i];
    split.rotor_model(i, 2) = 15.0 + 0.05 * std::sin(0.5 * t);
    split.rotor_model(i, 3) = moment(t);
    split.rigid_body(i, 2) = split.rotor_model(i, 2);
    split.rigid_body(i, 3) = moment(t - 0.02);
  }
  split.error = split.rigid_body - split.rotor_model;
  split.relative_error_pct = {std::nullopt, std::nullopt, 0.1, 5.0, std::nullopt, std::nullopt};
  return split;
}

TEST(WrenchFigureTest, TheZoomSitsOnTheMostExcitedStretchAndIsNotDecimated) {
  const WrenchSplit split = BurstFlight();
  const auto [start, end] = MostExcitedWindow(split, 5.0);
  EXPECT_NEAR(end - start, 5.0, 1e-9);
  EXPECT_LE(start, 12.0);
  EXPECT_GE(end, 15.0);
  // Shorter than the window: the whole flight.
  WrenchSplit short_flight = split;
  const auto [s0, s1] = MostExcitedWindow(short_flight, 60.0);
  EXPECT_EQ(s0, 0.0);
  EXPECT_NEAR(s1, 29.99, 1e-9);

  const FigureSpec f = WrenchFigure("fig_wrench_1", "burst", {{"linear", split}}, {}, 200, 5.0);
  EXPECT_NE(f.body.find("5 s zoom at"), std::string::npos);
  // The full-length curves are decimated to 200 points; the zoom keeps all 500 samples of its window.
  size_t longest_block = 0, current = 0;
  std::istringstream lines(f.data);
  for (std::string line; std::getline(lines, line);) {
    current = line.empty() ? 0 : current + 1;
    longest_block = std::max(longest_block, current);
  }
  EXPECT_GE(longest_block, 499u);
  EXPECT_LE(longest_block, 501u);
  EXPECT_EQ(WrenchFigure("fig_wrench_1", "burst", {{"linear", split}}, {}, 200, 0.0).body.find("zoom"),
            std::string::npos);

  const std::string svg = Render(f);
  if (svg.empty()) GTEST_SKIP() << "gnuplot is not installed";
  const testing::SvgCheck check = testing::CheckSvg(svg);
  ASSERT_TRUE(check.well_formed) << check.error;
  EXPECT_GE(check.max_path_vertices, 400);  // a zoomed curve drawn with every sample
}

}  // namespace
}  // namespace rotorid::internal

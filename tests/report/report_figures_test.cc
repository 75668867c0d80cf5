#include "report/report_figures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <regex>

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

}  // namespace
}  // namespace rotorid::internal

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "report/html_text.h"
#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"
#include "rotorid/predict/predict.h"

namespace rotorid {
namespace {

using internal::General;
using internal::Html;

constexpr const char* kUnits[kNumPredictionGroups] = {"m", "m/s", "rad", "rad/s"};
constexpr int kPanelWidth = 440, kPanelHeight = 260, kLeft = 62, kRight = 12, kTop = 26, kBottom = 40;

std::string Num(double v) { return FormatValue("%.1f", v); }

// One panel: MAE(h) of the model (solid) and of the naive predictor (dashed) against the time
// ahead, on a logarithmic axis (the model may sit decades below or above naive).
std::string Panel(const std::string& title, const std::string& unit, const std::vector<double>& model,
                  const std::vector<double>& naive, double dt_s) {
  double low = 1e300, high = 0.0;
  for (const std::vector<double>* curve : {&model, &naive})
    for (double v : *curve)
      if (std::isfinite(v) && v > 0.0) low = std::min(low, v), high = std::max(high, v);
  if (!(high > 0.0)) return "<p>" + Html(title) + ": no finite errors to draw.</p>\n";
  const double lo = std::floor(std::log10(low)), hi = std::max(lo + 1.0, std::ceil(std::log10(high)));
  const double plot_w = kPanelWidth - kLeft - kRight, plot_h = kPanelHeight - kTop - kBottom;
  const double horizon_s = model.size() * dt_s;
  const auto x = [&](size_t h) { return kLeft + plot_w * (static_cast<double>(h) * dt_s) / horizon_s; };
  const auto y = [&](double v) {
    const double l = std::log10(std::clamp(v, std::pow(10.0, lo), std::pow(10.0, hi)));
    return kTop + plot_h * (hi - l) / (hi - lo);
  };
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(kPanelWidth) +
                    "\" height=\"" + std::to_string(kPanelHeight) + "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  svg += "<text x=\"" + Num(kLeft) + "\" y=\"16\" font-size=\"13\">" + Html(title + " (" + unit + ")") + "</text>\n";
  for (double d = lo; d <= hi; d += 1.0)
    svg += "<line x1=\"" + Num(kLeft) + "\" x2=\"" + Num(kLeft + plot_w) + "\" y1=\"" + Num(y(std::pow(10.0, d))) +
           "\" y2=\"" + Num(y(std::pow(10.0, d))) + "\" stroke=\"#ddd\"/><text x=\"" + Num(kLeft - 4) + "\" y=\"" +
           Num(y(std::pow(10.0, d)) + 4) + "\" text-anchor=\"end\">1e" + std::to_string(static_cast<int>(d)) +
           "</text>\n";
  for (int k = 0; k <= 5; ++k) {
    const double t = horizon_s * k / 5.0, px = kLeft + plot_w * k / 5.0;
    svg += "<text x=\"" + Num(px) + "\" y=\"" + Num(kTop + plot_h + 16) + "\" text-anchor=\"middle\">" + General(t) +
           "</text>\n";
  }
  svg += "<text x=\"" + Num(kLeft + plot_w / 2) + "\" y=\"" + Num(kPanelHeight - 6) +
         "\" text-anchor=\"middle\">time ahead (s)</text>\n";
  const auto polyline = [&](const std::vector<double>& curve, const char* style) {
    std::string points;
    for (size_t h = 0; h < curve.size(); ++h)
      if (std::isfinite(curve[h])) points += Num(x(h + 1)) + "," + Num(y(curve[h])) + " ";
    return "<polyline fill=\"none\" " + std::string(style) + " points=\"" + points + "\"/>\n";
  };
  svg += polyline(naive, "stroke=\"#888\" stroke-width=\"2\" stroke-dasharray=\"6,4\"");
  svg += polyline(model, "stroke=\"#1f5fbf\" stroke-width=\"2\"");
  svg += "<rect x=\"" + Num(kLeft) + "\" y=\"" + Num(kTop) + "\" width=\"" + Num(plot_w) + "\" height=\"" +
         Num(plot_h) + "\" fill=\"none\" stroke=\"#444\"/>\n</svg>\n";
  return svg;
}

// The table of MAE at h = 1, 10, N with the ratio to naive, one row per group.
std::string SummaryTable(const PredictionCurves& curves, const std::vector<int>& steps) {
  std::string html = "<table><thead><tr><th>group</th>";
  for (int h : steps) html += "<th class=\"num\">h = " + std::to_string(h) + ": model / naive (ratio)</th>";
  html += "</tr></thead><tbody>\n";
  for (int g = 0; g < kNumPredictionGroups; ++g) {
    if (curves.mae[g].empty()) continue;
    html += "<tr><td>" + std::string(kPredictionGroupNames[g]) + " (" + kUnits[g] + ")</td>";
    for (int h : steps) {
      const double m = curves.mae[g][h - 1], n = curves.naive_mae[g][h - 1];
      html += "<td class=\"num\"" + std::string(m < n ? " style=\"color:#166016\"" : "") + ">" + General(m) + " / " +
              General(n) + " (" + FormatValue("%.2f", m / n) + ")</td>";
    }
    html += "</tr>\n";
  }
  return html + "</tbody></table>\n";
}

// The model's angular acceleration at the logged states against the body's, one row per band.
std::string TorqueBandTable(const std::vector<TorqueBand>& bands) {
  if (bands.empty()) return "";
  const auto pair = [](const Eigen::Vector3d& v) { return General(v[0]) + " / " + General(v[1]); };
  std::string html =
      "<table><thead><tr><th>band</th><th class=\"num\">body (rad/s<sup>2</sup> RMS, roll / pitch)</th>"
      "<th class=\"num\">model</th><th class=\"num\">error</th><th class=\"num\">gain</th>"
      "<th class=\"num\">error as a centre-of-mass shift (mm)</th></tr></thead><tbody>\n";
  for (const TorqueBand& b : bands)
    html += "<tr><td>" + Html(TorqueBandName(b)) + "</td><td class=\"num\">" + pair(b.body_rms_radps2) +
            "</td><td class=\"num\">" + pair(b.model_rms_radps2) + "</td><td class=\"num\">" +
            pair(b.error_rms_radps2) + "</td><td class=\"num\">" + TorqueBandGainText(b) + "</td><td class=\"num\">" +
            pair(b.centre_of_mass_equivalent_mm) +
            "</td></tr>\n";
  return html + "</tbody></table>\n";
}

}  // namespace

std::string PredictHtml(const PredictResult& result) {
  const PredictOptions& o = result.options;
  const std::vector<int> steps = PredictionSummarySteps(o.horizon_steps);
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>rotorid predict</title>\n"
      "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}table{border-collapse:collapse}"
      "td,th{border:1px solid #ccc;padding:3px 8px}.num{text-align:right}.bad{color:#a00}</style>\n</head>\n"
      "<body>\n<h1>rotorid predict</h1>\n<p><b>" +
      Html(PredictAnswer(result)) + "</b></p>\n<p>The " +
      Html(result.block) + " model of <code>" + Html(o.params_path) + "</code> flown open loop over " +
      std::to_string(o.horizon_steps) + " steps of " + General(o.dt_s) + " s from " +
      std::to_string(result.pooled.windows) + " logged states (" + PredictionScopeName(o.scope) +
      " scope), against the naive predictor x(t+h) = x(t) on the same windows. Green: below naive." +
      (o.torque_bias_window_s > 0.0 ? " Each window carries a constant body-frame torque bias observed over the " +
                                          General(o.torque_bias_window_s) + " s of the log before its start."
                                    : "") +
      "</p>\n";
  for (const Check& c : result.checks)
    if (c.status != CheckStatus::kOk)
      html += "<p class=\"bad\">check " + Html(c.name) + ": " + Html(c.message) + "</p>\n";
  html += "<h2>All flights</h2>\n" + SummaryTable(result.pooled, steps) + "<div>\n";
  for (int g = 0; g < kNumPredictionGroups; ++g)
    if (!result.pooled.mae[g].empty())
      html += Panel(kPredictionGroupNames[g], kUnits[g], result.pooled.mae[g], result.pooled.naive_mae[g], o.dt_s);
  html += "</div>\n<p>Solid blue: the model; dashed grey: naive. MAE against the time ahead, logarithmic.</p>\n";
  if (!result.torque_bands.empty())
    html +=
        "<h2>The model's torque against the body's, by frequency</h2>\n<p>The model's angular acceleration at every "
        "logged state with the logged rotor signal beside the body's (the gyro differentiated), split into bands. "
        "Gain: the body's per unit of the model's (1: the body follows the model's torque; near 0: it does not). A "
        "window integrates the error of the low bands: a constant error is what a torque bias observer takes out, "
        "what varies below 1 Hz grows the angular velocity error about linearly over a horizon of 0.5 s. The last "
        "column is the error as the shift of the centre of mass whose weight would exert it.</p>\n" +
        TorqueBandTable(result.torque_bands);
  for (const FlightPrediction& f : result.flights)
    html += "<h2>" + Html(f.file) + "</h2>\n<p>" + std::to_string(f.curves.windows) + " windows; " + Html(f.states) +
            "</p>\n" + SummaryTable(f.curves, steps) + TorqueBandTable(f.torque_bands);
  for (const Check& c : result.checks)
    html += "<p>check " + Html(c.name) + " (" + CheckStatusName(c.status) + "): " + Html(c.message) + "</p>\n";
  return html + "</body>\n</html>\n";
}

std::string WritePredictReport(const std::string& dir, const PredictResult& result) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(dir + ": cannot create the report folder: " + ec.message());
  const std::string path = (std::filesystem::path(dir) / "predict.html").string();
  WriteFileAtomically(path, PredictHtml(result));
  return path;
}

}  // namespace rotorid

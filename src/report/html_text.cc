#include "report/html_text.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "rotorid/core/text.h"
#include "rotorid/model/parameters.h"

namespace rotorid::internal {

std::string Html(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Sci(std::optional<double> v) { return v && std::isfinite(*v) ? FormatValue("%.4e", *v) : "&ndash;"; }

std::string Pct(std::optional<double> v, int digits) {
  if (!v || !std::isfinite(*v)) return "&ndash;";
  return FormatValue(digits == 1 ? "%.1f" : "%.2f", *v);
}

std::string General(double v) { return std::isfinite(v) ? FormatValue("%.4g", v) : "&ndash;"; }

std::string ComponentHeader(const std::vector<int>& components, const std::string& unit) {
  std::string out;
  for (const int c : components)
    out += "<th class=\"num\">" + std::string(kWrenchComponentNames[c]) + (unit.empty() ? "" : " (" + unit + ")") +
           "</th>";
  return out;
}

std::string ComponentCells(const std::vector<std::optional<double>>& values, const std::vector<int>& components) {
  std::string out;
  for (const int c : components)
    out += "<td class=\"num\">" + Pct(c < static_cast<int>(values.size()) ? values[c] : std::nullopt) + "</td>";
  return out;
}

namespace {

// "acc_bias_x" -> "acc_bias", "rotor_thrust_scale_3" -> "rotor_thrust_scale".
std::string WithoutAxisSuffix(const std::string& name) {
  const size_t underscore = name.rfind('_');
  if (underscore == std::string::npos || underscore + 1 >= name.size()) return name;
  const std::string tail = name.substr(underscore + 1);
  const bool axis = tail == "x" || tail == "y" || tail == "z" || std::all_of(tail.begin(), tail.end(), [](char c) {
                      return std::isdigit(static_cast<unsigned char>(c));
                    });
  return axis ? name.substr(0, underscore) : name;
}

}  // namespace

DisplayUnit EffectParameterUnit(const std::string& parameter_name) {
  const std::string name = WithoutAxisSuffix(parameter_name);
  if (EndsWith(name, "_s")) return {1e3, "ms"};
  if (EndsWith(name, "_rad")) return {180.0 / M_PI, "deg"};
  if (EndsWith(name, "_m")) return {1e3, "mm"};
  if (EndsWith(name, "_kgm2")) return {1.0, "kg m&sup2;"};
  // Sensor biases: in the unit of the sensor they bias.
  if (name.rfind("acc", 0) == 0 && EndsWith(name, "bias")) return {1.0, "m/s&sup2;"};
  if (name.rfind("gyro", 0) == 0 && EndsWith(name, "bias")) return {1.0, "rad/s"};
  return {1.0, ""};
}

std::string ValueWithStd(const std::vector<double>& value, const std::vector<double>& std_dev,
                         const DisplayUnit& unit) {
  if (value.empty()) return "&ndash;";
  const std::string suffix = unit.unit.empty() ? "" : " " + unit.unit;
  auto one = [&](size_t k) {
    if (std::isinf(value[k])) return std::string("unobservable");  // a detectable size none reaches
    return General(value[k] * unit.scale) +
           (k < std_dev.size() ? " &plusmn; " + General(std_dev[k] * unit.scale) : std::string()) + suffix;
  };
  if (value.size() == 1) return one(0);
  // A vector one component a line, so that a table cell stays narrow: "x: 0.011 ± 0.001 m/s²".
  static const char* const kAxes[] = {"x", "y", "z"};
  std::string out;
  for (size_t k = 0; k < value.size(); ++k)
    out +=
        std::string(k ? "<br/>" : "") + (value.size() == 3 ? kAxes[k] : std::to_string(k + 1).c_str()) + ": " + one(k);
  return out;
}

const char* ComponentUnit(int component) { return component < 3 ? "N" : "N m"; }

}  // namespace rotorid::internal

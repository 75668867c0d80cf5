#pragma once

// HTML text and number formatting shared by the report's sections (internal to the report module).

#include <optional>
#include <string>
#include <vector>

#include "rotorid/core/text.h"

namespace rotorid::internal {

// `text` with &, <, >, " and ' escaped.
std::string Html(const std::string& text);
// Parameter values: 4 significant digits in scientific notation, as the paper's tables; a dash
// when absent or not finite.
std::string Sci(std::optional<double> v);
// Percentages with 1 or 2 decimals; a dash when absent.
std::string Pct(std::optional<double> v, int digits = 2);
// %.4g; a dash when not finite.
std::string General(double v);

// <th> per wrench component (indices into kWrenchComponentNames), with an optional unit suffix.
std::string ComponentHeader(const std::vector<int>& components, const std::string& unit = "");
// <td class="num"> per component: Pct of values[c].
std::string ComponentCells(const std::vector<std::optional<double>>& values, const std::vector<int>& components);

// How an effect parameter is shown: its name's SI suffix (INTERFACE.md: delay_s, misalignment_rad,
// imu_position_m, rotor_inertia_kgm2) picks a readable unit (ms, deg, mm) and the scale into it;
// sensor biases are in the sensor's unit. An axis suffix (_x, _y, _z, _1 ...) is ignored.
struct DisplayUnit {
  double scale = 1.0;
  std::string unit;  // "" for dimensionless
};
DisplayUnit EffectParameterUnit(const std::string& parameter_name);
// "12.3 &plusmn; 0.4 ms"; a vector one component a line ("x: 0.011 &plusmn; 0.001 m/s&sup2;<br/>y:
// ..."). The std may be empty.
std::string ValueWithStd(const std::vector<double>& value, const std::vector<double>& std_dev, const DisplayUnit& unit);

// The unit of a wrench component: "N" or "N m".
const char* ComponentUnit(int component);

}  // namespace rotorid::internal

#pragma once

// The diagnosis part of the HTML report (internal to the report module), read from the keys that
// DiagnosisJson writes: the verdict first, then which effect (the ranking), how far the held-out
// gap shrinks, and where the gap is (component, frequency band, stretch of the flight, effect
// signatures), as tables with units and charts.

#include <functional>
#include <string>
#include <vector>

#include "report/report_figures.h"
#include "report/report_reader.h"

namespace rotorid::internal {

// True when the report is a diagnosis (it has DiagnosisJson's "ranking").
bool HasDiagnosis(const JsonNode& report);

// The figures of the diagnosis: fig_diagnosis (gap per component, shrink per effect),
// fig_diagnosis_bands (residual per frequency band before and after) and fig_diagnosis_signatures.
std::vector<FigureSpec> DiagnosisFigures(const JsonNode& report);

// The section's HTML; `figure` returns the HTML of a figure by name ("" when it was not made).
std::string DiagnosisHtml(const JsonNode& report, const std::function<std::string(const std::string&)>& figure);

// The frequency band (low, high Hz) holding most of the residual energy of where.component, to
// shade on the spectra; empty when the report has no bands.
std::vector<std::pair<double, double>> WorstBands(const JsonNode& report);

}  // namespace rotorid::internal

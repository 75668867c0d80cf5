#pragma once

// The diagnosis part of the HTML report (internal to the report module), from the Diagnosis that
// DiagnosisJson writes: the verdict first, then which effect (the ranking), how far the held-out
// gap shrinks, and where the gap is (component, frequency band, stretch of the flight, effect
// signatures), as tables with units and charts.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "report/report_figures.h"
#include "rotorid/diagnosis/diagnosis.h"

namespace rotorid::internal {

// The figures of the diagnosis: fig_diagnosis (gap per component, shrink per effect),
// fig_diagnosis_bands (residual per frequency band before and after) and fig_diagnosis_signatures.
std::vector<FigureSpec> DiagnosisFigures(const Diagnosis& diagnosis);

// The section's HTML; `figure` returns the HTML of a figure by name ("" when it was not made).
std::string DiagnosisHtml(const Diagnosis& diagnosis, const std::function<std::string(const std::string&)>& figure);

// The frequency band (low, high Hz) holding most of the residual energy of the where-component,
// to shade on the spectra; empty when the diagnosis has no bands.
std::vector<std::pair<double, double>> WorstBands(const Diagnosis& diagnosis);

}  // namespace rotorid::internal

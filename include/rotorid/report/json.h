#pragma once

// Machine-readable reports (INTERFACE.md section 5). Key names there are fixed; everything else
// is documented in docs/report_format.md.

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorid/ident/checks.h"
#include "rotorid/ident/identify.h"

namespace rotorid {

inline constexpr const char* kRotoridVersion = "0.1.0";

// A number for a report: JSON has no NaN or infinity, so they become null.
nlohmann::json JsonNumber(double value);

// One parameter of a solution as the reports show it: discarded parameters have value 0 (as used
// by the model) and the std, estimate and most correlated parameter of the moment they were dropped.
struct ParameterStatistics {
  double value = 0.0;
  double std = 0.0;
  double rel_std_pct = 0.0;
  bool essential = true;
  const DiscardedParameter* discarded = nullptr;  // into the solution; null unless the selection dropped it
};
// Of parameter `k` (named names[k]) of `solution`.
ParameterStatistics ParameterStatisticsOf(const std::vector<std::string>& names, const TlsSolution& solution,
                                          size_t k);

// {"value", "std", "rel_std_pct", "essential"} for every parameter of a solution (ParameterStatisticsOf);
// a discarded one also has "estimate_when_discarded", "most_correlated_with" and "correlation".
nlohmann::json ParametersJson(const std::vector<std::string>& names, const TlsSolution& solution);
// "bodies": per body the model predicts with (AssessBodies): whether it is physical, its centre of mass,
// principal moments about it and RMS extents, the distance (std) to the nearest physical body and,
// when it is not one, that body and the likely cause.
nlohmann::json BodiesJson(const CheckedParameters& parameters);
// {"Fx": null, "Fy": null, "Fz": 3.2, ...}
nlohmann::json ComponentsJson(const std::vector<std::optional<double>>& values);
nlohmann::json VectorJson(const Eigen::VectorXd& v);
nlohmann::json ObservationOptionsJson(const ObservationOptions& options);
nlohmann::json TlsOptionsJson(const TlsOptions& options);
ObservationOptions ObservationOptionsFromJson(const nlohmann::json& j);
nlohmann::json FlightFitJson(const FlightFit& fit);
// The "linear" block of identify and refine reports.
nlohmann::json LinearJson(const IdentificationResult& result);

// Parameter values by name from a report's "<block>.parameters" (refined when present, else
// linear, unless `block` names one): the reported values, or with `predicted` those the model
// predicts with (a discarded inertia's `predicts_with`: PredictionChi). Throws rotorid::Error naming
// the file on a malformed report.
std::map<std::string, double> ParameterValuesFromReport(const nlohmann::json& report, const std::string& source,
                                                        const std::string& block = "", bool predicted = false);

nlohmann::json ReadJsonFile(const std::string& path);
// Pretty JSON, written atomically.
void WriteJsonFile(const std::string& path, const nlohmann::json& j);

}  // namespace rotorid

#pragma once

// Internal: the JSON pieces the predict report and the diagnosis's step predictions share.

#include <array>
#include <nlohmann/json.hpp>
#include <vector>

#include "rotorid/predict/predict.h"

namespace rotorid::internal {

// {group: {"<h>": curve[h - 1]}} at the steps h, for the groups that have a curve.
nlohmann::json GroupsAtSteps(const std::array<std::vector<double>, kNumPredictionGroups>& curves,
                             const std::vector<int>& steps);

}  // namespace rotorid::internal

#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "rotorid/ident/checks.h"

namespace rotorid {

// checks[] of every report (INTERFACE.md section 5): [{name, status, message}, ...].
nlohmann::json ChecksJson(const std::vector<Check>& checks);

}  // namespace rotorid

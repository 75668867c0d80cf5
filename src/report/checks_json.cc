#include "rotorid/report/checks_json.h"

namespace rotorid {

nlohmann::json ChecksJson(const std::vector<Check>& checks) {
  nlohmann::json out = nlohmann::json::array();
  for (const Check& c : checks)
    out.push_back({{"name", c.name}, {"status", CheckStatusName(c.status)}, {"message", c.message}});
  return out;
}

}  // namespace rotorid

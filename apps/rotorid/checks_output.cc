#include <iostream>

#include "commands.h"

namespace rotorid::cli {

int PrintChecks(const std::vector<Check>& checks, bool quiet) {
  int warnings = 0, errors = 0;
  for (const Check& c : checks) {
    if (c.status == CheckStatus::kOk) continue;
    (c.status == CheckStatus::kError ? errors : warnings) += 1;
    if (quiet && c.status != CheckStatus::kError) continue;
    std::cerr << "rotorid: check " << c.name << ": " << CheckStatusName(c.status) << ": " << c.message << "\n";
  }
  if (!quiet)
    std::cout << "checks: " << checks.size() - warnings - errors << " ok, " << warnings << " warning(s), " << errors
              << " error(s)" << (errors ? " (exit 3: the report is written, but do not trust it)" : "") << "\n";
  return errors ? 3 : 0;
}

}  // namespace rotorid::cli

#pragma once

// The first screen of every HTML report (internal to the report module): what was found, before
// any table. The parameters that matter (kt, kd, each configuration's centre of mass and principal
// inertia) with their uncertainty, or why the flights do not fix one; the gap (Table III) and what
// closes it; the checks in one line, failures first; and the next step.

#include <string>

#include "rotorid/report/html_report.h"

namespace rotorid::internal {

std::string AnswerHtml(const ReportInput& input);

// The checks ordered failures first (errors, then warnings, then the passed ones), each group in
// the order the command ran them.
std::vector<Check> ChecksFailuresFirst(const std::vector<Check>& checks);

}  // namespace rotorid::internal

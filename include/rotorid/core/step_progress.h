#pragma once

#include <functional>

namespace rotorid {

// Progress of long library work: `done` of `total` steps, called from the calling thread after
// each step (the CLI draws it: rotorid/report/progress.h). An empty function reports nothing.
using StepProgress = std::function<void(int done, int total)>;

}  // namespace rotorid

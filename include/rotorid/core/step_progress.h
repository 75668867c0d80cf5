#pragma once

#include <functional>

namespace rotorid {

// Progress of long library work: `done` of `total` steps, called from the calling thread after
// each step (the CLI draws it: rotorid/report/progress.h). An empty function reports nothing.
using StepProgress = std::function<void(int done, int total)>;

// The progress of a part of the work that comes after `offset` steps of a `total`: the part's own
// count, reported on the whole's scale.
inline StepProgress OffsetProgress(const StepProgress& progress, int offset, int total) {
  if (!progress) return {};
  return [progress, offset, total](int done, int) { progress(offset + done, total); };
}

}  // namespace rotorid

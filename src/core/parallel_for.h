#pragma once

// Internal: the one thread pool of the library (the refinement, the diagnosis, reading text logs).

#include <functional>

namespace rotorid::internal {

// Runs task(i) for every i in [0, count) on up to `threads` threads (in this thread when one),
// each thread taking the next index as it finishes one. The first exception a task throws is
// rethrown here after every thread has stopped.
void ParallelFor(int count, int threads, const std::function<void(int)>& task);

}  // namespace rotorid::internal

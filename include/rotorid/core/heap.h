#pragma once

namespace rotorid {

// Sets up glibc's heap for a process that allocates and frees large arrays (log columns, the
// system's rows). Call first in main, before anything large is allocated; does nothing elsewhere.
void PrepareHeapForLargeArrays();

}  // namespace rotorid

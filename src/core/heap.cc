#include "rotorid/core/heap.h"

#include <cstdlib>  // defines __GLIBC__ with glibc

// glibc 2.33 or later (mallinfo2); not under AddressSanitizer, whose allocator replaces glibc's.
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
#if __GLIBC_PREREQ(2, 33)
#define ROTORID_TUNE_GLIBC_HEAP 1
#endif
#endif

#ifdef ROTORID_TUNE_GLIBC_HEAP
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#endif

namespace rotorid {

#ifdef ROTORID_TUNE_GLIBC_HEAP
namespace {

constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;  // x86-64 and arm64 with 4 KiB pages
constexpr std::size_t kMaxReserve = std::size_t{1} << 30;
constexpr int kMmapThreshold = 32 << 20;  // glibc's largest

}  // namespace

// A command allocates arrays of a log's length again and again (columns, filtered signals, rows),
// each freed soon after. glibc gives each large one fresh pages from the kernel (mmap) and returns
// them on free, so every one is faulted in page by page: 3700 faults, a third of an identify of a
// 90 s log on the project's virtual machine, and two thirds of one of a 1 h log. Here the arrays
// come from one heap that keeps what is freed, and the heap's first gigabyte is backed by 2 MiB
// pages where the kernel has them (transparent huge pages on request, the usual setting). Alone,
// on a loaded machine: 90 s identify 90 -> 56 ms, 1 h 4.1 -> 1.2 s, the same peak memory
// (docs/benchmarks.md, "Issue 14, eighth session").
void PrepareHeapForLargeArrays() {
  // Reserve at most a quarter of the machine's memory: virtual address space only, but a kernel
  // that does not overcommit counts it.
  const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page_size <= 0) return;
  const std::size_t reserve = std::min(kMaxReserve, static_cast<std::size_t>(pages) * page_size / 4);
  // Arrays up to glibc's largest threshold (32 MiB) from the main heap, not each from its own
  // mmap and munmap, and freed memory kept there for the next one instead of being returned and
  // faulted in again. One arena for every thread: memory freed in a thread's own arena is kept
  // there, out of the main thread's reach (refine of a 1 h log on 2 threads: 620 MB peak with
  // an arena per thread, 507 MB with one; diagnose as fast, refine with every effect about 10 %
  // slower in one three-run comparison: its evaluations allocate, and now share a lock).
  if (mallopt(M_MMAP_THRESHOLD, kMmapThreshold) == 0 ||
      mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max()) == 0 || mallopt(M_ARENA_MAX, 1) == 0)
    return;
  // Grow the heap once by `reserve`: a block larger than the free top forces the growth, and the
  // pad is added to it.
  mallopt(M_TOP_PAD, static_cast<int>(reserve));
  const std::size_t top = mallinfo2().keepcost;
  void* block = std::malloc(top + page_size);
  mallopt(M_TOP_PAD, 128 * 1024);  // glibc's default, for any growth beyond the reserve
  if (!block) return;
  const auto begin = (reinterpret_cast<std::uintptr_t>(block) + kHugePage - 1) & ~(kHugePage - 1);
  const auto end = reinterpret_cast<std::uintptr_t>(sbrk(0)) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
  std::free(block);
}
#else
void PrepareHeapForLargeArrays() {}
#endif

}  // namespace rotorid

#include "objmap/core/memory.h"

#include <malloc.h>
#include <sys/mman.h>

#include <cstdint>

namespace objmap {

bool keep_freed_memory() {
  // 32 MB: glibc's largest mmap threshold on 64-bit (HEAP_MAX_SIZE / 2); setting either value
  // also stops glibc adapting them.
  return mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024) == 1 &&
         mallopt(M_TRIM_THRESHOLD, 1024 * 1024 * 1024) == 1;
}

bool limit_malloc_arenas(int arenas) { return arenas > 0 && mallopt(M_ARENA_MAX, arenas) == 1; }

void advise_huge_pages(void* p, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t first = (at + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  const std::uintptr_t end = (at + bytes) / kHugePageBytes * kHugePageBytes;
  if (end > first) madvise(reinterpret_cast<void*>(first), end - first, MADV_HUGEPAGE);
#else
  (void)p;
  (void)bytes;
#endif
}

}  // namespace objmap

#include "objmap/core/memory.h"

#include <malloc.h>

namespace objmap {

bool keep_freed_memory() {
  // 32 MB: glibc's largest mmap threshold on 64-bit (HEAP_MAX_SIZE / 2); setting either value
  // also stops glibc adapting them.
  return mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024) == 1 &&
         mallopt(M_TRIM_THRESHOLD, 1024 * 1024 * 1024) == 1;
}

bool limit_malloc_arenas(int arenas) { return arenas > 0 && mallopt(M_ARENA_MAX, arenas) == 1; }

}  // namespace objmap

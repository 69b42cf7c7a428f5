// The global operator new and delete of the objmap executables (linked into them, not into the
// library: a program that links objmap keeps its own). A block of 2 MB and more gets transparent
// huge pages asked for (advise_huge_pages, core/memory.h) before it is handed out: the clouds,
// colour tables, keyframe buffers and sorted lists of a fuse or a publish are written whole right
// after they are allocated, and on the 2-core virtual machines objmap is measured on a 4 KB page
// written for the first time costs ~11 µs (a fault and its page-table work), a 2 MB page ~1 ms
// the first time and far less when the process had it before. Blocks of 32 MB and more are a
// mapping of their own (core/memory.h, keep_freed_memory), freed back to the kernel and mapped
// afresh each time. What it gives: docs/benchmarks.md, "The allocator".
//
// Not in builds with AddressSanitizer or ThreadSanitizer, whose runtimes bring operator new and
// delete of their own (to check them).
#include <cstdlib>
#include <new>

#include "objmap/core/memory.h"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define OBJMAP_OWN_OPERATOR_NEW 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define OBJMAP_OWN_OPERATOR_NEW 0
#endif
#endif
#ifndef OBJMAP_OWN_OPERATOR_NEW
#define OBJMAP_OWN_OPERATOR_NEW 1
#endif

#if OBJMAP_OWN_OPERATOR_NEW
// operator new[] and the nothrow forms of libstdc++ call these two; the aligned forms keep
// libstdc++'s (aligned_alloc, free).
void* operator new(std::size_t bytes) {
  for (;;) {
    if (void* p = std::malloc(bytes != 0 ? bytes : 1)) {
      if (bytes >= objmap::kHugePageBytes) objmap::advise_huge_pages(p, bytes);
      return p;
    }
    const std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#endif

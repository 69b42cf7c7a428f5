#pragma once
#include <cstddef>

// How the process's allocator treats memory it frees (glibc malloc), and huge pages.
namespace objmap {

// Freed memory is kept for the next allocation instead of going back to the kernel: blocks up to
// 32 MB come from the heap (not each from a fresh mmap) and the heap's free top is not trimmed.
// By default glibc maps every block above a threshold that adapts (from 128 kB) and trims freed
// tops, so a pipeline that frees and allocates buffers of tens of MB again and again (a follow
// publish, fuse's keyframe buffers) has the kernel zero and fault them in page by page each time
// (what it costs and saves: docs/benchmarks.md, "The allocator"). Call once, first thing in main.
// False when the allocator refused a setting.
bool keep_freed_memory();

// At most `arenas` malloc arenas (heaps) for the threads (glibc's default: 8 a core). Each arena
// keeps what its threads free (keep_freed_memory), so a process whose many short-lived threads
// allocate on a growing map (objmap follow's publishes, dense applies, scenes and reports) holds
// freed memory in each: follow limits them to its worker threads' count (docs/follow.md,
// "Memory"). Call before the threads start. False when the allocator refused it.
bool limit_malloc_arenas(int arenas);

// A transparent huge page (x86-64, and arm64 with 4 KB pages).
constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

// Asks the kernel for transparent huge pages (madvise MADV_HUGEPAGE) for the whole 2 MB pages
// inside [p, p + bytes); nothing for a block that holds none. A hint: where THP is off it does
// nothing, and memory works the same either way. Pages not yet written then come 2 MB at a time,
// one fault and one page-table entry each instead of 512. The objmap executables ask it for every
// block of 2 MB and more they allocate (core/huge_page_new.cpp).
void advise_huge_pages(void* p, std::size_t bytes);

}  // namespace objmap

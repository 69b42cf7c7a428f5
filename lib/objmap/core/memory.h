#pragma once

// How the process's allocator treats memory it frees (glibc malloc).
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

}  // namespace objmap

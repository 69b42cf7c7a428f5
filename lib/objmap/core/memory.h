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

}  // namespace objmap

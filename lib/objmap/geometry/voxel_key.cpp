#include "objmap/geometry/voxel_key.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>

#include "objmap/core/memory.h"

namespace objmap::geometry {

namespace {

std::size_t page_rounded(std::size_t bytes) {
  const std::size_t page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  return (bytes + page - 1) / page * page;
}

}  // namespace

// The mapping starts on a 2 MB boundary (mapped with room to spare, the spare trimmed), so that
// every whole 2 MB of it can be a huge page; its end stays where `bytes` ends (no page of memory
// beyond the table).
void* map_zeroed(std::size_t bytes) {
  const std::size_t size = page_rounded(bytes);
  const std::size_t room = size + kHugePageBytes;
  void* p = mmap(nullptr, room, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) return nullptr;
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t start = (at + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  if (start > at) munmap(p, start - at);
  if (at + room > start + size)
    munmap(reinterpret_cast<void*>(start + size), at + room - (start + size));
  void* table = reinterpret_cast<void*>(start);
  advise_huge_pages(table, size);  // a hint: without huge pages the table works the same
#ifdef MADV_POPULATE_WRITE
  // Its pages made now, written: a hash table is touched all over anyway, and a page first read
  // (a probe) maps the shared zero page, whose replacement on the write is a second fault and a
  // TLB flush on the other threads' cores (docs/fusion.md, "Voxel keys"). Kernels before 5.14
  // refuse it, and the pages come on first touch as before.
  madvise(table, size, MADV_POPULATE_WRITE);
#endif
  return table;
}

void unmap(void* p, std::size_t bytes) {
  if (p) munmap(p, page_rounded(bytes));
}

}  // namespace objmap::geometry

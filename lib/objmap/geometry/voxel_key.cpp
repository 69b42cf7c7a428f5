#include "objmap/geometry/voxel_key.h"

#include <sys/mman.h>

namespace objmap::geometry {

void* map_zeroed(std::size_t bytes) {
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) return nullptr;
#ifdef MADV_HUGEPAGE
  madvise(p, bytes, MADV_HUGEPAGE);  // a hint: without huge pages the table works the same
#endif
  return p;
}

void unmap(void* p, std::size_t bytes) {
  if (p) munmap(p, bytes);
}

}  // namespace objmap::geometry

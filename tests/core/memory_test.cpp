// keep_freed_memory: a buffer of tens of MB comes from the heap, not a fresh mapping, and the heap
// keeps it once freed (glibc's defaults map such a buffer and give freed tops back).
#include "objmap/core/memory.h"

#include <gtest/gtest.h>
#include <malloc.h>

#include <cstdlib>
#include <cstring>

namespace objmap {
namespace {

TEST(Memory, BuffersOfTensOfMegabytesComeFromTheHeapAndStayThereWhenFreed) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator replaces glibc's: no mallopt, no mallinfo2";
#endif
  ASSERT_TRUE(keep_freed_memory());
  constexpr std::size_t kBlock = 20u << 20;  // 20 MB: above glibc's default mmap threshold
  const std::size_t mapped_before = mallinfo2().hblkhd;
  char* block = static_cast<char*>(std::malloc(kBlock));
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBlock);
  EXPECT_EQ(mallinfo2().hblkhd, mapped_before);  // not a mapping of its own
  const std::size_t heap_with_block = mallinfo2().arena;
  EXPECT_GE(heap_with_block, kBlock);
  std::free(block);
  EXPECT_EQ(mallinfo2().arena, heap_with_block);  // not trimmed: the next buffer reuses it
}

}  // namespace
}  // namespace objmap

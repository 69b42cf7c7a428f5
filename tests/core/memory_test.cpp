// keep_freed_memory: a buffer of tens of MB comes from the heap, not a fresh mapping, and the heap
// keeps it once freed (glibc's defaults map such a buffer and give freed tops back).
// limit_malloc_arenas: threads share the arenas allowed.
#include "objmap/core/memory.h"

#include <gtest/gtest.h>
#include <malloc.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <vector>

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

// The heaps malloc_info lists (one <heap nr="…"> per arena).
int malloc_arenas() {
  char* text = nullptr;
  std::size_t size = 0;
  FILE* stream = open_memstream(&text, &size);
  malloc_info(0, stream);
  std::fclose(stream);
  int heaps = 0;
  for (const char* at = text; (at = std::strstr(at, "<heap nr=")) != nullptr; ++at) ++heaps;
  std::free(text);
  return heaps;
}

TEST(Memory, ThreadsAllocatingAtOnceShareAtMostTheArenasAllowed) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator replaces glibc's: no mallopt, no malloc_info";
#endif
  EXPECT_FALSE(limit_malloc_arenas(0));
  ASSERT_TRUE(limit_malloc_arenas(2));
  // Six threads holding a block each until all have one: glibc gives a contended thread an arena
  // of its own while it may make more.
  constexpr int kThreads = 6;
  std::atomic<int> holding{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < kThreads; ++i)
    threads.emplace_back([&holding] {
      std::vector<char> block(1 << 20, 1);
      ++holding;
      while (holding.load() < kThreads) std::this_thread::yield();
      EXPECT_EQ(block[1000], 1);
    });
  for (std::thread& t : threads) t.join();
  EXPECT_GE(malloc_arenas(), 1);
  EXPECT_LE(malloc_arenas(), 2);
}

}  // namespace
}  // namespace objmap

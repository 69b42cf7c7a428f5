// keep_freed_memory: a buffer of tens of MB comes from the heap, not a fresh mapping, and the heap
// keeps it once freed (glibc's defaults map such a buffer and give freed tops back).
// limit_malloc_arenas: threads share the arenas allowed.
// advise_huge_pages and the executables' operator new (core/huge_page_new.cpp, linked into this
// test): the hint covers the whole 2 MB pages of a block, and a large block from new is backed by
// huge pages once written.
#include "objmap/core/memory.h"

#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/mman.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
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

// A mapping of /proc/self/smaps: its range, VmFlags and AnonHugePages.
struct SmapsArea {
  std::uintptr_t begin = 0, end = 0;
  bool huge_advised = false;  // VmFlags "hg": MADV_HUGEPAGE
  std::size_t anon_huge_kb = 0;
};

// The mapping that holds `address` (begin == end when none does).
SmapsArea smaps_area_of(const void* address) {
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream in("/proc/self/smaps");
  std::string line;
  SmapsArea area;
  bool inside = false;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string first;
    fields >> first;
    unsigned long begin = 0, end = 0;
    if (first.back() != ':' && std::sscanf(first.c_str(), "%lx-%lx", &begin, &end) == 2) {
      if (inside) return area;  // the next mapping's header: the one asked for is complete
      inside = at >= begin && at < end;
      area = {};
      if (inside) area.begin = begin, area.end = end;
      continue;
    }
    if (!inside) continue;
    if (first == "AnonHugePages:") fields >> area.anon_huge_kb;
    if (first == "VmFlags:")
      for (std::string flag; fields >> flag;) area.huge_advised |= flag == "hg";
  }
  return inside ? area : SmapsArea{};
}

// The kernel's THP mode: "always", "madvise" or "never" ("" where it has no THP).
std::string thp_mode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string text;
  std::getline(in, text);
  const std::size_t open = text.find('['), close = text.find(']');
  return open == std::string::npos || close == std::string::npos
             ? std::string()
             : text.substr(open + 1, close - open - 1);
}

TEST(Memory, TheHugePageHintCoversTheWholeTwoMegabytePagesInsideABlock) {
  if (thp_mode().empty()) {
    GTEST_SKIP() << "this kernel has no transparent huge pages";
  }
  constexpr std::size_t kMb = std::size_t{1} << 20;
  // 12 MB mapped; a 2 MB-aligned base inside it with 8 MB after it.
  const std::size_t room = 12 * kMb;
  void* mapped = mmap(nullptr, room, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(mapped, MAP_FAILED);
  const std::uintptr_t base = (reinterpret_cast<std::uintptr_t>(mapped) + kHugePageBytes - 1) /
                              kHugePageBytes * kHugePageBytes;
  char* const b = reinterpret_cast<char*>(base);
  advise_huge_pages(b + 1 * kMb, 5 * kMb);  // [1, 6) MB: the whole pages [2, 6) MB
  const SmapsArea hinted = smaps_area_of(b + 2 * kMb);
  EXPECT_TRUE(hinted.huge_advised);
  EXPECT_EQ(hinted.begin, base + 2 * kMb);
  EXPECT_EQ(hinted.end, base + 6 * kMb);
  EXPECT_FALSE(smaps_area_of(b + 1 * kMb).huge_advised);
  EXPECT_FALSE(smaps_area_of(b + 6 * kMb).huge_advised);
  advise_huge_pages(b + 1 * kMb, 2 * kMb);  // [1, 3) MB holds no whole page: nothing changes
  EXPECT_FALSE(smaps_area_of(b + 1 * kMb).huge_advised);
  munmap(mapped, room);
}

TEST(Memory, ALargeBlockFromNewIsBackedByHugePagesOnceWritten) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "the sanitizer's runtime brings its own operator new";
#endif
  const std::string mode = thp_mode();
  if (mode.empty() || mode == "never") {
    GTEST_SKIP() << "transparent huge pages are off";
  }
  constexpr std::size_t kBlock = std::size_t{40} << 20;  // a mapping of its own (over 32 MB)
  std::unique_ptr<char[]> block(new char[kBlock]);
  std::memset(block.get(), 1, kBlock);
  const SmapsArea area = smaps_area_of(block.get() + kBlock / 2);
  ASSERT_LT(area.begin, area.end) << "no mapping holds the block";
  if (mode == "madvise") {
    EXPECT_TRUE(area.huge_advised);
  }
  // All but the partial 2 MB pages at the block's two ends; less only if the kernel found no free
  // huge page, which a test machine with memory to spare does.
  EXPECT_GE(area.anon_huge_kb, (kBlock - 2 * kHugePageBytes) / 1024);
  EXPECT_EQ(block[kBlock - 1], 1);
}

}  // namespace
}  // namespace objmap

#include "objmap/geometry/voxel_key.h"
#include "objmap/geometry/voxel_key_set.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>

namespace objmap::geometry {
namespace {

TEST(VoxelKey, PacksAndUnpacksNegativeCoordinatesAndSortsByXYZ) {
  EXPECT_EQ(unpack_voxel(pack_voxel(-3, 7, -1048576)), Eigen::Vector3i(-3, 7, -1048576));
  EXPECT_EQ(voxel_key(Vec3f(-0.005f, 0.015f, 0.0f), 100.f), pack_voxel(-1, 1, 0));
  EXPECT_LT(pack_voxel(-1, 5, 5), pack_voxel(0, -5, -5));
  EXPECT_LT(pack_voxel(0, -1, 5), pack_voxel(0, 0, -5));
  EXPECT_EQ(voxel_key(Vec3f(std::numeric_limits<float>::quiet_NaN(), 0, 0), 100.f), kNoVoxel);
  EXPECT_EQ(voxel_key(Vec3f(2e4f, 0, 0), 100.f), kNoVoxel);  // 20 km: out of range
}

TEST(VoxelHashTable, GrowsAndFindsEveryKey) {
  VoxelHashTable<int> table;
  for (int i = 0; i < 10000; ++i) table[pack_voxel(i % 37, i / 37, -i)] += i;
  EXPECT_EQ(table.size(), 10000u);
  for (int i = 0; i < 10000; ++i) {
    const int* v = table.find(pack_voxel(i % 37, i / 37, -i));
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(*v, i);
  }
  EXPECT_EQ(table.find(pack_voxel(1000, 1000, 1000)), nullptr);
  const auto keys = table.sorted_keys();
  EXPECT_TRUE(std::is_sorted(keys.begin(), keys.end()));
}

TEST(VoxelKeySet, HoldsEachKeyOnceAndGivesThemBackEmptied) {
  VoxelKeySet set;
  std::vector<VoxelKey> want;
  for (int i = 0; i < 5000; ++i) want.push_back(pack_voxel(i % 71, -i / 71, i % 3));
  for (int round = 0; round < 3; ++round)  // every key met three times, the last round reversed
    for (int i = 0; i < 5000; ++i) {
      const VoxelKey key = want[round == 2 ? 4999 - i : i];
      set.prefetch(key);
      EXPECT_EQ(set.insert(key), round == 0) << i;
    }
  EXPECT_EQ(set.size(), 5000u);
  EXPECT_LE(set.size() * 4, set.capacity() * 3);  // at most 3/4 full
  std::vector<VoxelKey> got = {kNoVoxel};         // take appends
  set.take(got);
  EXPECT_EQ(got.size(), 5001u);
  EXPECT_EQ(set.size(), 0u);
  got.erase(got.begin());
  std::sort(got.begin(), got.end());
  std::sort(want.begin(), want.end());
  EXPECT_EQ(got, want);
  // Emptied, it keeps its slots for a fill of the same size; a small fill after a large one
  // lets the large slot array go at the next take.
  const std::size_t capacity = set.capacity();
  EXPECT_TRUE(set.insert(want[7]));
  EXPECT_EQ(set.capacity(), capacity);
  got.clear();
  set.take(got);
  EXPECT_EQ(got, std::vector<VoxelKey>{want[7]});
  EXPECT_EQ(set.capacity(), 0u);
  EXPECT_TRUE(set.insert(want[7]));  // and fills again from nothing
  EXPECT_FALSE(set.insert(want[7]));
}

TEST(VoxelHashTable, ATableMadeWhereDirtyMemoryWasFreedStartsEmpty) {
  // The slots below 2 MB come from malloc and are zeroed by the table (not by calloc): blocks of
  // the tables' sizes filled with ones and freed first, so that the heap hands their memory out
  // again; every table made after them is empty, and finds only what was put in.
  for (std::size_t slots : {std::size_t{1024}, std::size_t{16384}, std::size_t{65536}}) {
    const std::size_t bytes = slots * sizeof(VoxelHashTable<int>::Slot);
    for (int round = 0; round < 3; ++round) {
      void* dirty = std::malloc(bytes);
      ASSERT_NE(dirty, nullptr);
      std::memset(dirty, 0xff, bytes);
      std::free(dirty);
    }
    VoxelHashTable<int> table(slots / 2);
    ASSERT_EQ(table.capacity(), slots);
    std::size_t entries = 0;
    table.for_each([&](VoxelKey, int) { ++entries; });
    EXPECT_EQ(entries, 0u) << slots << " slots";
    table[pack_voxel(1, 2, 3)] = 7;
    EXPECT_EQ(table.size(), 1u);
    EXPECT_EQ(table.find(pack_voxel(3, 2, 1)), nullptr);
    ASSERT_NE(table.find(pack_voxel(1, 2, 3)), nullptr);
    EXPECT_EQ(*table.find(pack_voxel(1, 2, 3)), 7);
  }
}

TEST(VoxelHashTable, ACopyOfAMappedTableHoldsEveryKeyAndLivesOnItsOwn) {
  // A table above 2 MB of slots is mapped from the kernel; its copy comes from malloc. Both hold
  // the same entries, change apart, and each is freed the way it was made (ASan in `make sanitize`
  // checks the frees; a grown copy gets mapped slots again).
  VoxelHashTable<int> table;
  const int n = 200000;  // 2^19 slots of 16 bytes: 8 MB
  for (int i = 0; i < n; ++i) table[pack_voxel(i % 500, i / 500, -i % 7)] = i;
  ASSERT_GE(table.memory_bytes(), std::size_t{2} << 20);
  auto copy = std::make_unique<VoxelHashTable<int>>(table);
  EXPECT_EQ(copy->size(), table.size());
  EXPECT_EQ(copy->capacity(), table.capacity());
  table[pack_voxel(1, 1, 1)] = -1;
  (*copy)[pack_voxel(2, 2, 2)] = -2;
  for (int i = 0; i < n; i += 997) {
    const VoxelKey key = pack_voxel(i % 500, i / 500, -i % 7);
    ASSERT_NE(copy->find(key), nullptr) << i;
    EXPECT_EQ(*copy->find(key), i);
  }
  EXPECT_EQ(copy->find(pack_voxel(1, 1, 1)), nullptr);
  EXPECT_EQ(table.find(pack_voxel(2, 2, 2)), nullptr);
  for (int i = n; i < 2 * n; ++i) (*copy)[pack_voxel(i % 500, i / 500, 9)] = i;  // grows
  EXPECT_GT(copy->capacity(), table.capacity());
  EXPECT_EQ(*copy->find(pack_voxel(1, 401, 9)), 200501);
  VoxelHashTable<int> assigned;
  assigned = *copy;
  copy.reset();
  EXPECT_EQ(assigned.size(), table.size() + n);
  EXPECT_EQ(*assigned.find(pack_voxel(2, 2, 2)), -2);
}

TEST(VoxelHashTable, EraseKeepsEveryOtherKeyFindable) {
  // A table at its fullest (5/8), so with long clusters: every third key erased, the rest still
  // found with their values, the erased ones not; inserting again reuses the slots.
  VoxelHashTable<int> table;
  const int n = 640;  // 640 of 1024 slots
  for (int i = 0; i < n; ++i) table[pack_voxel(i, -i, 3)] = i;
  ASSERT_EQ(table.capacity(), 1024u);
  std::size_t erased = 0;
  for (int i = 0; i < n; i += 3) erased += table.erase(pack_voxel(i, -i, 3));
  EXPECT_EQ(erased, 214u);
  EXPECT_FALSE(table.erase(pack_voxel(0, 0, 3)));  // erased already
  EXPECT_EQ(table.size(), static_cast<std::size_t>(n) - 214u);
  EXPECT_EQ(table.capacity(), 1024u);
  for (int i = 0; i < n; ++i) {
    const int* v = table.find(pack_voxel(i, -i, 3));
    if (i % 3 == 0) {
      EXPECT_EQ(v, nullptr) << i;
    } else {
      ASSERT_NE(v, nullptr) << i;
      EXPECT_EQ(*v, i);
    }
  }
  std::size_t visited = 0;
  table.for_each([&](VoxelKey, int v) { visited += v % 3 != 0; });
  EXPECT_EQ(visited, table.size());
  for (int i = 0; i < n; i += 3) table[pack_voxel(i, -i, 3)] = -i;
  EXPECT_EQ(table.size(), static_cast<std::size_t>(n));
  EXPECT_EQ(table.capacity(), 1024u);
  EXPECT_EQ(*table.find(pack_voxel(3, -3, 3)), -3);
  for (int i = 0; i < n; ++i) EXPECT_TRUE(table.erase(pack_voxel(i, -i, 3)));
  EXPECT_TRUE(table.empty());
  EXPECT_EQ(table.find(pack_voxel(1, -1, 3)), nullptr);
}

}  // namespace
}  // namespace objmap::geometry

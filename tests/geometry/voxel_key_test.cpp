#include "objmap/geometry/voxel_key.h"

#include <gtest/gtest.h>

#include <limits>

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

}  // namespace
}  // namespace objmap::geometry

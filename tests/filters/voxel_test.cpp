#include "objmap/filters/voxel.h"

#include <gtest/gtest.h>

#include <limits>

namespace objmap::filters {
namespace {

TEST(VoxelFilter, CountIsExactOnAGrid) {
  // 10×10×10 voxels of 1 cm, 4 points in each (x = 0.3, 0.4, 0.5, 0.6 cm into the voxel).
  PointCloud cloud;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k)
        for (int s = 0; s < 4; ++s)  // 4 points in the same 1 cm voxel
          cloud.push_back(Vec3f(0.01f * i + 0.003f + 0.001f * s, 0.01f * j + 0.005f,
                                0.01f * k + 0.005f - 0.05f),
                          Rgb{static_cast<std::uint8_t>(10 * s), 100, 200});
  const VoxelFilterResult r = voxel_filter(cloud, {0.01});
  ASSERT_EQ(r.kept.size(), 1000u);
  for (std::uint32_t c : r.counts) EXPECT_EQ(c, 4u);
  // Centroid of the 4 points and their mean colour (0+10+20+30)/4 = 15.
  EXPECT_NEAR(r.kept.points[0].x(), 0.0045f, 1e-6);
  EXPECT_NEAR(r.kept.points[0].z(), -0.045f, 1e-6);
  EXPECT_EQ(r.kept.colors[0], (Rgb{15, 100, 200}));
  // Sorted by voxel: x, then y, then z.
  EXPECT_LT(r.kept.points[0].z(), r.kept.points[1].z());
  EXPECT_EQ(r.voxel_of_point[0], 0u);
  EXPECT_EQ(r.voxel_of_point[4], 1u);

  // 2 cm: x and y in [0, 0.1) span 5 voxels each, z in [-0.05, 0.05) spans 6 (-3..2: -0.045 and
  // 0.045 fall in the half-filled voxels -3 and 2).
  const VoxelFilterResult coarse = voxel_filter(cloud, {0.02});
  EXPECT_EQ(coarse.kept.size(), 5u * 5u * 6u);
}

TEST(VoxelFilter, DropsNonFinitePointsAndKeepsInputOrderIndependence) {
  PointCloud a;
  a.push_back(Vec3f(0.005f, 0.005f, 0.005f));
  a.push_back(Vec3f(1.005f, 0.005f, 0.005f));
  a.push_back(Vec3f(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  PointCloud b;
  b.push_back(a.points[1]);
  b.push_back(a.points[0]);
  const auto ra = voxel_filter(a), rb = voxel_filter(b);
  EXPECT_EQ(ra.dropped, 1u);
  EXPECT_EQ(ra.voxel_of_point[2], VoxelFilterResult::kDropped);
  EXPECT_EQ(ra.kept.points, rb.kept.points);
}

}  // namespace
}  // namespace objmap::filters

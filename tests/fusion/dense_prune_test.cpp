#include "objmap/fusion/dense_prune.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/fusion/voxel_map.h"

namespace objmap::fusion {
namespace {

// A pinhole camera (no distortion) looking along +z from the world origin at a wall 2 m away.
Camera wall_camera() {
  Camera c;
  c.fx = c.fy = 500.0;
  c.cx = 319.5;
  c.cy = 239.5;
  return c;
}
cv::Mat wall_depth(double z_m, double factor) {
  return cv::Mat(480, 640, CV_16UC1, cv::Scalar(static_cast<double>(z_m * factor)));
}

// The wall's voxels (z index 200) with 10 points each, and single points at `extra`.
PointCloud wall_points(const std::vector<Vec3f>& extra) {
  PointCloud c;
  for (int i = -20; i < 20; ++i)
    for (int j = -20; j < 20; ++j)
      for (int k = 0; k < 10; ++k)
        c.push_back(Vec3f(0.01f * i + 0.005f, 0.01f * j + 0.005f, 2.0002f + 0.0004f * k));
  for (const Vec3f& p : extra) c.push_back(p);
  return c;
}

TEST(DensePrune, DropsVoxelsTheViewsPutTheSurfaceElsewhereAndKeepsTheSurface) {
  const Camera camera = wall_camera();
  RecentViews views(camera, 8);
  // Eight views of the wall with ±6 mm of depth noise; the latest five decide, their median (1.994
  // m) is 8 mm in front of the wall voxels' mean points (2.002 m): within a voxel.
  for (int v = 0; v < 8; ++v)
    views.add(wall_depth(v % 2 ? 1.994 : 2.006, camera.depth_factor), Pose::Identity());
  const Vec3f behind(0.055f, 0.055f, 2.045f);     // 4.5 cm behind the wall: the surface is in front
  const Vec3f in_front(-0.105f, 0.025f, 1.965f);  // 3.5 cm in front: the rays went through it
  const Vec3f flying(0.105f, -0.095f, 1.5f);      // 0.5 m in front (a flying pixel): free space
  const Vec3f occluded(0.155f, 0.155f, 2.5f);     // 0.5 m behind the wall: hidden, no evidence
  const Vec3f outside(5.005f, 0.005f, 2.005f);    // outside every view
  VoxelMap map({0.01, 2, 4});                     // 4 shards by x: the voxels spread over them
  map.remember_new_voxels();
  map.insert(wall_points({behind, in_front, flying, occluded, outside}));
  ASSERT_EQ(map.size(), 1600u + 5u);
  const DensePruneOptions options;  // 1 voxel of tolerance, 3 views at least, 5 are enough
  const VoxelMap::Judge is_noise = [&](const std::vector<VoxelKey>& keys,
                                       const std::vector<const VoxelData*>& voxels,
                                       std::vector<std::uint8_t>& noise) {
    std::vector<Vec3> points;
    for (std::size_t i = 0; i < keys.size(); ++i)
      points.push_back(map.mean_position(keys[i], *voxels[i]));
    views.judge(points, map.voxel_m(), options, noise);
  };
  EXPECT_EQ(map.prune_remembered(is_noise), 0u);  // the first call judges nothing yet
  EXPECT_EQ(map.prune_remembered(is_noise), 3u);
  for (const Vec3f& p : {behind, in_front, flying}) EXPECT_FALSE(map.contains(map.key_of(p)));
  for (const Vec3f& p : {occluded, outside}) EXPECT_TRUE(map.contains(map.key_of(p)));
  for (int i = -20; i < 20; ++i)
    for (int j = -20; j < 20; ++j)
      ASSERT_TRUE(map.contains(geometry::pack_voxel(i, j, 200))) << i << " " << j;
  EXPECT_EQ(map.voxels_pruned(), 3u);
  EXPECT_EQ(map.prune_remembered(is_noise), 0u);  // each voxel is judged once
}

TEST(DensePrune, FewViewsGiveNoVerdictAndTheToleranceIsInVoxels) {
  const Camera camera = wall_camera();
  const Vec3 behind(0.0, 0.0, 2.025);  // 2.5 cm behind the wall
  RecentViews two(camera, 8);
  for (int v = 0; v < 2; ++v) two.add(wall_depth(2.0, camera.depth_factor), Pose::Identity());
  DensePruneOptions options;
  EXPECT_FALSE(two.contradicted(behind, 0.01, options));  // 2 views < min_views 3
  options.min_views = 2;
  EXPECT_TRUE(two.contradicted(behind, 0.01, options));
  options.tolerance_voxels = 3.0;  // 3 cm: within
  EXPECT_FALSE(two.contradicted(behind, 0.01, options));
  // The oldest view goes first: capacity 2, the last two views see the wall 2.5 cm farther.
  RecentViews moved(camera, 2);
  for (double z : {2.0, 2.025, 2.025})
    moved.add(wall_depth(z, camera.depth_factor), Pose::Identity());
  EXPECT_EQ(moved.size(), 2u);
  options = DensePruneOptions();
  options.min_views = 2;
  EXPECT_FALSE(moved.contradicted(behind, 0.01, options));
  // A camera moved 1 m back along its axis measures the same wall at 3 m.
  RecentViews back(camera, 4);
  Pose world_from_cam = Pose::Identity();
  world_from_cam.translation() = Vec3(0.0, 0.0, -1.0);
  for (int v = 0; v < 3; ++v) back.add(wall_depth(3.0, camera.depth_factor), world_from_cam);
  EXPECT_FALSE(back.contradicted(Vec3(0.0, 0.0, 2.005), 0.01, DensePruneOptions()));
  EXPECT_TRUE(back.contradicted(behind, 0.01, DensePruneOptions()));
  // Bad options and images name what is wrong.
  options.truncation_m = 0.0;
  EXPECT_THROW(options.check(), InputError);
  EXPECT_THROW(back.add(cv::Mat(480, 640, CV_8UC1), Pose::Identity()), InputError);
  VoxelMap plain({0.01, 1, 4});
  const VoxelMap::Judge everything =
      [](const std::vector<VoxelKey>& keys, const std::vector<const VoxelData*>&,
         std::vector<std::uint8_t>& noise) { noise.assign(keys.size(), 1); };
  EXPECT_THROW(plain.prune_remembered(everything), InputError);
}

}  // namespace
}  // namespace objmap::fusion

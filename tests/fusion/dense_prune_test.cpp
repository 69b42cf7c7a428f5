#include "objmap/fusion/dense_prune.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
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

// judge_peaks() of the map's remembered voxels against `views`.
VoxelMap::Judge peak_judge(const VoxelMap& map, const RecentViews& views,
                           const DensePruneOptions& options) {
  return [&map, &views, options](const std::vector<VoxelKey>& keys,
                                 const std::vector<const VoxelData*>& voxels,
                                 std::vector<std::uint8_t>& noise) {
    std::vector<Vec3> points;
    std::vector<std::uint32_t> counts;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      points.push_back(map.mean_position(keys[i], *voxels[i]));
      counts.push_back(voxels[i]->count);
    }
    views.judge_peaks(points, counts, map, options, noise);
  };
}

DensePruneOptions peak_options(double ratio, int rejudge) {
  DensePruneOptions options;
  options.peak_ratio = ratio;
  options.rejudge = rejudge;
  return options;
}

TEST(DensePrunePeak, DropsVoxelsBesideABusierVoxelAlongTheRayAndKeepsTheSurface) {
  const Camera camera = wall_camera();
  RecentViews views(camera, 4);
  views.add(wall_depth(2.0, camera.depth_factor), Pose::Identity());
  // σ(2 m) = 6 mm: the ray is searched within ±1.2 cm (2σ), i.e. the voxels next to the wall's.
  const Vec3f behind(0.005f, 0.005f, 2.015f);      // one point 1.5 cm behind the wall (10 each)
  const Vec3f in_front(0.025f, 0.015f, 1.988f);    // one point 1.2 cm in front
  const Vec3f far_behind(0.055f, 0.055f, 2.045f);  // 4.5 cm behind: beyond 2σ, kept
  VoxelMap map({0.01, 2, 4});
  map.remember_new_voxels();
  map.insert(wall_points({behind, in_front, far_behind}));
  const VoxelMap::Judge judge = peak_judge(map, views, peak_options(0.75, 0));
  EXPECT_EQ(map.prune_remembered(judge), 0u);  // the first call judges nothing yet
  EXPECT_EQ(map.prune_remembered(judge), 2u);
  EXPECT_FALSE(map.contains(map.key_of(behind)));
  EXPECT_FALSE(map.contains(map.key_of(in_front)));
  EXPECT_TRUE(map.contains(map.key_of(far_behind)));
  for (int i = -20; i < 20; ++i)
    for (int j = -20; j < 20; ++j)
      ASSERT_TRUE(map.contains(geometry::pack_voxel(i, j, 200))) << i << " " << j;
}

TEST(DensePrunePeak, ASurvivorIsJudgedAgainOnceItsNeighbourHasGrown) {
  const Camera camera = wall_camera();
  RecentViews views(camera, 4);
  views.add(wall_depth(2.0, camera.depth_factor), Pose::Identity());
  const Vec3f surface(0.005f, 0.005f, 2.005f), beside(0.005f, 0.005f, 2.015f);
  for (const int rejudge : {0, 1}) {
    VoxelMap map({0.01, 1, 2});
    map.remember_new_voxels(rejudge);
    PointCloud first;  // two points each: equal, both survive their first judgement
    for (const Vec3f& p : {surface, surface, beside, beside}) first.push_back(p);
    map.insert(first);
    const VoxelMap::Judge judge = peak_judge(map, views, peak_options(0.75, rejudge));
    EXPECT_EQ(map.prune_remembered(judge), 0u);  // call 0: nothing to judge
    EXPECT_EQ(map.prune_remembered(judge), 0u);  // call 1: both judged, both kept
    PointCloud more;  // the surface gets ten more points (no voxel opened)
    for (int k = 0; k < 10; ++k) more.push_back(surface);
    map.insert(more);
    EXPECT_EQ(map.prune_remembered(judge), 0u);  // call 2: nothing due
    // Call 3 (two calls after the first judgement): the survivors are judged again.
    EXPECT_EQ(map.prune_remembered(judge), rejudge == 1 ? 1u : 0u) << "rejudge " << rejudge;
    EXPECT_EQ(map.contains(map.key_of(beside)), rejudge == 0);
    EXPECT_TRUE(map.contains(map.key_of(surface)));
    for (int call = 0; call < 8; ++call) EXPECT_EQ(map.prune_remembered(judge), 0u);
  }
}

// A wall 2 m away with Gaussian depth noise (σ 8 mm), `frames` points per column: the surface
// voxels stay, the slab thins, and the map does not depend on the thread count.
TEST(DensePrunePeak, ANoisyWallThinsToItsSurfaceTheSameOnAnyThreadCount) {
  const Camera camera = wall_camera();
  RecentViews views(camera, 4);
  views.add(wall_depth(2.0, camera.depth_factor), Pose::Identity());
  std::vector<VoxelMap::VoxelPoints> results;
  std::size_t before = 0;
  for (const int threads : {1, 3}) {
    VoxelMap map({0.01, threads, 4});
    map.remember_new_voxels(2);
    std::mt19937 rng(7);
    std::normal_distribution<float> noise(0.f, 0.008f);
    const VoxelMap::Judge judge = peak_judge(map, views, peak_options(0.75, 2));
    for (int frame = 0; frame < 24; ++frame) {
      PointCloud cloud;
      for (int i = -20; i < 20; ++i)
        for (int j = -20; j < 20; ++j)
          for (int k = 0; k < 4; ++k)
            cloud.push_back(Vec3f(0.01f * i + 0.005f, 0.01f * j + 0.005f, 2.005f + noise(rng)));
      map.insert(cloud);
      if (threads == 1 && frame == 7) before = map.size();  // what 8 frames open, unpruned
      if (frame % 4 == 3) map.prune_remembered(judge);
    }
    // Every column keeps a voxel at the surface or next to it (a surface voxel that loses to its
    // neighbour early, when both have few points, stays dropped: the neighbour holds the surface).
    for (int i = -20; i < 20; ++i)
      for (int j = -20; j < 20; ++j)
        ASSERT_TRUE(map.contains(geometry::pack_voxel(i, j, 200)) ||
                    map.contains(geometry::pack_voxel(i, j, 199)) ||
                    map.contains(geometry::pack_voxel(i, j, 201)))
            << i << " " << j;
    EXPECT_LT(map.size(), before / 2);  // the slab: less than half of it after 24 frames
    results.push_back(map.sorted_points());
  }
  ASSERT_EQ(results[0].size(), results[1].size());
  for (std::size_t i = 0; i < results[0].size(); ++i)
    ASSERT_EQ(results[0][i].key, results[1][i].key);
}

TEST(DensePrunePeak, BadOptionsNameTheField) {
  EXPECT_THROW(peak_options(1.5, 0).check(), InputError);
  EXPECT_THROW(peak_options(-0.1, 0).check(), InputError);
  EXPECT_THROW(peak_options(0.75, -1).check(), InputError);
  EXPECT_THROW(peak_options(0.75, 17).check(), InputError);
  DensePruneOptions options = peak_options(0.75, 2);
  options.peak_sigmas = 0.0;
  EXPECT_THROW(options.check(), InputError);
  VoxelMap map({0.01, 1, 2});
  EXPECT_THROW(map.remember_new_voxels(-1), InputError);
}

}  // namespace
}  // namespace objmap::fusion

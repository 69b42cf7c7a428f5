#include "objmap/fusion/voxel_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "objmap/core/error.h"

#include "objmap/fusion/palette.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {
namespace {

TEST(VoxelMap, CountsAndColourAveragesAreExact) {
  VoxelMap map({0.01, 1});
  PointCloud a;
  a.push_back(Vec3f(0.002f, 0.002f, 0.002f), Rgb{10, 20, 30});
  a.push_back(Vec3f(0.004f, 0.006f, 0.008f), Rgb{20, 40, 61});  // same voxel (0,0,0)
  a.push_back(Vec3f(-0.005f, 0.005f, 0.005f), Rgb{255, 0, 0});  // voxel (-1,0,0)
  map.insert(a);
  PointCloud b;
  b.push_back(Vec3f(0.006f, 0.004f, 0.002f), Rgb{30, 60, 92});  // voxel (0,0,0) again, next frame
  map.insert(b);
  EXPECT_EQ(map.size(), 2u);
  EXPECT_EQ(map.points_inserted(), 4u);

  const VoxelData* v = map.find(geometry::pack_voxel(0, 0, 0));
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->count, 3u);
  EXPECT_EQ(v->color_sum[0], 60u);
  EXPECT_EQ(v->mean_color(), (Rgb{20, 40, 61}));  // 183/3 = 61
  const Vec3 mean = map.mean_position(geometry::pack_voxel(0, 0, 0), *v);
  EXPECT_NEAR(mean.x(), 0.004, 1e-7);
  EXPECT_NEAR(mean.y(), 0.004, 1e-7);
  EXPECT_NEAR(mean.z(), 0.004, 1e-7);

  const PointCloud cloud = map.to_cloud();  // sorted by key: (-1,0,0) first
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_NEAR(cloud.points[0].x(), -0.005f, 1e-7);
  EXPECT_EQ(cloud.colors[0], (Rgb{255, 0, 0}));
  EXPECT_EQ(cloud.colors[1], (Rgb{20, 40, 61}));
}

// sorted_points() buckets by x slice, then by y, then sorts each (x, y) row: the result must be the
// order of a plain sort of the keys, for short rows (a floor), long rows (a wall along z, > 32
// voxels per row), sparse slices (< 64 voxels) and both thread counts, with each point's data.
TEST(VoxelMap, SortedPointsAreInKeyOrder) {
  PointCloud cloud;
  std::uint32_t state = 12345;
  const auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  };
  for (int i = 0; i < 60000; ++i)  // a thick floor, 1 m x 1 m x 5 cm: rows of ~4 voxels
    cloud.push_back(Vec3f(-1.0f + next(), -1.0f + next(), 0.05f * next()),
                    Rgb{static_cast<std::uint8_t>(i), 7, 9});
  for (int i = 0; i < 40000; ++i)  // a wall along z at x ~ 1.2 m: rows of ~150 voxels
    cloud.push_back(Vec3f(1.2f + 0.004f * next(), -0.5f + next(), 1.5f * next()), Rgb{1, 2, 3});
  for (int i = 0; i < 20; ++i)  // a few far voxels: slices with fewer than 64 voxels
    cloud.push_back(Vec3f(-3.0f - 0.1f * i, 0.5f * next(), next()), Rgb{4, 5, 6});
  for (int threads : {1, 2}) {
    VoxelMap map({0.01, threads, 16});
    map.insert(cloud);
    const VoxelMap::VoxelPoints points = map.sorted_points();
    ASSERT_EQ(points.size(), map.size());
    std::vector<VoxelKey> keys;
    map.for_each([&](VoxelKey key, const VoxelData&) { keys.push_back(key); });
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 0; i < keys.size(); ++i) {
      ASSERT_EQ(points[i].key, keys[i]) << "at " << i << " with " << threads << " threads";
      const VoxelData* v = map.find(keys[i]);
      EXPECT_EQ(points[i].point, map.mean_position(keys[i], *v).cast<float>());
      EXPECT_EQ(points[i].color(), v->mean_color());
    }
  }
}

// A synthetic "frame": a noisy-looking but deterministic surface of 200k points with colours.
PointCloud frame(int f) {
  PointCloud c;
  for (int i = 0; i < 200000; ++i) {
    const float u = static_cast<float>(i % 500) * 0.002f, v = static_cast<float>(i / 500) * 0.002f;
    c.push_back(Vec3f(u + 0.0007f * f, v, 1.0f + 0.05f * std::sin(u * 9 + f)),
                Rgb{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(f), 3});
  }
  return c;
}

TEST(VoxelMap, EveryPointLandsInItsOwnVoxelWhateverItsPlaceInTheBatch) {
  // insert() takes four points at a time where it can: every point, in any lane and in the scalar
  // tail, must land in voxel_key()'s voxel with voxel_coords()'s offset, and the points that are
  // not finite or out of range are dropped. One point per voxel (spread apart), so each voxel's
  // sums are that point's own values.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  PointCloud c;
  std::size_t bad = 0;
  for (int i = 0; i < 1031; ++i) {  // not a multiple of 4 (scalar tail)
    const float t = static_cast<float>(i);
    Vec3f p(0.37f * t - 150.f, -0.0f - 0.21f * t, 0.013f * t + (i % 3 == 0 ? -0.0f : 0.5f));
    if (i % 17 == 3) p[i % 3] = (i % 2) ? nan : -inf;
    if (i % 29 == 5) p[(i + 1) % 3] = 2.0e4f;  // beyond the ±10 km key range at 1 cm
    if (i % 31 == 7) p[i % 3] = -1.0e4f;       // exactly at the range's lower end: kept
    c.push_back(p, Rgb{static_cast<std::uint8_t>(i), 7, static_cast<std::uint8_t>(255 - i % 256)});
  }
  VoxelMap map({0.01, 1});
  map.insert(c);
  for (std::size_t i = 0; i < c.size(); ++i) {
    Eigen::Vector3i ijk;
    Eigen::Vector3f offset;
    if (!geometry::voxel_coords(c.points[i], 100.0f, ijk, offset)) {
      ++bad;
      continue;
    }
    const VoxelData* v = map.find(geometry::pack_voxel(ijk.x(), ijk.y(), ijk.z()));
    ASSERT_NE(v, nullptr) << i;
    ASSERT_EQ(v->count, 1u) << i;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(v->offset_sum[k], offset[k]) << i << " axis " << k;
    EXPECT_EQ(v->color_sum[0], c.colors[i].r) << i;
    EXPECT_EQ(v->color_sum[2], c.colors[i].b) << i;
  }
  EXPECT_GT(bad, 50u);
  EXPECT_EQ(map.points_dropped(), bad);
  EXPECT_EQ(map.size(), c.size() - bad);
}

TEST(VoxelMap, IdenticalOutputForOneAndTwoThreads) {
  VoxelMap one({0.01, 1}), two({0.01, 2});
  for (int f = 0; f < 3; ++f) {
    const PointCloud c = frame(f);
    one.insert(c);
    two.insert(c);
  }
  EXPECT_EQ(one.size(), two.size());
  const PointCloud a = one.to_cloud(), b = two.to_cloud();
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.colors, b.colors);
  for (const auto& [key, v] : one.sorted_voxels()) {
    const VoxelData* w = two.find(key);
    ASSERT_NE(w, nullptr);
    EXPECT_EQ(v->count, w->count);
    EXPECT_EQ(v->color_count, w->color_count);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(v->offset_sum[a], w->offset_sum[a]);
      EXPECT_EQ(v->color_sum[a], w->color_sum[a]);
    }
  }
}

TEST(VoxelMap, MergeAddsVoxelsAndCommonCountsOverlap) {
  VoxelMap a, b;
  PointCloud pa, pb;
  for (int i = 0; i < 10; ++i) pa.push_back(Vec3f(0.01f * i + 0.005f, 0.005f, 0.005f));
  for (int i = 5; i < 15; ++i) pb.push_back(Vec3f(0.01f * i + 0.005f, 0.005f, 0.005f));
  a.insert(pa);
  b.insert(pb);
  EXPECT_EQ(common_voxels(a, b), 5u);
  a.merge(b);
  EXPECT_EQ(a.size(), 15u);
  EXPECT_EQ(a.find(geometry::pack_voxel(7, 0, 0))->count, 2u);
  EXPECT_EQ(a.points_inserted(), 20u);
}

TEST(VoxelMap, ShardedMapsMergeShardByShardLikeOneMap) {
  // 16 shards filled in one pass, merged shard by shard (in a scrambled shard order) into a sharded
  // map: the same voxels, sums and sorted export as one unsharded map fed the same frames.
  VoxelMapOptions sharded{0.01, 1, 16}, plain{0.01, 1};
  VoxelMap one(plain), many(sharded);
  for (int f = 0; f < 3; ++f) {
    const PointCloud c = frame(f);
    VoxelMap frame_one(plain), frame_many(sharded);
    frame_one.insert(c);
    frame_many.insert(c);
    EXPECT_EQ(frame_one.size(), frame_many.size());
    one.merge(frame_one);
    for (std::size_t k = 0; k < 16; ++k) many.merge_shard(frame_many, (k * 7 + f) % 16);
    many.merge_counts(frame_many);
  }
  EXPECT_EQ(many.shard_count(), 16u);
  EXPECT_EQ(one.size(), many.size());
  EXPECT_EQ(one.points_inserted(), many.points_inserted());
  EXPECT_EQ(many.points_inserted(), 600000u);
  const auto a = one.sorted_voxels(), b = many.sorted_voxels();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first, b[i].first);
    EXPECT_EQ(a[i].second->count, b[i].second->count);
    EXPECT_EQ(a[i].second->offset_sum[0], b[i].second->offset_sum[0]);
    EXPECT_EQ(a[i].second->color_sum[2], b[i].second->color_sum[2]);
  }
  EXPECT_TRUE(std::is_sorted(b.begin(), b.end(),
                             [](const auto& x, const auto& y) { return x.first < y.first; }));
  // Sorting on two threads gives the same list.
  VoxelMap two_threads({0.01, 2, 16});
  two_threads.merge(many);
  const auto c = two_threads.sorted_voxels();
  ASSERT_EQ(c.size(), b.size());
  for (std::size_t i = 0; i < c.size(); ++i) ASSERT_EQ(c[i].first, b[i].first);
  // A map of another shard count is refused by merge_shard, and the error names it.
  VoxelMap four({0.01, 1, 4});
  try {
    many.merge_shard(four, 0);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shard count"), std::string::npos) << e.what();
  }
}

TEST(VoxelMap, TrackingListsEveryTouchedVoxelOnceHoweverOftenItWasTouched) {
  // Ten frames over the same voxels between two takes: every voxel listed, each once.
  VoxelMap map({0.01, 1, 16});
  map.track_touched();
  const PointCloud c = frame(0);
  for (int f = 0; f < 10; ++f) map.insert(c);
  auto unique_keys = [](std::vector<VoxelKey> keys) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return keys;
  };
  std::vector<VoxelKey> in_map;
  for (const auto& [key, voxel] : map.sorted_voxels()) in_map.push_back(key);
  const std::vector<VoxelKey> touched = map.take_touched();
  EXPECT_EQ(unique_keys(touched), in_map);
  EXPECT_EQ(touched.size(), in_map.size()) << "ten frames";
  // After a take, the same voxels touched again are listed again, each at least once.
  map.insert(c);
  EXPECT_EQ(unique_keys(map.take_touched()), in_map);
  EXPECT_TRUE(map.take_touched().empty());
}

TEST(Palette, CocoNamesAndFixedColours) {
  const auto& names = segmentation::coco80_names();
  ASSERT_EQ(names.size(), 80u);
  EXPECT_EQ(class_color("teddy_bear"), class_color("teddy bear"));
  EXPECT_EQ(class_color("tvmonitor"), class_color("tv monitor"));
  EXPECT_EQ(class_color("tv monitor"), (Rgb{31, 119, 180}));
  EXPECT_EQ(class_color("person"), (Rgb{220, 20, 60}));
  EXPECT_EQ(class_color("no such class"), (Rgb{128, 128, 128}));
  // All 80 colours are distinct.
  std::set<std::tuple<int, int, int>> seen;
  for (const auto& n : names) {
    const Rgb c = class_color(n);
    seen.insert({c.r, c.g, c.b});
  }
  EXPECT_EQ(seen.size(), 80u);
}

}  // namespace
}  // namespace objmap::fusion

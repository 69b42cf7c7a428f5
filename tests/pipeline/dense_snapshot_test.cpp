// pipeline::DenseSnapshot: a live dense map's cloud kept up to date from the voxels it touched, the
// same as taking the whole map's sorted cloud at each update.
#include "objmap/pipeline/dense_snapshot.h"

#include <gtest/gtest.h>

#include <random>

#include "objmap/core/error.h"
#include "objmap/fusion/voxel_map.h"

namespace objmap::pipeline {
namespace {

// A chunk of coloured points around `centre` (a 40 cm cube): new voxels and voxels seen before.
PointCloud chunk(const Vec3f& centre, std::mt19937& rng) {
  std::uniform_real_distribution<float> d(-0.2f, 0.2f);
  std::uniform_int_distribution<int> c(0, 255);
  PointCloud cloud;
  for (int i = 0; i < 3000; ++i) {
    cloud.points.push_back(centre + Vec3f(d(rng), d(rng), d(rng)));
    cloud.colors.push_back(Rgb{static_cast<std::uint8_t>(c(rng)), static_cast<std::uint8_t>(c(rng)),
                               static_cast<std::uint8_t>(c(rng))});
  }
  return cloud;
}

void expect_cloud_of(const fusion::VoxelMap& map, const DenseCloud& cloud) {
  const fusion::VoxelMap::VoxelPoints want = map.sorted_points();
  ASSERT_EQ(cloud.keys.size(), want.size());
  ASSERT_EQ(cloud.cloud.points.size(), want.size());
  ASSERT_EQ(cloud.cloud.colors.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    ASSERT_EQ(cloud.keys[i], want[i].key) << i;
    ASSERT_EQ(cloud.cloud.points[i], want[i].point) << i;  // bit-identical
    ASSERT_EQ(cloud.cloud.colors[i], want[i].color()) << i;
  }
}

TEST(DenseSnapshot, EachUpdateIsTheWholeMapsSortedCloudAndEarlierOnesStayAsTheyWere) {
  std::mt19937 rng(3);
  fusion::VoxelMap map({0.02, 2, 4});
  DenseSnapshot snapshot(map);
  expect_cloud_of(map, *snapshot.update(map));  // empty
  std::vector<std::shared_ptr<const DenseCloud>> held;
  std::vector<fusion::VoxelMap::VoxelPoints> then;
  for (int step = 0; step < 8; ++step) {
    // Chunks that overlap the last ones (voxels updated) and reach out (voxels new, before and
    // after the existing keys).
    map.insert(chunk(Vec3f(0.1f * static_cast<float>(step % 3), -0.15f * static_cast<float>(step),
                           1.f + 0.05f * static_cast<float>(step)),
                     rng));
    const std::shared_ptr<const DenseCloud> cloud = snapshot.update(map);
    EXPECT_GT(snapshot.last_touched(), 0u);
    expect_cloud_of(map, *cloud);
    if (step % 3 == 0) {  // held as a publish would hold it
      held.push_back(cloud);
      then.push_back(map.sorted_points());
    }
  }
  for (std::size_t h = 0; h < held.size(); ++h) {
    ASSERT_EQ(held[h]->keys.size(), then[h].size());
    for (std::size_t i = 0; i < then[h].size(); ++i)
      ASSERT_EQ(held[h]->cloud.points[i], then[h][i].point);
  }
  const std::shared_ptr<const DenseCloud> same = snapshot.update(map);  // nothing touched
  EXPECT_EQ(snapshot.last_touched(), 0u);
  expect_cloud_of(map, *same);
}

TEST(DenseSnapshot, VoxelsPrunedFromTheMapLeaveTheCloud) {
  std::mt19937 rng(5);
  fusion::VoxelMap map({0.02, 1, 2});
  DenseSnapshot snapshot(map);
  map.remember_new_voxels();
  map.insert(chunk(Vec3f(0.f, 0.f, 1.f), rng));
  expect_cloud_of(map, *snapshot.update(map));
  // Every voxel with an odd z index is noise.
  const fusion::VoxelMap::Judge odd_z = [](const std::vector<fusion::VoxelKey>& keys,
                                           const std::vector<const fusion::VoxelData*>&,
                                           std::vector<std::uint8_t>& noise) {
    for (std::size_t i = 0; i < keys.size(); ++i) noise[i] = keys[i] & 1;
  };
  map.prune_remembered(odd_z);
  ASSERT_GT(map.prune_remembered(odd_z), 0u);
  map.insert(chunk(Vec3f(0.1f, 0.f, 1.1f), rng));
  expect_cloud_of(map, *snapshot.update(map));
}

TEST(DenseSnapshot, ChangesTakenAndAppliedLaterInTheirOrderGiveEachTakesCloud) {
  // A publish takes the changes on the map's thread and applies them on its own, while the map
  // goes on growing; the next take may come before that apply.
  std::mt19937 rng(7);
  fusion::VoxelMap map({0.02, 1, 4});
  DenseSnapshot snapshot(map);
  map.insert(chunk(Vec3f(0.f, 0.f, 1.f), rng));
  map.insert(chunk(Vec3f(0.05f, 0.f, 1.f), rng));  // voxels touched twice: listed once or twice
  const fusion::VoxelMap::VoxelPoints at_first = map.sorted_points();
  DenseChanges first = snapshot.take(map);
  map.insert(chunk(Vec3f(0.1f, 0.05f, 1.05f), rng));
  DenseChanges second = snapshot.take(map);
  EXPECT_TRUE(snapshot.take(map).points.empty());  // nothing since
  const std::shared_ptr<const DenseCloud> one = snapshot.apply(std::move(first));
  ASSERT_EQ(one->keys.size(), at_first.size());
  for (std::size_t i = 0; i < at_first.size(); ++i) {
    ASSERT_EQ(one->keys[i], at_first[i].key) << i;
    ASSERT_EQ(one->cloud.points[i], at_first[i].point) << i;
  }
  expect_cloud_of(map, *snapshot.apply(std::move(second)));
  EXPECT_EQ(one->keys.size(), at_first.size());  // the first cloud handed out stays as it was
}

TEST(DenseSnapshot, NeedsAnEmptyMap) {
  fusion::VoxelMap map;
  map.insert(PointCloud{{Vec3f(0.f, 0.f, 1.f)}, {}});
  EXPECT_THROW(DenseSnapshot{map}, InputError);
}

}  // namespace
}  // namespace objmap::pipeline

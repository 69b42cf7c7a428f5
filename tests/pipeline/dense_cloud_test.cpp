// semantic_colors and drop_sighting_voxels against a plain lookup of each owned voxel in the
// dense keys (a binary search over all of them).
#include "objmap/pipeline/dense_cloud.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "objmap/fusion/object_map.h"
#include "objmap/geometry/voxel_key.h"

namespace objmap::pipeline {
namespace {

constexpr double kVoxel = 0.01;

// A dense cloud of `n` random voxels in a 2 m cube (sorted by key, one point each).
DenseCloud random_dense_cloud(std::size_t n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::map<fusion::VoxelKey, Vec3f> voxels;
  while (voxels.size() < n) {
    const Vec3f p(u(rng), u(rng), u(rng));
    voxels.emplace(geometry::voxel_key(p, 1.0 / kVoxel), p);
  }
  DenseCloud dense;
  for (const auto& [key, p] : voxels) {
    dense.keys.push_back(key);
    dense.cloud.points.push_back(p);
    dense.cloud.colors.push_back(Rgb{static_cast<std::uint8_t>(key & 0xff), 7, 9});
  }
  return dense;
}

// Confirmed records holding every `every`-th dense point from `first` on and points outside it.
fusion::ObjectRecord record_of(const DenseCloud& dense, std::size_t first, std::size_t every,
                               int id) {
  fusion::ObjectRecord r;
  r.id = id;
  r.confirmed = true;
  r.observations = 3 + id;
  for (std::size_t i = first; i < dense.keys.size(); i += every)
    r.cloud.points.push_back(dense.cloud.points[i]);
  r.cloud.points.push_back(Vec3f(5.f + static_cast<float>(id), 5.f, 5.f));  // not in the map
  return r;
}

std::size_t plain_index(const DenseCloud& dense, fusion::VoxelKey key) {
  const auto it = std::lower_bound(dense.keys.begin(), dense.keys.end(), key);
  return it != dense.keys.end() && *it == key ? static_cast<std::size_t>(it - dense.keys.begin())
                                              : dense.keys.size();
}

TEST(DenseCloud, SemanticColoursAreThoseOfAPlainLookupOfEachOwnedVoxel) {
  std::mt19937 rng(7);
  const DenseCloud dense = random_dense_cloud(200000, rng);
  const std::vector<fusion::ObjectRecord> records = {
      record_of(dense, 0, 3, 1), record_of(dense, 1, 7, 2), record_of(dense, 199990, 1, 3)};
  const std::vector<Rgb> record_color = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
  const std::vector<Rgb> colors = semantic_colors(dense, kVoxel, records, record_color);
  std::vector<Rgb> expected = dense.cloud.colors;
  std::size_t painted = 0;
  fusion::voxel_owners(records, kVoxel).for_each([&](fusion::VoxelKey key, std::uint32_t slot) {
    const std::size_t i = plain_index(dense, key);
    if (i == dense.keys.size()) return;
    expected[i] = record_color[slot - 1];
    ++painted;
  });
  EXPECT_GT(painted, 85000u);  // a third, a seventh (a 21st in both) and the last ten
  ASSERT_EQ(colors.size(), expected.size());
  EXPECT_TRUE(colors == expected);
  EXPECT_TRUE(colors.back() == (Rgb{0, 0, 255}));  // the last dense voxel found
}

TEST(DenseCloud, SightingVoxelsNotHeldByAnObjectAreDropped) {
  std::mt19937 rng(11);
  DenseCloud dense = random_dense_cloud(50000, rng);
  const std::vector<fusion::ObjectRecord> sightings = {record_of(dense, 0, 5, 1)};
  const std::vector<fusion::ObjectRecord> objects = {record_of(dense, 0, 10, 2)};
  std::vector<char> keep(dense.keys.size(), 1);
  const auto staying = fusion::voxel_owners(objects, kVoxel);
  fusion::voxel_owners(sightings, kVoxel).for_each([&](fusion::VoxelKey key, std::uint32_t) {
    const std::size_t i = plain_index(dense, key);
    if (i < dense.keys.size() && !staying.contains(key)) keep[i] = 0;
  });
  std::vector<fusion::VoxelKey> expected;
  for (std::size_t i = 0; i < dense.keys.size(); ++i)
    if (keep[i]) expected.push_back(dense.keys[i]);
  EXPECT_EQ(drop_sighting_voxels(dense, sightings, objects, kVoxel), 5000u);
  EXPECT_EQ(dense.keys, expected);
  EXPECT_EQ(dense.cloud.points.size(), expected.size());
}

}  // namespace
}  // namespace objmap::pipeline

#include "objmap/filters/neighbour_distances.h"

#include <gtest/gtest.h>

#include <random>

#include "objmap/core/error.h"

namespace objmap::filters {
namespace {

// A sphere shell of 1 m with 2 mm noise and, every 200th point, a point anywhere in a 3 m cube:
// the shell settles in the first ring, the scattered points need wider rings or the kd-tree.
PointCloud shell_with_scatter(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(0.f, 1.f);
  std::normal_distribution<float> noise(0.f, 0.002f);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 200 == 199) {
      c.push_back(Vec3f(uni(rng) * 3, uni(rng) * 3, uni(rng) * 3));
      continue;
    }
    const float th = uni(rng) * 3.14159f, ph = uni(rng) * 6.28318f;
    c.push_back(Vec3f(1.5f + 0.5f * std::sin(th) * std::cos(ph) + noise(rng),
                      1.5f + 0.5f * std::sin(th) * std::sin(ph) + noise(rng),
                      1.5f + 0.5f * std::cos(th) + noise(rng)));
  }
  return c;
}

// One point per occupied 1 cm voxel of a box's faces, off the voxel centre (as an object's
// record is), far from the origin, with a few repeated points.
PointCloud voxel_box(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.004f, 0.004f);
  PointCloud c;
  const Vec3f base(12.3f, -40.7f, 3.1f);
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 20; ++j)
      for (int f = 0; f < 2; ++f) {
        const float off = 0.005f + 0.01f;
        c.push_back(base + Vec3f(i * 0.01f + off + jitter(rng), j * 0.01f + off + jitter(rng),
                                 f * 0.15f + jitter(rng)));
        c.push_back(base + Vec3f(i * 0.01f + jitter(rng), f * 0.2f + jitter(rng),
                                 j * 0.0075f + jitter(rng)));
      }
  for (int i = 0; i < 40; ++i) c.push_back(c.points[static_cast<std::size_t>(i) * 7]);
  return c;
}

void expect_same_bits(const PointCloud& cloud, int k, int threads) {
  NeighbourSearchStats stats;
  const std::vector<double> grid = mean_neighbour_distances(cloud, k, threads, &stats);
  const std::vector<double> tree = mean_neighbour_distances_kdtree(cloud, k, 1);
  ASSERT_EQ(grid.size(), tree.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < grid.size(); ++i) differ += grid[i] != tree[i];
  EXPECT_EQ(differ, 0u) << "of " << grid.size() << " points, k " << k << ", cell " << stats.cell_m;
  EXPECT_EQ(stats.in_first_ring + stats.in_wider_rings + stats.by_kdtree, cloud.size());
}

TEST(NeighbourDistances, TheGridGivesTheKdTreesDistancesBitForBit) {
  const PointCloud shell = shell_with_scatter(30000, 3);
  for (int k : {1, 5, 20, 50}) expect_same_bits(shell, k, 2);
  const PointCloud box = voxel_box(4);
  for (int k : {1, 8, 20}) expect_same_bits(box, k, 1);
  // A line and a cloud of one repeated point.
  PointCloud line, same;
  for (int i = 0; i < 500; ++i) line.push_back(Vec3f(0.5f, 0.003f * i, -2.f));
  for (int i = 0; i < 50; ++i) same.push_back(Vec3f(1.f, 2.f, 3.f));
  expect_same_bits(line, 20, 2);
  expect_same_bits(same, 20, 1);
  // Mostly one repeated point (the sampled (k+1)-th distances are 0), and a few spread out.
  PointCloud mostly_same = same;
  for (int i = 0; i < 150; ++i) mostly_same.push_back(Vec3f(1.f, 2.f, 3.f));
  for (int i = 0; i < 30; ++i) mostly_same.push_back(Vec3f(1.f + 0.01f * i, 2.f, 3.f - 0.02f * i));
  expect_same_bits(mostly_same, 20, 2);
}

TEST(NeighbourDistances, TheSurfaceSettlesInTheFirstRingTheScatterBeyond) {
  const PointCloud shell = shell_with_scatter(60000, 5);
  NeighbourSearchStats stats;
  const std::vector<double> one = mean_neighbour_distances(shell, 20, 1, &stats);
  // 59,700 points on the shell, 300 scattered in 27 m^3 (one per ~0.45 m).
  EXPECT_GT(stats.in_first_ring, 0.9 * 59700) << "cell " << stats.cell_m;
  EXPECT_GT(stats.by_kdtree, 200u);
  EXPECT_LE(stats.by_kdtree, 400u);
  EXPECT_EQ(one, mean_neighbour_distances(shell, 20, 2));  // any thread count
}

TEST(NeighbourDistances, FewPointsAndBadInputAreNamed) {
  PointCloud few;
  for (int i = 0; i < 3; ++i) few.push_back(Vec3f(static_cast<float>(i), 0, 0));
  EXPECT_EQ(mean_neighbour_distances(few, 3, 1), std::vector<double>(3, 0.0));
  few.push_back(Vec3f(0, std::nanf(""), 0));
  few.push_back(Vec3f(1, 1, 1));
  try {
    mean_neighbour_distances(few, 2, 1);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mean_neighbour_distances: point 3 is not finite");
  }
}

}  // namespace
}  // namespace objmap::filters

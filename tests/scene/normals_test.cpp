// scene::detail::grid_normals (private to lib/objmap/scene): the normals that tell the horizontal
// points of the dense map's sample from walls.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <pcl/filters/voxel_grid.h>

#include <array>
#include <map>

#include "objmap/scene/sampled.h"

namespace objmap::scene::detail {
namespace {

double angle_deg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return std::acos(std::min(1.0f, std::fabs(a.normalized().dot(b.normalized())))) * 180.0 / M_PI;
}

// A 1 m square of dense-map points (1 cm apart, ±3 mm of noise along its normal) through
// `origin` spanned by u and v, sampled on the 4 cm grid as the scene step samples the map.
std::vector<Vec3f> square(const Vec3f& origin, const Vec3f& u, const Vec3f& v, std::mt19937& rng) {
  std::normal_distribution<float> noise(0.f, 0.003f);
  const Vec3f n = u.cross(v).normalized();
  std::vector<Vec3f> points;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j)
      points.push_back(origin + 0.01f * (i * u + j * v) + noise(rng) * n);
  return points;
}

TEST(GridNormals, FloorAndTiltedWallGetTheirPlanesNormals) {
  std::mt19937 rng(3);
  std::vector<Vec3f> map = square({0.f, 0.f, 0.f}, Vec3f::UnitX(), Vec3f::UnitY(), rng);
  const Vec3f slope = Vec3f(0.f, std::sin(0.3f), std::cos(0.3f));  // a wall leaning 17 deg
  const std::vector<Vec3f> wall = square({0.f, 2.f, 0.1f}, Vec3f::UnitX(), slope, rng);
  map.insert(map.end(), wall.begin(), wall.end());
  const Cloud::Ptr sample = sample_on_grid(map, 0.04);
  const std::vector<Eigen::Vector3f> normals = grid_normals(sample, 0.04);
  ASSERT_EQ(normals.size(), sample->size());
  const Eigen::Vector3f wall_normal = Vec3f::UnitX().cross(slope).normalized();
  // The leaning wall crosses the axis-aligned cells in steps: at a step the cells' means bend,
  // so a few normals there lean by up to ~10 deg; the horizontal test allows 25.
  int floor = 0, on_wall = 0, floor_within_2 = 0, wall_within_5 = 0;
  for (std::size_t i = 0; i < sample->size(); ++i) {
    const Eigen::Vector3f p = (*sample)[i].getVector3fMap();
    ASSERT_NEAR(normals[i].norm(), 1.0f, 1e-4f) << "every sample point has neighbours here";
    const bool on_floor = p.y() < 1.0f;
    const double error = angle_deg(normals[i], on_floor ? Vec3f::UnitZ() : wall_normal);
    EXPECT_LT(error, 12.0) << p.transpose();
    floor += on_floor;
    on_wall += !on_floor;
    floor_within_2 += on_floor && error < 2.0;
    wall_within_5 += !on_floor && error < 5.0;
  }
  EXPECT_GT(floor, 500);
  EXPECT_GT(on_wall, 500);
  EXPECT_EQ(floor_within_2, floor);
  EXPECT_GE(wall_within_5, 0.9 * on_wall);
}

TEST(GridNormals, APointWithFewerThanThreeInItsNeighbourhoodHasNone) {
  Cloud::Ptr sample(new Cloud);
  sample->push_back(pcl::PointXYZ(0.01f, 0.01f, 0.01f));
  sample->push_back(pcl::PointXYZ(0.05f, 0.01f, 0.01f));  // the next cell: two in all
  sample->push_back(pcl::PointXYZ(1.01f, 1.01f, 1.01f));  // alone
  for (const Eigen::Vector3f& n : grid_normals(sample, 0.04)) EXPECT_EQ(n, Eigen::Vector3f::Zero());
}

TEST(GridNormals, AStraightLineOfCellsGivesANormalAcrossIt) {
  // Three cells in a row: the plane is not determined, but the normal is still a unit vector
  // perpendicular to the line (an eigenvector of a rank-1 covariance), never NaN.
  Cloud::Ptr sample(new Cloud);
  for (int i = 0; i < 3; ++i) sample->push_back(pcl::PointXYZ(0.02f + 0.04f * i, 0.02f, 0.02f));
  for (const Eigen::Vector3f& n : grid_normals(sample, 0.04)) {
    EXPECT_TRUE(n.allFinite());
    EXPECT_NEAR(n.x(), 0.0f, 1e-4f);
  }
}

}  // namespace
}  // namespace objmap::scene::detail

namespace objmap::scene::detail {
namespace {

TEST(SampleOnGrid, IsPclsVoxelGridOnTheWorldsGridAndMovesWithItsFrame) {
  // The cells' means, as PCL's VoxelGrid gives them (compared as sorted point sets).
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.f, 2.f);
  std::vector<Vec3f> map;
  for (int i = 0; i < 20000; ++i) map.emplace_back(u(rng), u(rng), 0.3f * u(rng));
  Cloud::Ptr all(new Cloud);
  for (const Vec3f& p : map) all->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(all);
  grid.setLeafSize(0.04f, 0.04f, 0.04f);
  Cloud pcl_sample;
  grid.filter(pcl_sample);
  const auto sorted = [](const Cloud& c) {
    std::vector<std::array<float, 3>> v;
    for (const auto& p : c) v.push_back({p.x, p.y, p.z});
    std::sort(v.begin(), v.end());
    return v;
  };
  const auto ours = sorted(*sample_on_grid(map, 0.04));
  const auto theirs = sorted(pcl_sample);
  ASSERT_EQ(ours.size(), theirs.size());
  for (std::size_t i = 0; i < ours.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(ours[i][k], theirs[i][k], 1e-5f) << i;
  // Laid in a moved frame, the sample of the moved map is the moved sample (but for the few points
  // that the move's rounding takes across a cell's side).
  GridFrame frame;
  frame.grid_from_world = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  frame.origin = Vec3(0.3, -2.0, 1.0);
  std::vector<Vec3f> moved;
  for (const Vec3f& p : map)
    moved.push_back(
        (frame.grid_from_world.transpose() * p.cast<double>() + frame.origin).cast<float>());
  const Cloud::Ptr moved_sample = sample_on_grid(moved, 0.04, frame);
  std::map<std::array<float, 3>, int> cell_means;
  for (const auto& p : ours) cell_means[p] = 1;
  std::size_t same = 0;
  for (const auto& p : *moved_sample) {
    const Vec3 q = frame.grid_from_world * (Vec3(p.x, p.y, p.z) - frame.origin);
    const auto near = cell_means.lower_bound(
        {static_cast<float>(q.x()) - 1e-4f, static_cast<float>(q.y()), static_cast<float>(q.z())});
    for (auto it = near; it != cell_means.end() && it->first[0] <= q.x() + 1e-4; ++it)
      if ((Vec3(it->first[0], it->first[1], it->first[2]) - q).norm() < 1e-4) {
        ++same;
        break;
      }
  }
  EXPECT_NEAR(static_cast<double>(moved_sample->size()), static_cast<double>(ours.size()), 5.0);
  EXPECT_GE(same, ours.size() * 995 / 1000);
}

}  // namespace
}  // namespace objmap::scene::detail

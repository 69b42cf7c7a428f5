#include "objmap/geometry/bounds.h"

#include <gtest/gtest.h>

namespace objmap::geometry {
namespace {

TEST(Bounds, AabbCentroidAndObbOfARotatedBox) {
  // A 0.4 × 0.2 × 0.1 box surface sampled on a grid, rotated 30° about z and moved.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 6, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 t(1.0, 2.0, 0.5);
  PointCloud cloud;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 20; ++j)
      for (int k = 0; k <= 10; ++k) {
        if (i != 0 && i != 40 && j != 0 && j != 20 && k != 0 && k != 10) continue;  // surface only
        const Vec3 local(-0.2 + 0.01 * i, -0.1 + 0.01 * j, -0.05 + 0.01 * k);
        cloud.push_back((R * local + t).cast<float>());
      }
  EXPECT_LT((centroid(cloud) - t).norm(), 1e-5);
  const Obb obb = compute_obb(cloud);
  EXPECT_LT((obb.center - t).norm(), 1e-5);
  EXPECT_NEAR(obb.half_extent.x(), 0.2, 1e-5);
  EXPECT_NEAR(obb.half_extent.y(), 0.1, 1e-5);
  EXPECT_NEAR(obb.half_extent.z(), 0.05, 1e-5);
  EXPECT_NEAR(std::abs(obb.rotation.col(0).dot(R.col(0))), 1.0, 1e-6);
  EXPECT_NEAR(obb.rotation.determinant(), 1.0, 1e-9);
  for (const Vec3f& p : cloud.points) EXPECT_TRUE(obb.contains(p.cast<double>(), 1e-5));
  const Aabb aabb = compute_aabb(cloud);
  EXPECT_LE(aabb.min.x(), t.x() - 0.2);
  EXPECT_GE(aabb.max.x(), t.x() + 0.2);
  EXPECT_EQ(compute_aabb(PointCloud{}).min, Vec3::Zero());
}

}  // namespace
}  // namespace objmap::geometry

#include "objmap/geometry/bounds.h"

#include <Eigen/Eigenvalues>
#include <limits>

namespace objmap::geometry {

Vec3 centroid(const PointCloud& cloud) {
  if (cloud.empty()) return Vec3::Zero();
  Vec3 sum = Vec3::Zero();
  for (const Vec3f& p : cloud.points) sum += p.cast<double>();
  return sum / static_cast<double>(cloud.size());
}

Aabb compute_aabb(const PointCloud& cloud) {
  Aabb box;
  if (cloud.empty()) return box;
  Eigen::Vector3f lo = cloud.points.front(), hi = cloud.points.front();
  for (const Vec3f& p : cloud.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  box.min = lo.cast<double>();
  box.max = hi.cast<double>();
  return box;
}

Obb compute_obb(const PointCloud& cloud) {
  Obb box;
  if (cloud.empty()) return box;
  const Vec3 mean = centroid(cloud);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3f& p : cloud.points) {
    const Vec3 d = p.cast<double>() - mean;
    cov.noalias() += d * d.transpose();
  }
  cov /= static_cast<double>(cloud.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  // Eigen sorts eigenvalues ascending; the box's first axis is the largest variance.
  Eigen::Matrix3d axes;
  for (int i = 0; i < 3; ++i) axes.col(i) = solver.eigenvectors().col(2 - i);
  for (int i = 0; i < 2; ++i) {
    Eigen::Index k;
    axes.col(i).cwiseAbs().maxCoeff(&k);
    if (axes(k, i) < 0) axes.col(i) = -axes.col(i);
  }
  axes.col(2) = axes.col(0).cross(axes.col(1));  // right-handed
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max());
  Vec3 hi = Vec3::Constant(std::numeric_limits<double>::lowest());
  for (const Vec3f& p : cloud.points) {
    const Vec3 local = axes.transpose() * (p.cast<double>() - mean);
    lo = lo.cwiseMin(local);
    hi = hi.cwiseMax(local);
  }
  box.rotation = axes;
  box.center = mean + axes * ((lo + hi) / 2.0);
  box.half_extent = (hi - lo) / 2.0;
  return box;
}

}  // namespace objmap::geometry

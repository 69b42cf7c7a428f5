#include "objmap/geometry/bounds.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace objmap::geometry {

namespace {

// The box whose axes are the columns of `axes` (a rotation) around the cloud: the points' extent
// along each axis, measured from `mean`.
Obb box_along(const Eigen::Matrix3d& axes, const Vec3& mean, const PointCloud& cloud) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max());
  Vec3 hi = Vec3::Constant(std::numeric_limits<double>::lowest());
  for (const Vec3f& p : cloud.points) {
    const Vec3 local = axes.transpose() * (p.cast<double>() - mean);
    lo = lo.cwiseMin(local);
    hi = hi.cwiseMax(local);
  }
  Obb box;
  box.rotation = axes;
  box.center = mean + axes * ((lo + hi) / 2.0);
  box.half_extent = (hi - lo) / 2.0;
  return box;
}

}  // namespace

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
  if (cloud.empty()) return Obb();
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
  return box_along(axes, mean, cloud);
}

Obb compute_upright_obb(const PointCloud& cloud, const Vec3& up) {
  if (cloud.empty()) return Obb();
  const Vec3 mean = centroid(cloud);
  // Any horizontal basis (h0, h1), then the 2x2 covariance of the points in it.
  const Vec3 h0 = up.unitOrthogonal();
  const Vec3 h1 = up.cross(h0);
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const Vec3f& p : cloud.points) {
    const Vec3 d = p.cast<double>() - mean;
    const Eigen::Vector2d q(d.dot(h0), d.dot(h1));
    cov.noalias() += q * q.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(cov);
  const Eigen::Vector2d major = solver.eigenvectors().col(1);  // eigenvalues ascending
  Vec3 a = (major.x() * h0 + major.y() * h1).normalized();
  Eigen::Index k;
  a.cwiseAbs().maxCoeff(&k);
  if (a[k] < 0) a = -a;
  Eigen::Matrix3d axes;
  axes.col(0) = a;
  axes.col(1) = up.cross(a);
  axes.col(2) = up;
  return box_along(axes, mean, cloud);
}

Vec3 percentile_box_centre(const PointCloud& cloud, double q,
                           const Eigen::Matrix3d& frame_from_world) {
  Vec3 centre = Vec3::Zero();
  if (cloud.empty()) return centre;
  const bool world_axes = frame_from_world.isIdentity(0.0);
  const std::size_t n = cloud.size();
  const auto rank = [&](double f) {
    return std::min(n - 1, static_cast<std::size_t>(std::llround(f * static_cast<double>(n - 1))));
  };
  q = std::clamp(q, 0.0, 0.5);
  const std::size_t lo = rank(q), hi = rank(1.0 - q);
  std::vector<float> v(n);
  for (int axis = 0; axis < 3; ++axis) {
    if (world_axes) {
      for (std::size_t i = 0; i < n; ++i) v[i] = cloud.points[i][axis];
    } else {
      const Eigen::Vector3f row = frame_from_world.row(axis).transpose().cast<float>();
      for (std::size_t i = 0; i < n; ++i) v[i] = row.dot(cloud.points[i]);
    }
    std::nth_element(v.begin(), v.begin() + lo, v.end());
    const double a = v[lo];
    std::nth_element(v.begin(), v.begin() + hi, v.end());
    centre[axis] = 0.5 * (a + static_cast<double>(v[hi]));
  }
  return world_axes ? centre : Vec3(frame_from_world.transpose() * centre);
}

}  // namespace objmap::geometry

#include "objmap/geometry/bounds.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_set>
#include <vector>

#include "objmap/core/error.h"

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

void SupportStripOptions::check() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto share = [](double v) { return v >= 0.0 && v <= 1.0; };
  require(positive(band_m), "SupportStripOptions.band_m", "must be a positive number of metres");
  require(positive(reach_m), "SupportStripOptions.reach_m", "must be a positive number of metres");
  require(positive(area_factor), "SupportStripOptions.area_factor", "must be positive");
  require(positive(cell_m), "SupportStripOptions.cell_m", "must be a positive number of metres");
  require(share(min_body_share), "SupportStripOptions.min_body_share", "must be within [0, 1]");
  require(share(min_strip_share), "SupportStripOptions.min_strip_share", "must be within [0, 1]");
}

namespace {

// A footprint cell of (x, y) in the gravity frame, packed in one integer.
std::uint64_t footprint_cell(const Vec3& g, double cell_m) {
  // Indices clamped to 32 bits (a point 40,000 km away shares a cell with others out there),
  // shifted unsigned: a negative index is no undefined behaviour.
  const auto index = [cell_m](double v) {
    const double f = std::floor(v / cell_m);
    const double i = std::isnan(f) ? 0.0 : std::clamp(f, -2147483648.0, 2147483647.0);
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(i));
  };
  return (index(g.x()) << 32) ^ (index(g.y()) & 0xffffffffULL);
}

// The height of the plane the object of `g` (its points in the gravity frame) rests on: the
// largest plane within reach of its 1st-percentile height and larger than area_factor × its
// footprint (cells of cell_m holding a point); NaN when there is none.
double resting_plane(const std::vector<Vec3>& g, const std::vector<SupportPlane>& planes,
                     const SupportStripOptions& options) {
  std::vector<double> heights(g.size());
  std::unordered_set<std::uint64_t> cells;
  for (std::size_t i = 0; i < g.size(); ++i) {
    heights[i] = g[i].z();
    cells.insert(footprint_cell(g[i], options.cell_m));
  }
  const auto rank =
      static_cast<std::size_t>(std::llround(0.01 * static_cast<double>(heights.size() - 1)));
  std::nth_element(heights.begin(), heights.begin() + rank, heights.end());
  const double lowest = heights[rank];
  const double footprint_m2 = static_cast<double>(cells.size()) * options.cell_m * options.cell_m;
  double height = std::numeric_limits<double>::quiet_NaN(), area = 0.0;
  for (const SupportPlane& p : planes)
    if (std::abs(p.height_m - lowest) <= options.reach_m &&
        p.area_m2 >= options.area_factor * footprint_m2 && p.area_m2 > area) {
      height = p.height_m;
      area = p.area_m2;
    }
  return height;
}

}  // namespace

std::vector<bool> support_strip(const PointCloud& cloud, const Eigen::Matrix3d& gravity_from_world,
                                const std::vector<SupportPlane>& planes,
                                const SupportStripOptions& options) {
  const std::size_t n = cloud.size();
  std::vector<bool> strip(n, false);
  if (n < std::max<std::size_t>(options.min_points, 1) || planes.empty()) return strip;
  std::vector<Vec3> g(n);
  for (std::size_t i = 0; i < n; ++i) g[i] = gravity_from_world * cloud.points[i].cast<double>();
  const double plane = resting_plane(g, planes, options);
  if (!std::isfinite(plane)) return strip;
  // The footprint of the points above the layer, widened by one cell.
  std::unordered_set<std::uint64_t> footprint;
  std::size_t above = 0;
  for (const Vec3& p : g) {
    if (p.z() <= plane + options.band_m) continue;
    ++above;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        footprint.insert(footprint_cell(p + Vec3(dx, dy, 0) * options.cell_m, options.cell_m));
  }
  if (static_cast<double>(above) < options.min_body_share * static_cast<double>(n)) return strip;
  std::size_t marked = 0;
  for (std::size_t i = 0; i < n; ++i) {
    strip[i] = std::abs(g[i].z() - plane) <= options.band_m &&
               !footprint.count(footprint_cell(g[i], options.cell_m));
    marked += strip[i];
  }
  if (static_cast<double>(marked) < options.min_strip_share * static_cast<double>(n))
    std::fill(strip.begin(), strip.end(), false);
  return strip;
}

PointCloud without(const PointCloud& cloud, const std::vector<bool>& drop) {
  PointCloud out;
  const bool colours = cloud.has_colors();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (i < drop.size() && drop[i]) continue;
    out.points.push_back(cloud.points[i]);
    if (colours) out.colors.push_back(cloud.colors[i]);
  }
  return out;
}

}  // namespace objmap::geometry

// Support surfaces: horizontal patches of the dense map (docs/scene.md, "Surfaces").

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <set>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/scene/footprint.h"
#include "objmap/scene/sampled.h"

namespace objmap::scene {
namespace {

using Cell = std::pair<long, long>;

// A patch while it is built: its sample points (gravity frame) and occupied grid cells.
struct Patch {
  std::vector<Vec3f> points;  // gravity frame
  std::set<Cell> cells;
  double level = 0.0;  // the median height of its points
  // Its plane: height = level + slope · (xy − centre), least squares (zero for a narrow patch):
  // the estimated up leaves a real floor tilted by a few degrees, 10 cm across a room.
  Eigen::Vector2d centre = Eigen::Vector2d::Zero(), slope = Eigen::Vector2d::Zero();
  double height_at(const Eigen::Vector2d& xy) const { return level + slope.dot(xy - centre); }
  Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector2f hi = Eigen::Vector2f::Constant(std::numeric_limits<float>::lowest());
  void add(const Vec3f& q, double cell_m) {
    points.push_back(q);
    cells.insert(
        {std::lround(std::floor(q.x() / cell_m)), std::lround(std::floor(q.y() / cell_m))});
    lo = lo.cwiseMin(q.head<2>());
    hi = hi.cwiseMax(q.head<2>());
  }
};

// The patch's plane (Patch::slope) by least squares, when it spans at least 0.3 m both ways; its
// tilt is kept within max_tilt_deg.
void fit_plane(Patch& p, double max_tilt_deg) {
  const double n = static_cast<double>(p.points.size());
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  double z_mean = 0.0;
  for (const Vec3f& q : p.points) {
    mean += q.head<2>().cast<double>();
    z_mean += q.z();
  }
  mean /= n;
  z_mean /= n;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  Eigen::Vector2d cross = Eigen::Vector2d::Zero();
  for (const Vec3f& q : p.points) {
    const Eigen::Vector2d d = q.head<2>().cast<double>() - mean;
    cov.noalias() += d * d.transpose();
    cross += d * (q.z() - z_mean);
  }
  p.centre = mean;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov / n);
  constexpr double kMinSpan = 0.3;  // a uniform spread of this width has variance span² / 12
  if (eig.eigenvalues()[0] < kMinSpan * kMinSpan / 12.0) return;
  p.slope = cov.ldlt().solve(cross);
  const double max_slope = std::tan(max_tilt_deg * M_PI / 180.0);
  if (p.slope.norm() > max_slope) p.slope *= max_slope / p.slope.norm();
}

// Step 2: the horizontal points split into patches by Euclidean clustering at most cluster_gap_m
// apart (PCL's clusters, on a grid: euclidean_clusters). A patch follows its surface wherever it
// goes: a table top that the estimated up sees tilted by a few degrees stays one patch (its level
// is its median height).
std::vector<Patch> horizontal_patches(const std::vector<Vec3f>& g, const SurfaceOptions& o,
                                      std::size_t min_points) {
  std::vector<Patch> out;
  if (g.size() < min_points) return out;
  const std::vector<std::vector<int>> clusters =
      detail::euclidean_clusters(g, o.cluster_gap_m, min_points);
  for (const auto& c : clusters) {
    Patch p;
    std::vector<float> z;
    z.reserve(c.size());
    for (int k : c) {
      p.add(g[static_cast<std::size_t>(k)], o.sample_voxel_m);
      z.push_back(g[static_cast<std::size_t>(k)].z());
    }
    std::nth_element(z.begin(), z.begin() + static_cast<long>(z.size() / 2), z.end());
    p.level = z[z.size() / 2];
    fit_plane(p, o.max_tilt_deg);
    out.push_back(std::move(p));
  }
  return out;
}

// The narrower horizontal spread (std, m) of a patch: a wall's slice is a few cm wide.
double narrow_spread(const Patch& p) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Vec3f& q : p.points) mean += q.head<2>().cast<double>();
  mean /= static_cast<double>(p.points.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const Vec3f& q : p.points) {
    const Eigen::Vector2d d = q.head<2>().cast<double>() - mean;
    cov.noalias() += d * d.transpose();
  }
  cov /= static_cast<double>(p.points.size());
  return std::sqrt(
      std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvalues()[0]));
}

// Whether two patches are one surface: layers of it (the depth noise of far views leaves a floor
// or a table top as parallel layers a few cm apart: within merge_height_m, sharing cells), or
// pieces of it at the same level that the objects on it cut apart (levels within
// piece_height_m, boxes less than merge_gap_m apart). Levels are compared on the plane of the
// larger patch `m` at the centre of `p`.
bool one_surface(const Patch& m, const Patch& p, const SurfaceOptions& o) {
  const double dh = std::fabs(m.height_at(p.centre) - p.level);  // m's plane at p's centre
  if (dh <= o.piece_height_m) {
    const Eigen::Vector2f gap =
        (m.lo - p.hi).cwiseMax(p.lo - m.hi).cwiseMax(Eigen::Vector2f::Zero());
    if (gap.norm() <= o.merge_gap_m) return true;
  }
  if (dh > o.merge_height_m) return false;
  for (const Cell& c : p.cells)
    if (m.cells.count(c)) return true;
  return false;
}

// Step 3: the patches of one surface merge (one_surface); the largest keeps its level.
std::vector<Patch> merge_layers(std::vector<Patch> patches, const SurfaceOptions& o) {
  std::stable_sort(patches.begin(), patches.end(),
                   [](const Patch& a, const Patch& b) { return a.cells.size() > b.cells.size(); });
  std::vector<Patch> merged;
  for (Patch& p : patches) {
    Patch* into = nullptr;
    for (Patch& m : merged)
      if (one_surface(m, p, o)) {
        into = &m;
        break;
      }
    if (!into) {
      merged.push_back(std::move(p));
      continue;
    }
    into->cells.insert(p.cells.begin(), p.cells.end());
    into->points.insert(into->points.end(), p.points.begin(), p.points.end());
    into->lo = into->lo.cwiseMin(p.lo);
    into->hi = into->hi.cwiseMax(p.hi);
  }
  return merged;
}

// A patch as a Surface in the world frame: its level, centre, area (occupied cells), outline.
Surface make_surface(const Patch& p, const Eigen::Matrix3d& gravity, double cell_m) {
  const Eigen::Matrix3d world_from_gravity = gravity.transpose();
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Vec3f& q : p.points) mean += q.head<2>().cast<double>();
  mean /= static_cast<double>(p.points.size());
  std::vector<cv::Point2f> xy, hull;
  for (const Vec3f& q : p.points) xy.emplace_back(q.x(), q.y());
  cv::convexHull(xy, hull, /*clockwise=*/false);
  Surface s;
  s.height_m = p.level;
  s.points = p.points.size();
  s.area_m2 = static_cast<double>(p.cells.size()) * cell_m * cell_m;
  s.center = world_from_gravity * Vec3(mean.x(), mean.y(), p.level);
  for (const cv::Point2f& q : hull)
    s.outline.push_back(world_from_gravity * Vec3(q.x, q.y, p.level));
  return s;
}

// The object whose top the surface is (a chair's seat, a shelf's board): the surface's centre
// inside the object's footprint, its height above the object's bottom (1 cm) and at most 3 cm over
// its top, and its area at most 1.5 times the footprint's (a person or a chair whose mask bled
// over a desk has the desk's centre in its footprint; the desk is no top of theirs).
std::optional<int> object_under(const Surface& s, const Eigen::Matrix3d& gravity_from_world,
                                const std::vector<SceneObject>& objects,
                                const std::vector<detail::Footprint>& footprints) {
  const Vec3 g = gravity_from_world * s.center;
  const cv::Point2f c(static_cast<float>(g.x()), static_cast<float>(g.y()));
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const auto& f = footprints[i];
    if (s.height_m >= f.bottom + 0.01 && s.height_m <= f.top + 0.03 &&
        detail::inside_distance(f.hull, c) >= 0.0 &&
        s.area_m2 <= 1.5 * (f.hull.size() >= 3 ? cv::contourArea(f.hull) : 0.0))
      return objects[i].id;
  }
  return std::nullopt;
}

// Step 1: the horizontal points of the sample (gravity frame): those whose surface normal (the
// plane of the sample points in the 3x3x3 cells around it, grid_normals) is within max_tilt_deg
// of up. A wall has points at
// every height: its slices would be patches at every level.
std::vector<Vec3f> horizontal_points(const detail::Cloud::Ptr& sample,
                                     const std::vector<Eigen::Vector3f>& normals,
                                     const Eigen::Matrix3f& r, const SurfaceOptions& o) {
  const Eigen::Vector3f up = r.row(2).transpose();
  const float min_nz = static_cast<float>(std::cos(o.max_tilt_deg * M_PI / 180.0));
  std::vector<Vec3f> out;
  out.reserve(sample->size());
  for (std::size_t i = 0; i < sample->size(); ++i)
    if (std::fabs(normals[i].dot(up)) >= min_nz) out.push_back(r * (*sample)[i].getVector3fMap());
  return out;
}

}  // namespace

void SurfaceOptions::check() const {
  require(sample_voxel_m > 0.0, "SurfaceOptions.sample_voxel_m", "must be > 0");
  require(max_tilt_deg >= 0.0 && max_tilt_deg <= 90.0, "SurfaceOptions.max_tilt_deg",
          "must be in [0, 90]");
  require(piece_height_m >= 0.0, "SurfaceOptions.piece_height_m", "must be >= 0");
  require(cluster_gap_m > 0.0, "SurfaceOptions.cluster_gap_m", "must be > 0");
  require(min_area_m2 > 0.0, "SurfaceOptions.min_area_m2", "must be > 0");
  require(min_width_m >= 0.0, "SurfaceOptions.min_width_m", "must be >= 0");
  require(merge_height_m >= 0.0, "SurfaceOptions.merge_height_m", "must be >= 0");
  require(merge_gap_m >= 0.0, "SurfaceOptions.merge_gap_m", "must be >= 0");
  require(table_min_area_m2 < table_max_area_m2, "SurfaceOptions.table_min_area_m2",
          "must be < table_max_area_m2");
  require(table_min_height_m < table_max_height_m, "SurfaceOptions.table_min_height_m",
          "must be < table_max_height_m");
}

std::vector<Surface> find_surfaces(const std::vector<Vec3f>& map_points, const Vec3& up,
                                   const SurfaceOptions& o) {
  if (!o.enabled || map_points.empty()) return {};
  const detail::Cloud::Ptr sample = detail::sample_on_grid(map_points, o.sample_voxel_m);
  return detail::find_surfaces(sample, detail::grid_normals(sample, o.sample_voxel_m), up, o);
}

std::vector<Surface> detail::find_surfaces(const Cloud::Ptr& sample,
                                           const std::vector<Eigen::Vector3f>& normals,
                                           const Vec3& up, const SurfaceOptions& o) {
  std::vector<Surface> surfaces;
  if (!o.enabled || sample->empty()) return surfaces;
  const Eigen::Matrix3d gravity = gravity_from_world(up);
  const double cell = o.sample_voxel_m;
  const std::size_t min_points =
      std::max<std::size_t>(10, static_cast<std::size_t>(o.min_area_m2 / (cell * cell)));
  const std::vector<Vec3f> g = horizontal_points(sample, normals, gravity.cast<float>(), o);
  std::vector<Patch> patches;
  for (Patch& p : horizontal_patches(g, o, min_points))
    if (narrow_spread(p) >= o.min_width_m) patches.push_back(std::move(p));
  for (const Patch& p : merge_layers(std::move(patches), o)) {
    Surface s = make_surface(p, gravity, cell);
    if (s.area_m2 >= o.min_area_m2) surfaces.push_back(std::move(s));
  }
  std::stable_sort(surfaces.begin(), surfaces.end(),
                   [](const Surface& a, const Surface& b) { return a.area_m2 > b.area_m2; });
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    surfaces[i].id = static_cast<int>(i) + 1;
    surfaces[i].label = "surface";
  }
  return surfaces;
}

void mark_object_tops(std::vector<Surface>& surfaces, const Vec3& up,
                      const std::vector<SceneObject>& objects) {
  const Eigen::Matrix3d gravity = gravity_from_world(up);
  std::vector<detail::Footprint> footprints;
  for (const auto& obj : objects)
    footprints.push_back(detail::footprint(obj.cloud ? obj.cloud->points : std::vector<Vec3f>{},
                                           gravity, obj.position));
  for (Surface& s : surfaces) s.object = object_under(s, gravity, objects, footprints);
}

}  // namespace objmap::scene

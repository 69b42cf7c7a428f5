// Support surfaces: horizontal patches of the dense map (docs/scene.md, "Surfaces").
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <set>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/scene/footprint.h"
#include "objmap/scene/pcl_cloud.h"
#include "objmap/scene/scene.h"

namespace objmap::scene {
namespace {

using Cell = std::pair<long, long>;

// A patch while it is built: its sample points (gravity frame) and occupied grid cells.
struct Patch {
  std::vector<Vec3f> points;  // gravity frame
  std::set<Cell> cells;
  double level = 0.0;  // the histogram level it came from
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

// Step 1: the horizontal levels: peaks of the histogram of the sample's heights (a bin at least
// as full as the two bins on either side, with at least `min_points`), fullest first.
std::vector<double> levels(const std::vector<Vec3f>& g, const SurfaceOptions& o,
                           std::size_t min_points) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (const Vec3f& p : g) lo = std::min(lo, p.z()), hi = std::max(hi, p.z());
  const std::size_t bins = static_cast<std::size_t>((hi - lo) / o.bin_m) + 1;
  std::vector<std::size_t> count(bins, 0);
  for (const Vec3f& p : g) ++count[static_cast<std::size_t>((p.z() - lo) / o.bin_m)];
  std::vector<std::pair<std::size_t, double>> peaks;
  for (std::size_t b = 0; b < bins; ++b) {
    bool peak = count[b] >= min_points;
    for (std::size_t k = b >= 2 ? b - 2 : 0; peak && k <= std::min(bins - 1, b + 2); ++k)
      peak = k == b || count[k] < count[b] || (count[k] == count[b] && k > b);
    if (peak) peaks.emplace_back(count[b], lo + (static_cast<double>(b) + 0.5) * o.bin_m);
  }
  std::stable_sort(peaks.begin(), peaks.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<double> out;
  for (std::size_t i = 0; i < peaks.size() && static_cast<int>(i) < o.max_levels; ++i)
    out.push_back(peaks[i].second);
  return out;
}

// Step 2: a level's points (not taken by a fuller level) split into patches by Euclidean
// clustering (PCL) at most cluster_gap_m apart.
std::vector<Patch> patches_at(double level, const std::vector<Vec3f>& g, std::vector<bool>& used,
                              const SurfaceOptions& o, std::size_t min_points) {
  detail::Cloud::Ptr slab(new detail::Cloud);
  for (std::size_t i = 0; i < g.size(); ++i)
    if (!used[i] && std::fabs(g[i].z() - level) <= o.plane_distance_m) {
      used[i] = true;
      slab->push_back(pcl::PointXYZ(g[i].x(), g[i].y(), g[i].z()));
    }
  std::vector<Patch> out;
  if (slab->size() < min_points) return out;
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(slab);
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> extract;
  extract.setClusterTolerance(o.cluster_gap_m);
  extract.setMinClusterSize(static_cast<int>(min_points));
  extract.setMaxClusterSize(std::numeric_limits<int>::max());
  extract.setSearchMethod(tree);
  extract.setInputCloud(slab);
  std::vector<pcl::PointIndices> clusters;
  extract.extract(clusters);
  for (const auto& c : clusters) {
    Patch p;
    p.level = level;
    for (int k : c.indices) p.add((*slab)[k].getVector3fMap(), o.sample_voxel_m);
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
// 2 × plane_distance_m, boxes less than merge_gap_m apart).
bool one_surface(const Patch& m, const Patch& p, const SurfaceOptions& o) {
  const double dh = std::fabs(m.level - p.level);
  if (dh <= 2 * o.plane_distance_m) {
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
// its top.
std::optional<int> object_under(const Surface& s, const Eigen::Matrix3d& gravity_from_world,
                                const std::vector<SceneObject>& objects,
                                const std::vector<detail::Footprint>& footprints) {
  const Vec3 g = gravity_from_world * s.center;
  const cv::Point2f c(static_cast<float>(g.x()), static_cast<float>(g.y()));
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const auto& f = footprints[i];
    if (s.height_m >= f.bottom + 0.01 && s.height_m <= f.top + 0.03 &&
        detail::inside_distance(f.hull, c) >= 0.0)
      return objects[i].id;
  }
  return std::nullopt;
}

}  // namespace

void SurfaceOptions::check() const {
  require(sample_voxel_m > 0.0, "SurfaceOptions.sample_voxel_m", "must be > 0");
  require(bin_m > 0.0, "SurfaceOptions.bin_m", "must be > 0");
  require(plane_distance_m > 0.0, "SurfaceOptions.plane_distance_m", "must be > 0");
  require(max_levels >= 1, "SurfaceOptions.max_levels", "must be >= 1");
  require(cluster_gap_m > 0.0, "SurfaceOptions.cluster_gap_m", "must be > 0");
  require(min_area_m2 > 0.0, "SurfaceOptions.min_area_m2", "must be > 0");
  require(min_width_m >= 0.0, "SurfaceOptions.min_width_m", "must be >= 0");
  require(merge_height_m >= 0.0, "SurfaceOptions.merge_height_m", "must be >= 0");
  require(merge_gap_m >= 0.0, "SurfaceOptions.merge_gap_m", "must be >= 0");
  require(table_min_height_m < table_max_height_m, "SurfaceOptions.table_min_height_m",
          "must be < table_max_height_m");
}

std::vector<Surface> find_surfaces(const std::vector<Vec3f>& map_points, const Vec3& up,
                                   const std::vector<SceneObject>& objects,
                                   const SurfaceOptions& o) {
  std::vector<Surface> surfaces;
  if (!o.enabled || map_points.empty()) return surfaces;
  const Eigen::Matrix3d gravity = gravity_from_world(up);
  const double cell = o.sample_voxel_m;
  const std::size_t min_points =
      std::max<std::size_t>(10, static_cast<std::size_t>(o.min_area_m2 / (cell * cell)));
  const detail::Cloud::Ptr sample = detail::sample_on_grid(map_points, cell, 600000);
  std::vector<Vec3f> g(sample->size());
  const Eigen::Matrix3f r = gravity.cast<float>();
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = r * (*sample)[i].getVector3fMap();
  std::vector<bool> used(g.size(), false);
  std::vector<Patch> patches;
  for (double level : levels(g, o, min_points))
    for (Patch& p : patches_at(level, g, used, o, min_points))
      if (narrow_spread(p) >= o.min_width_m) patches.push_back(std::move(p));
  std::vector<detail::Footprint> footprints;
  for (const auto& obj : objects)
    footprints.push_back(detail::footprint(obj.cloud ? obj.cloud->points : std::vector<Vec3f>{},
                                           gravity, obj.position));
  for (const Patch& p : merge_layers(std::move(patches), o)) {
    Surface s = make_surface(p, gravity, cell);
    if (s.area_m2 < o.min_area_m2) continue;
    s.object = object_under(s, gravity, objects, footprints);
    surfaces.push_back(std::move(s));
  }
  std::stable_sort(surfaces.begin(), surfaces.end(),
                   [](const Surface& a, const Surface& b) { return a.area_m2 > b.area_m2; });
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    surfaces[i].id = static_cast<int>(i) + 1;
    surfaces[i].label = "surface";
  }
  return surfaces;
}

}  // namespace objmap::scene

// The up direction of the world: a prior from the cameras, refined by the dense map's horizontal
// planes (docs/scene.md, "Up direction").
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/scene/sampled.h"

namespace objmap::scene {
namespace {

double angle_deg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

// Step 1: the cameras' prior. Cameras are held roughly upright: the camera's y axis points down,
// so the mean of the cameras' -y axes points up, tilted by how far they look down (30-50 deg at a
// desk) but not by how they roll. The mean viewing direction (z axes) tells a floor or table top
// (the cameras look down at it) from a wall in front of them (as far from the prior).
void camera_prior(const std::vector<Pose>& cameras, UpEstimate& e) {
  Vec3 mean_up = Vec3::Zero();
  Vec3 mean_view = Vec3::Zero();
  for (const Pose& c : cameras) {
    mean_up -= c.linear().col(1);
    mean_view += c.linear().col(2);
  }
  const double n = static_cast<double>(std::max<std::size_t>(cameras.size(), 1));
  e.camera_agreement = mean_up.norm() / n;
  e.camera_prior = e.camera_agreement > 0.0 ? Vec3(mean_up.normalized()) : Vec3::UnitZ();
  e.camera_view = mean_view / n;
}

// Step 2: the sample's normals that may be a horizontal surface's, signed toward the prior: within
// max_prior_angle of it, and the cameras do not look up at them (mean view elevation <=
// max_view_elevation: a wall in front of cameras that look down at a desk is as far from the prior
// as the desk, but they would look up at it as if it were a ceiling).
std::vector<Vec3> candidate_normals(const std::vector<Eigen::Vector3f>& normals,
                                    const UpEstimate& e, const UpOptions& o) {
  const double min_cos = std::cos(o.max_prior_angle_deg * M_PI / 180.0);
  std::vector<Vec3> out;
  for (const Eigen::Vector3f& f : normals) {
    if (f.isZero()) continue;
    Vec3 n = f.cast<double>().normalized();
    if (n.dot(e.camera_prior) < 0) n = -n;
    if (n.dot(e.camera_prior) >= min_cos && e.camera_view.dot(n) <= o.max_view_elevation)
      out.push_back(n);
  }
  return out;
}

// The candidates' directions on a grid around the prior (gnomonic: x/z, y/z in `frame`, whose z is
// the prior), each cell's count summed over the cells around it (a window about 2 · window_cells
// cells wide): the density of the normals, a function of the map alone.
struct NormalDensity {
  Eigen::Matrix3d frame;  // rows: x, y, z = the prior
  double half = 0.0, cell = 0.0;
  int size = 0;
  std::vector<double> sum;  // size × size, the window's count
  Vec3 direction(int i, int j) const {
    const double a = -half + (i + 0.5) * cell, b = -half + (j + 0.5) * cell;
    return (frame.transpose() * Vec3(a, b, 1.0)).normalized();
  }
  double at(int i, int j) const { return sum[static_cast<std::size_t>(i * size + j)]; }
};
NormalDensity normal_density(const std::vector<Vec3>& normals, const Eigen::Matrix3d& frame,
                             const UpOptions& o) {
  constexpr int kWindow = 2;  // cells each side
  NormalDensity d;
  d.frame = frame;
  d.half = std::tan(o.max_prior_angle_deg * M_PI / 180.0);
  d.cell = std::tan(o.density_cell_deg * M_PI / 180.0);
  d.size = static_cast<int>(std::ceil(2.0 * d.half / d.cell));
  std::vector<double> count(static_cast<std::size_t>(d.size) * d.size, 0.0);
  for (const Vec3& n : normals) {
    const Vec3 f = frame * n;
    const int i = static_cast<int>(std::floor((f.x() / f.z() + d.half) / d.cell));
    const int j = static_cast<int>(std::floor((f.y() / f.z() + d.half) / d.cell));
    if (i >= 0 && j >= 0 && i < d.size && j < d.size) count[i * d.size + j] += 1.0;
  }
  d.sum.assign(count.size(), 0.0);
  for (int i = 0; i < d.size; ++i)
    for (int j = 0; j < d.size; ++j) {
      double s = 0.0;
      for (int a = std::max(0, i - kWindow); a <= std::min(d.size - 1, i + kWindow); ++a)
        for (int b = std::max(0, j - kWindow); b <= std::min(d.size - 1, j + kWindow); ++b)
          s += count[a * d.size + b];
      d.sum[i * d.size + j] = s;
    }
  return d;
}

// Step 3: where the candidates' normals are densest (the largest horizontal area: floor and table
// tops together), unless a peak about perpendicular to it (>= 60 deg) lies closer to the prior
// with at least a quarter of its density (a wall seen more than the floor: both are candidates
// when the prior leans 40 deg; the horizontal one is the nearer).
std::optional<Vec3> densest_direction(const NormalDensity& d, const Vec3& prior) {
  int bi = -1, bj = -1;
  for (int i = 0; i < d.size; ++i)
    for (int j = 0; j < d.size; ++j)
      if (d.at(i, j) > 0 && (bi < 0 || d.at(i, j) > d.at(bi, bj))) bi = i, bj = j;
  if (bi < 0) return std::nullopt;
  const Vec3 best = d.direction(bi, bj);
  Vec3 chosen = best;
  const auto peak = [&](int i, int j) {
    for (int a = std::max(0, i - 1); a <= std::min(d.size - 1, i + 1); ++a)
      for (int b = std::max(0, j - 1); b <= std::min(d.size - 1, j + 1); ++b)
        if (d.at(a, b) > d.at(i, j)) return false;
    return true;
  };
  for (int i = 0; i < d.size; ++i)
    for (int j = 0; j < d.size; ++j) {
      if (4 * d.at(i, j) < d.at(bi, bj) || !peak(i, j)) continue;
      const Vec3 c = d.direction(i, j);
      if (angle_deg(c, best) >= 60.0 && angle_deg(c, prior) < angle_deg(chosen, prior)) chosen = c;
    }
  return chosen;
}

// Step 4: from there, the mean of the normals within family_deg of the estimate, until it no longer
// moves (mean shift: it climbs to the nearest mode of the normals' density whatever the start).
// The normals of the floor and the table tops are averaged point by point: each sample point is a
// cell of the grid, so each surface weighs by its area.
Vec3 mean_shift(const std::vector<Vec3>& normals, Vec3 u, double family_deg, std::size_t& members) {
  const double min_cos = std::cos(family_deg * M_PI / 180.0);
  for (int iteration = 0; iteration < 100; ++iteration) {
    Vec3 sum = Vec3::Zero();
    members = 0;
    for (const Vec3& n : normals)
      if (n.dot(u) >= min_cos) {
        sum += n;
        ++members;
      }
    if (members == 0) return u;
    const Vec3 next = sum.normalized();
    const bool still = (next - u).norm() < 1e-9;
    u = next;
    if (still) break;
  }
  return u;
}

// A level's plane: the least-squares plane of the sample points heights[begin, end) index.
PlaneEvidence level_plane(const detail::Cloud& sample,
                          const std::vector<std::pair<double, std::size_t>>& heights,
                          std::size_t begin, std::size_t end, const Vec3& up, const UpEstimate& e) {
  Vec3 mean = Vec3::Zero();
  for (std::size_t k = begin; k < end; ++k)
    mean += sample[heights[k].second].getVector3fMap().cast<double>();
  mean /= static_cast<double>(end - begin);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = begin; k < end; ++k) {
    const Vec3 q = sample[heights[k].second].getVector3fMap().cast<double>() - mean;
    cov.noalias() += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  PlaneEvidence p;
  p.normal = eig.eigenvectors().col(0);
  if (p.normal.dot(up) < 0) p.normal = -p.normal;
  p.offset = p.normal.dot(mean);
  p.inliers = end - begin;
  p.angle_to_prior_deg = angle_deg(p.normal, e.camera_prior);
  p.view_elevation = e.camera_view.dot(p.normal);
  return p;
}

// Step 5: the horizontal levels (floor, table tops): the sample points whose normal lies within
// family_deg of up, split along up where fewer than 1 in 500 of them (and 2) fall in a slice of
// plane_distance_m / 2; each level's plane by least squares; the levels of at least min_plane_share
// of these points, largest first (at most max_planes).
std::vector<PlaneEvidence> horizontal_levels(const detail::Cloud& sample,
                                             const std::vector<Eigen::Vector3f>& normals,
                                             const Vec3& up, const UpEstimate& e,
                                             const UpOptions& o) {
  const double min_cos = std::cos(o.family_deg * M_PI / 180.0);
  std::vector<std::pair<double, std::size_t>> heights;
  for (std::size_t i = 0; i < normals.size(); ++i)
    if (!normals[i].isZero() && std::abs(normals[i].cast<double>().normalized().dot(up)) >= min_cos)
      heights.emplace_back(up.dot(sample[i].getVector3fMap().cast<double>()), i);
  std::vector<PlaneEvidence> levels;
  if (heights.empty()) return levels;
  std::sort(heights.begin(), heights.end());
  const double slice = o.plane_distance_m / 2.0;
  const std::size_t min_slice = std::max<std::size_t>(2, heights.size() / 500);
  const std::size_t min_points = std::max<std::size_t>(
      3, static_cast<std::size_t>(o.min_plane_share * static_cast<double>(heights.size())));
  const auto slice_of = [&](std::size_t k) {
    return static_cast<long>(std::floor((heights[k].first - heights.front().first) / slice));
  };
  std::size_t begin = 0;  // the level's first point
  for (std::size_t k = 0; k <= heights.size();) {
    // The slice starting at point k: [k, next).
    std::size_t next = k;
    while (next < heights.size() && slice_of(next) == slice_of(k)) ++next;
    const bool dense = k < heights.size() && next - k >= min_slice &&
                       (k == begin || slice_of(k) == slice_of(k - 1) + 1);
    if (!dense) {
      if (k > begin && k - begin >= min_points)
        levels.push_back(level_plane(sample, heights, begin, k, up, e));
      begin = k < heights.size() && next - k >= min_slice ? k : next;
    }
    if (k == heights.size()) break;
    k = next;
  }
  std::stable_sort(levels.begin(), levels.end(),
                   [](const auto& a, const auto& b) { return a.inliers > b.inliers; });
  if (levels.size() > static_cast<std::size_t>(o.max_planes)) levels.resize(o.max_planes);
  return levels;
}

// Step 6: up is the inlier-weighted mean of the levels' planes within parallel_deg of it, the
// levels taken again along it, until it moves less than 0.001 deg (at most 10 rounds). The planes'
// own fits (thousands of points each) are steadier than the points' normals, which lean with the
// depth's noise.
void refine_on_levels(const detail::Cloud& sample, const std::vector<Eigen::Vector3f>& normals,
                      UpEstimate& e, const UpOptions& o) {
  for (int round = 0; round < 10; ++round) {
    e.planes = horizontal_levels(sample, normals, e.up, e, o);
    Vec3 sum = Vec3::Zero();
    for (const auto& p : e.planes)
      if (angle_deg(p.normal, e.up) <= o.parallel_deg)
        sum += static_cast<double>(p.inliers) * p.normal;
    if (sum.isZero()) break;
    const Vec3 next = sum.normalized();
    const bool still = angle_deg(next, e.up) < 0.001;
    e.up = next;
    if (still) break;
  }
  for (auto& p : e.planes) p.used = angle_deg(p.normal, e.up) <= o.parallel_deg;
}

// Steps 2-4: up from the sample's normals, nullopt when no family of them near the prior holds
// min_plane_share of the sample.
std::optional<Vec3> normals_up(const std::vector<Eigen::Vector3f>& normals, const UpEstimate& e,
                               const Eigen::Matrix3d& frame, const UpOptions& o) {
  const std::vector<Vec3> candidates = candidate_normals(normals, e, o);
  const std::optional<Vec3> start =
      densest_direction(normal_density(candidates, frame, o), e.camera_prior);
  if (!start) return std::nullopt;
  std::size_t members = 0;
  const Vec3 up = mean_shift(candidates, *start, o.family_deg, members);
  if (static_cast<double>(members) < o.min_plane_share * static_cast<double>(normals.size()))
    return std::nullopt;
  return up;
}

}  // namespace

void UpOptions::check() const {
  parse_up(mode, "UpOptions.mode");
  require(sample_voxel_m > 0.0, "UpOptions.sample_voxel_m",
          "must be > 0, got " + std::to_string(sample_voxel_m));
  require(plane_distance_m > 0.0, "UpOptions.plane_distance_m",
          "must be > 0, got " + std::to_string(plane_distance_m));
  require(max_planes >= 1, "UpOptions.max_planes", "must be >= 1");
  require(min_plane_share > 0.0 && min_plane_share < 1.0, "UpOptions.min_plane_share",
          "must be in (0, 1)");
  require(max_prior_angle_deg > 0.0 && max_prior_angle_deg <= 90.0, "UpOptions.max_prior_angle_deg",
          "must be in (0, 90]");
  require(family_deg > 0.0 && family_deg < 45.0, "UpOptions.family_deg", "must be in (0, 45)");
  require(parallel_deg > 0.0 && parallel_deg < 45.0, "UpOptions.parallel_deg",
          "must be in (0, 45)");
  require(density_cell_deg > 0.0 && density_cell_deg < 10.0, "UpOptions.density_cell_deg",
          "must be in (0, 10)");
}

std::optional<Vec3> parse_up(const std::string& text, const std::string& where) {
  if (text == "auto") return std::nullopt;
  static const char* kAxes[] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis)
    for (const char* sign : {"", "+", "-"})
      if (text == std::string(sign) + kAxes[axis])
        return (std::string(sign) == "-" ? -1.0 : 1.0) * Vec3::Unit(axis);
  std::vector<double> v;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != part.size() || !std::isfinite(value)) {
      v.clear();
      break;
    }
    v.push_back(value);
  }
  const bool ok = v.size() == 3 && Vec3(v[0], v[1], v[2]).norm() > 1e-9;
  require(ok, where,
          "'" + text +
              "' is not an up direction; expected auto, an axis (x, y, z, -x, -y, -z) or " +
              "a vector x,y,z");
  return Vec3(v[0], v[1], v[2]).normalized();
}

Eigen::Matrix3d gravity_from_world(const Vec3& up) {
  const Vec3 u = up.normalized();
  if (u.dot(Vec3::UnitZ()) < -1.0 + 1e-12)
    return Eigen::Matrix3d(Eigen::AngleAxisd(M_PI, Vec3::UnitX()));
  return Eigen::Quaterniond::FromTwoVectors(u, Vec3::UnitZ()).toRotationMatrix();
}

detail::GridFrame detail::camera_frame(const std::vector<Pose>& cameras) {
  GridFrame f;
  if (cameras.empty()) return f;
  UpEstimate e;
  camera_prior(cameras, e);
  const Vec3 z = e.camera_prior;
  Vec3 x = e.camera_view - e.camera_view.dot(z) * z;
  if (x.norm() < 1e-6) x = z.unitOrthogonal();
  x.normalize();
  f.grid_from_world.row(0) = x.transpose();
  f.grid_from_world.row(1) = z.cross(x).transpose();
  f.grid_from_world.row(2) = z.transpose();
  for (const Pose& c : cameras) f.origin += c.translation();
  f.origin /= static_cast<double>(cameras.size());
  return f;
}

UpEstimate estimate_up(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                       const UpOptions& options) {
  if (parse_up(options.mode, "--up"))
    return detail::estimate_up(cameras, detail::Cloud::Ptr(new detail::Cloud), {}, options);
  const detail::GridFrame frame = detail::camera_frame(cameras);
  const detail::Cloud::Ptr sample =
      detail::sample_on_grid(map_points, options.sample_voxel_m, frame);
  return detail::estimate_up(cameras, sample,
                             detail::grid_normals(sample, options.sample_voxel_m, frame), options);
}

UpEstimate detail::estimate_up(const std::vector<Pose>& cameras, const Cloud::Ptr& sample,
                               const std::vector<Eigen::Vector3f>& normals,
                               const UpOptions& options) {
  UpEstimate e;
  camera_prior(cameras, e);
  if (const auto given = parse_up(options.mode, "--up")) {
    e.source = "given";
    e.up = *given;
  } else {
    e.sample_points = sample->size();
    const std::optional<Vec3> planes_up =
        normals_up(normals, e, camera_frame(cameras).grid_from_world, options);
    e.source = planes_up ? "planes" : "cameras";
    e.up = planes_up ? *planes_up : e.camera_prior;
    if (planes_up) refine_on_levels(*sample, normals, e, options);
    if (e.camera_agreement < 0.5)
      e.warnings.push_back("the cameras' up axes disagree (agreement " +
                           fixed_text(e.camera_agreement, 2) +
                           " < 0.5: a camera not held upright, e.g. on a ceiling?); the up "
                           "direction rests on the map's planes alone; give --up if it is known");
    if (!planes_up && sample->empty())
      e.warnings.push_back(
          "no dense map to find the floor and tables in (--dense-map false): up is the cameras' "
          "(the mean of their -y axes), and with it the objects' upright boxes, positions and "
          "relations; give --up if the world's up is known");
    else if (!planes_up)
      e.warnings.push_back(
          "no plane of the dense map lies within " + fixed_text(options.max_prior_angle_deg, 0) +
          " deg of the cameras' up (the mean of their -y axes) that they look down "
          "at; up is the cameras'; give --up if the world's up is known");
  }
  e.prior_to_up_deg = angle_deg(e.camera_prior, e.up);
  if (e.source == "planes" && e.prior_to_up_deg > options.disagree_warning_deg)
    e.warnings.push_back("the map's horizontal planes are " + fixed_text(e.prior_to_up_deg, 1) +
                         " deg from the cameras' up; check the up direction in the report, give "
                         "--up if it is wrong");
  e.gravity_from_world = gravity_from_world(e.up);
  return e;
}

}  // namespace objmap::scene

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

// Step 2: the dominant planes of the sampled map, one after another (RANSAC, then the next in
// what is left), while each holds at least min_plane_share of the sample.
std::vector<PlaneEvidence> dominant_planes(const detail::Cloud::Ptr& sample, const UpOptions& o,
                                           UpEstimate& e) {
  std::vector<PlaneEvidence> planes;
  detail::Cloud::Ptr rest = sample;
  e.sample_points = rest->size();
  const std::size_t min_inliers = std::max<std::size_t>(
      50, static_cast<std::size_t>(o.min_plane_share * static_cast<double>(rest->size())));
  for (int i = 0; i < o.max_planes && rest->size() >= min_inliers; ++i) {
    detail::Plane plane = detail::fit_plane(rest, o.plane_distance_m);
    if (plane.inliers.size() < min_inliers) break;
    PlaneEvidence p;
    const double sign = plane.normal.dot(e.camera_prior) < 0 ? -1.0 : 1.0;
    p.normal = sign * plane.normal;
    p.offset = sign * plane.offset;
    p.inliers = plane.inliers.size();
    p.angle_to_prior_deg = angle_deg(p.normal, e.camera_prior);
    p.view_elevation = e.camera_view.dot(p.normal);
    planes.push_back(p);
    std::sort(plane.inliers.begin(), plane.inliers.end());
    rest = detail::without(rest, plane.inliers);
  }
  return planes;
}

// Step 3: the horizontal planes. Candidates lie within max_prior_angle of the prior and the cameras
// do not look up at them (mean view elevation <= max_view_elevation: a wall in front of cameras
// that look down at a desk is as far from the prior as the desk, but they would look up at it as
// if it were a ceiling); the one with
// the most support (its inliers and those of the planes parallel to it) wins, unless a candidate
// about perpendicular to it is closer to the prior (a wall found before the floor: both are
// candidates when the prior leans 40°; the horizontal one is the nearer). Up is the inlier-weighted
// mean of the winner and its parallels.
std::optional<Vec3> horizontal_up(std::vector<PlaneEvidence>& planes, const UpOptions& o) {
  const auto support = [&](const PlaneEvidence& c) {
    std::size_t s = 0;
    for (const auto& p : planes)
      if (angle_deg(p.normal, c.normal) <= o.parallel_deg) s += p.inliers;
    return s;
  };
  const auto candidate = [&](const PlaneEvidence& c) {
    return c.angle_to_prior_deg <= o.max_prior_angle_deg &&
           c.view_elevation <= o.max_view_elevation;
  };
  const PlaneEvidence* best = nullptr;
  for (const auto& c : planes)
    if (candidate(c) && (!best || support(c) > support(*best))) best = &c;
  if (!best) return std::nullopt;
  const PlaneEvidence* chosen = best;
  for (const auto& c : planes)
    if (c.angle_to_prior_deg <= o.max_prior_angle_deg &&
        angle_deg(c.normal, best->normal) >= 60.0 &&
        c.angle_to_prior_deg < chosen->angle_to_prior_deg && 4 * support(c) >= support(*best))
      chosen = &c;
  Vec3 sum = Vec3::Zero();
  const Vec3 axis = chosen->normal;
  for (auto& p : planes)
    if (angle_deg(p.normal, axis) <= o.parallel_deg) {
      sum += static_cast<double>(p.inliers) * p.normal;
      p.used = true;
    }
  return Vec3(sum.normalized());
}

}  // namespace

void UpOptions::check() const {
  parse_up(mode, "UpOptions.mode");
  require(sample_voxel_m > 0.0, "UpOptions.sample_voxel_m",
          "must be > 0, got " + std::to_string(sample_voxel_m));
  require(max_sample_points >= 100, "UpOptions.max_sample_points",
          "must be >= 100, got " + std::to_string(max_sample_points));
  require(plane_distance_m > 0.0, "UpOptions.plane_distance_m",
          "must be > 0, got " + std::to_string(plane_distance_m));
  require(max_planes >= 1, "UpOptions.max_planes", "must be >= 1");
  require(min_plane_share > 0.0 && min_plane_share < 1.0, "UpOptions.min_plane_share",
          "must be in (0, 1)");
  require(max_prior_angle_deg > 0.0 && max_prior_angle_deg <= 90.0, "UpOptions.max_prior_angle_deg",
          "must be in (0, 90]");
  require(parallel_deg > 0.0 && parallel_deg < 45.0, "UpOptions.parallel_deg",
          "must be in (0, 45)");
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

UpEstimate estimate_up(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                       const UpOptions& options) {
  const detail::Cloud::Ptr sample =
      parse_up(options.mode, "--up")
          ? detail::Cloud::Ptr(new detail::Cloud)
          : detail::thin(detail::sample_on_grid(map_points, options.sample_voxel_m),
                         static_cast<std::size_t>(options.max_sample_points));
  return detail::estimate_up(cameras, sample, options);
}

UpEstimate detail::estimate_up(const std::vector<Pose>& cameras, const Cloud::Ptr& sample,
                               const UpOptions& options) {
  UpEstimate e;
  camera_prior(cameras, e);
  if (const auto given = parse_up(options.mode, "--up")) {
    e.source = "given";
    e.up = *given;
  } else {
    e.planes = dominant_planes(sample, options, e);
    const std::optional<Vec3> planes_up = horizontal_up(e.planes, options);
    e.source = planes_up ? "planes" : "cameras";
    e.up = planes_up ? *planes_up : e.camera_prior;
    if (e.camera_agreement < 0.5)
      e.warnings.push_back("the cameras' up axes disagree (agreement " +
                           fixed_text(e.camera_agreement, 2) +
                           " < 0.5: a camera not held upright, e.g. on a ceiling?); the up "
                           "direction rests on the map's planes alone; give --up if it is known");
    if (!planes_up)
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

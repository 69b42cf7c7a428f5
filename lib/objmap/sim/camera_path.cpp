#include "objmap/sim/camera_path.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/sim/random.h"
#include "objmap/sim/text.h"

namespace objmap::sim {

namespace {
constexpr double kDeg = M_PI / 180.0;

bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }
}  // namespace

void CameraPathOptions::check() const {
  require(std::isfinite(radius_m) && radius_m > 0.0, "CameraPathOptions.radius_m",
          "must be > 0, got " + num(radius_m));
  require(std::isfinite(height_m) && std::isfinite(look_at_height_m) &&
              std::isfinite(start_angle_deg) && std::isfinite(speed_deg_per_s) &&
              orbit_center_world.allFinite(),
          "CameraPathOptions", "heights, angles and the orbit centre must be finite");
  require(finite_nonneg(jitter_translation_m), "CameraPathOptions.jitter_translation_m",
          "must be >= 0, got " + num(jitter_translation_m));
  require(finite_nonneg(jitter_rotation_deg), "CameraPathOptions.jitter_rotation_deg",
          "must be >= 0, got " + num(jitter_rotation_deg));
  require(std::isfinite(walk_speed_m_per_s) && walk_speed_m_per_s > 0.0,
          "CameraPathOptions.walk_speed_m_per_s", "must be > 0, got " + num(walk_speed_m_per_s));
  require(waypoints.empty() || waypoints.size() >= 2, "CameraPathOptions.waypoints",
          "a walk needs at least 2 waypoints, got 1");
  for (std::size_t i = 0; i < waypoints.size(); ++i)
    require(waypoints[i].eye_world.allFinite() && waypoints[i].target_world.allFinite() &&
                (waypoints[i].target_world - waypoints[i].eye_world).norm() > 1e-6 &&
                (waypoints[i].eye_world - waypoints[(i + 1) % waypoints.size()].eye_world).norm() >
                    1e-6,
            "CameraPathOptions.waypoints[" + std::to_string(i) + "]",
            "eye and target must be finite and apart, and the eye apart from the next one");
}

namespace {

// The eye and target at `distance` metres along the closed loop of waypoints.
std::pair<Vec3, Vec3> on_walk(const std::vector<Waypoint>& w, double distance) {
  double loop = 0.0;
  for (std::size_t i = 0; i < w.size(); ++i)
    loop += (w[(i + 1) % w.size()].eye_world - w[i].eye_world).norm();
  double d = std::fmod(distance, loop);
  for (std::size_t i = 0;; i = (i + 1) % w.size()) {
    const Waypoint &a = w[i], &b = w[(i + 1) % w.size()];
    const double leg = (b.eye_world - a.eye_world).norm();
    if (d <= leg) {
      const double s = d / leg;
      return {a.eye_world + s * (b.eye_world - a.eye_world),
              a.target_world + s * (b.target_world - a.target_world)};
    }
    d -= leg;
  }
}

}  // namespace

void DriftOptions::check() const {
  require(finite_nonneg(translation_fraction), "--drift",
          "translation drift fraction must be >= 0, got " + num(translation_fraction));
  require(finite_nonneg(yaw_deg_per_m), "--yaw-drift",
          "yaw drift must be >= 0 deg/m, got " + num(yaw_deg_per_m));
  require(std::isfinite(random_walk) && random_walk >= 0.0 && random_walk <= 1.0,
          "DriftOptions.random_walk", "must be in [0, 1], got " + num(random_walk));
  require(finite_nonneg(white_noise_m), "DriftOptions.white_noise_m",
          "must be >= 0, got " + num(white_noise_m));
}

Pose look_at(const Vec3& eye, const Vec3& target) {
  const Vec3 z = (target - eye).normalized();
  Vec3 x = z.cross(Vec3::UnitZ());
  if (x.norm() < 1e-9) x = Vec3::UnitX();  // looking straight up or down
  x.normalize();
  const Vec3 y = z.cross(x);
  Pose pose = Pose::Identity();
  pose.linear().col(0) = x;
  pose.linear().col(1) = y;
  pose.linear().col(2) = z;
  pose.translation() = eye;
  return pose;
}

Trajectory make_camera_path(const CameraPathOptions& o, const std::vector<double>& timestamps,
                            std::uint64_t seed) {
  o.check();
  Rng rng(derive_seed(seed, 0, 0xCA3E7A));
  // Three sinusoids per degree of freedom (6: position xyz, rotation xyz); unit std overall.
  struct Wave {
    double amp, freq_hz, phase;
  };
  std::vector<std::vector<Wave>> waves(6);
  for (auto& dof : waves)
    for (int k = 0; k < 3; ++k)
      dof.push_back({rng.uniform(0.5, 1.0), rng.uniform(0.4, 2.5), rng.uniform(0.0, 2.0 * M_PI)});
  auto shake = [&](int dof, double t) {
    double v = 0.0, norm = 0.0;
    for (const auto& w : waves[dof]) {
      v += w.amp * std::sin(2.0 * M_PI * w.freq_hz * t + w.phase);
      norm += 0.5 * w.amp * w.amp;
    }
    return v / std::sqrt(norm);  // unit variance over time
  };

  Trajectory path;
  path.source = "synthetic";
  const double t0 = timestamps.empty() ? 0.0 : timestamps.front();
  for (double ts : timestamps) {
    const double azimuth = (o.start_angle_deg + (ts - t0) * o.speed_deg_per_s) * kDeg;
    const Vec3 eye = o.orbit_center_world +
                     Vec3(o.radius_m * std::cos(azimuth), o.radius_m * std::sin(azimuth), 0.0);
    Vec3 eye_world(eye.x(), eye.y(), o.height_m);
    Vec3 target(o.orbit_center_world.x(), o.orbit_center_world.y(), o.look_at_height_m);
    if (!o.waypoints.empty())
      std::tie(eye_world, target) = on_walk(o.waypoints, (ts - t0) * o.walk_speed_m_per_s);
    Pose pose = look_at(eye_world, target);
    const double dt = ts - t0;
    const Vec3 dp(shake(0, dt), shake(1, dt), shake(2, dt));
    const Vec3 dr(shake(3, dt), shake(4, dt), shake(5, dt));
    pose.translation() += o.jitter_translation_m * dp;
    const Vec3 rot = o.jitter_rotation_deg * kDeg * dr;  // small rotation in the camera frame
    if (rot.norm() > 0.0)
      pose.linear() = pose.linear() * Eigen::AngleAxisd(rot.norm(), rot.normalized()).matrix();
    path.poses.push_back({ts, pose});
  }
  return path;
}

double path_length_m(const Trajectory& trajectory) {
  double length = 0.0;
  for (std::size_t i = 1; i < trajectory.poses.size(); ++i)
    length += (trajectory.poses[i].world_from_cam.translation() -
               trajectory.poses[i - 1].world_from_cam.translation())
                  .norm();
  return length;
}

Trajectory add_drift(const Trajectory& gt, const DriftOptions& o, std::uint64_t seed) {
  o.check();
  Rng rng(derive_seed(seed, 0, 0xD81F7));
  Trajectory est;
  est.source = "synthetic estimate";
  if (gt.empty()) return est;

  // Drift direction: a constant bias plus a random walk, both per metre travelled.
  Vec3 bias(rng.normal(), rng.normal(), 0.3 * rng.normal());
  bias.normalize();
  const double yaw_rate = o.yaw_deg_per_m * kDeg * rng.normal();  // rad per metre
  std::vector<Vec3> error(gt.size(), Vec3::Zero());
  std::vector<double> yaw(gt.size(), 0.0);
  Vec3 wander = Vec3::Zero();
  for (std::size_t i = 1; i < gt.size(); ++i) {
    const double step =
        (gt.poses[i].world_from_cam.translation() - gt.poses[i - 1].world_from_cam.translation())
            .norm();
    wander += Vec3(rng.normal(), rng.normal(), 0.3 * rng.normal()) * 0.3;
    if (wander.norm() > 1.0) wander.normalize();
    const Vec3 direction = (1.0 - o.random_walk) * bias + o.random_walk * (bias + wander);
    error[i] = error[i - 1] + step * direction;
    yaw[i] = yaw[i - 1] + step * yaw_rate;
  }
  // Scale the accumulated translation error so that the end point, including the displacement
  // that the yaw drift causes, is off by the requested fraction of the path length: solve
  // |a + s b| = target for s >= 0 (a: yaw-only displacement at the end, b: translation error).
  const double length = path_length_m(gt);
  const double target = o.translation_fraction * length;
  const Vec3 pivot = gt.poses.front().world_from_cam.translation();
  const Vec3 p_end = gt.poses.back().world_from_cam.translation();
  auto yaw_displacement = [&] {
    return Vec3(Eigen::AngleAxisd(yaw.back(), Vec3::UnitZ()).matrix() * (p_end - pivot) + pivot -
                p_end);
  };
  Vec3 a = yaw_displacement();
  if (a.norm() > 0.7 * target) {  // the yaw's share is capped at 70% of the end error
    const double shrink = a.norm() > 0.0 ? 0.7 * target / a.norm() : 0.0;
    for (double& y : yaw) y *= shrink;
    a = yaw_displacement();
  }
  const Vec3 b = error.back();
  double scale = 0.0;
  if (b.squaredNorm() > 0.0 && target > 0.0) {
    const double qa = b.squaredNorm(), qb = 2.0 * a.dot(b), qc = a.squaredNorm() - target * target;
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) scale = std::max(0.0, (-qb + std::sqrt(disc)) / (2.0 * qa));
  }

  for (std::size_t i = 0; i < gt.size(); ++i) {
    Pose drift = Pose::Identity();
    drift.linear() = Eigen::AngleAxisd(yaw[i], Vec3::UnitZ()).matrix();
    drift.translation() = pivot - drift.linear() * pivot + scale * error[i];
    Pose pose = drift * gt.poses[i].world_from_cam;
    if (i > 0 && o.white_noise_m > 0.0)
      pose.translation() += o.white_noise_m * Vec3(rng.normal(), rng.normal(), rng.normal());
    est.poses.push_back({gt.poses[i].timestamp, pose});
  }
  return est;
}

}  // namespace objmap::sim

#include "objmap/sim/render.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/sim/parallel.h"
#include "objmap/sim/texture.h"

namespace objmap::sim {

namespace {
// round(c * 255) clamped to [0, 255], rounding halves away from zero (as std::lround) without the
// library call: for |x| < 2^52, x - trunc(x) is exact.
inline std::uint8_t to8(double c) {
  const double x = c * 255.0;
  if (!(x > 0.0)) return 0;  // also NaN
  if (x >= 255.0) return 255;
  const int r = static_cast<int>(x);
  return static_cast<std::uint8_t>(r + static_cast<int>(x - r >= 0.5));  // no branch
}

constexpr double kTMin = 1e-6;  // as cast_ray()

struct Lights {
  Vec3 light, fill;  // unit vectors, world frame
};

// Everything that does not depend on the pixel, computed once per frame: the camera centre in each
// part's frame and the bounding-sphere terms (the same expressions as intersect_part() and
// cast_ray(), so the results are bit-identical).
struct PreparedPart {
  const Part* part;
  Eigen::Matrix3d part_from_world_r;
  Vec3 origin_in_part;
};
struct Candidate {
  const SceneObject* object;
  int u0, u1, v0, v1;
  Vec3 origin_from_center;  // camera centre - bounding sphere centre
  double c;                 // |origin_from_center|^2 - radius^2
  std::vector<PreparedPart> parts;
};

// An object's candidate: the pixel rectangle of its box (projected corners; the whole image when a
// corner is behind the camera, e.g. the room around it); none when the box is off the image.
std::optional<Candidate> candidate_of(const SceneObject& o, const Camera& camera,
                                      const Pose& cam_from_world, const Vec3& origin) {
  Candidate c{&o, 0, camera.width - 1, 0, camera.height - 1, Vec3::Zero(), 0.0, {}};
  double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  bool behind = false;
  for (int k = 0; k < 8 && !behind; ++k) {
    const Vec3 corner(k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, k & 4 ? 1.0 : -1.0);
    const Vec3 p =
        cam_from_world * (o.obb.center + o.obb.rotation * corner.cwiseProduct(o.obb.half_extent));
    if (p.z() < 1e-3) {
      behind = true;
      break;
    }
    const Eigen::Vector2d px = camera.project(p);
    umin = std::min(umin, px.x());
    umax = std::max(umax, px.x());
    vmin = std::min(vmin, px.y());
    vmax = std::max(vmax, px.y());
  }
  if (!behind) {
    if (umax < -1.0 || vmax < -1.0 || umin > camera.width || vmin > camera.height)
      return std::nullopt;
    c.u0 = std::max(0, static_cast<int>(std::floor(umin)) - 1);
    c.u1 = std::min(camera.width - 1, static_cast<int>(std::ceil(umax)) + 1);
    c.v0 = std::max(0, static_cast<int>(std::floor(vmin)) - 1);
    c.v1 = std::min(camera.height - 1, static_cast<int>(std::ceil(vmax)) + 1);
  }
  c.origin_from_center = origin - o.bound_center;
  c.c = c.origin_from_center.squaredNorm() - o.bound_radius * o.bound_radius;
  for (std::size_t i = 0; i < o.parts.size(); ++i) {
    PreparedPart p{&o.parts[i], o.world_from_part[i].linear().transpose(), Vec3::Zero()};
    p.origin_in_part = p.part_from_world_r * (origin - o.world_from_part[i].translation());
    c.parts.push_back(p);
  }
  return c;
}

// Screen-space culling: the candidates of the scene's structure and objects, in scene order.
std::vector<Candidate> screen_candidates(const Scene& scene, const Camera& camera,
                                         const Pose& world_from_cam) {
  std::vector<Candidate> candidates;
  const Pose cam_from_world = world_from_cam.inverse();
  const Vec3 origin = world_from_cam.translation();
  for (const auto* list : {&scene.structure, &scene.objects})
    for (const auto& o : *list)
      if (auto c = candidate_of(o, camera, cam_from_world, origin))
        candidates.push_back(std::move(*c));
  return candidates;
}

// Nearest hit of the ray through column u, objects in scene order, bounding sphere first (as
// cast_ray()).
SurfaceHit nearest_hit(const std::vector<const Candidate*>& row_candidates, int u,
                       const Vec3& direction) {
  SurfaceHit hit;
  const double a = direction.squaredNorm();
  for (const Candidate* c : row_candidates) {
    if (u < c->u0 || u > c->u1) continue;
    const double b = c->origin_from_center.dot(direction);
    const double disc = b * b - a * c->c;
    if (disc < 0.0) continue;
    const double s = std::sqrt(disc);
    if ((-b + s) / a <= kTMin || (-b - s) / a >= hit.t) continue;
    for (std::size_t i = 0; i < c->parts.size(); ++i) {
      const PreparedPart& p = c->parts[i];
      const Vec3 d = p.part_from_world_r * direction;
      if (intersect_part_local(*p.part, p.origin_in_part, d, kTMin, &hit)) {
        hit.object = c->object;
        hit.part = static_cast<int>(i);
      }
    }
  }
  return hit;
}

// The colour of a hit (BGR): albedo times ambient + the light + a weak fill light.
cv::Vec3b shaded_colour(const Scene& scene, const Lights& lights, const SurfaceHit& hit,
                        const Vec3& direction) {
  const Part& part = hit.object->parts[hit.part];
  const Eigen::Matrix3d& world_from_part_r = hit.object->world_from_part[hit.part].linear();
  Vec3 normal = world_from_part_r * hit.normal_in_part;
  if (normal.dot(direction) > 0.0) normal = -normal;  // seen from inside (room walls)
  const double shade = scene.ambient +
                       (1.0 - scene.ambient) * std::max(0.0, normal.dot(lights.light)) +
                       0.2 * std::max(0.0, normal.dot(lights.fill));
  const Eigen::Vector3d colour =
      albedo(material_at(part, hit.normal_in_part), hit.point_in_part) * shade;
  return cv::Vec3b(to8(colour.z()), to8(colour.y()), to8(colour.x()));
}

}  // namespace

RenderedFrame render_frame(const Scene& scene, const Camera& camera, const Pose& world_from_cam,
                           int threads) {
  camera.check("synthetic camera");
  require(!camera.has_distortion(), "synthetic camera",
          "has distortion; the renderer casts rays through an undistorted pinhole");
  RenderedFrame frame;
  frame.rgb = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar::all(0));
  frame.depth_m = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar::all(0));
  frame.labels = cv::Mat(camera.height, camera.width, CV_16UC1, cv::Scalar::all(0));
  const Lights lights{scene.light_dir_world.normalized(),
                      Vec3(-0.5, -0.7, 0.4).normalized()};  // fill: weak, from the other side

  // 1. Screen-space culling: each object's pixel rectangle and its per-frame ray terms.
  const std::vector<Candidate> candidates = screen_candidates(scene, camera, world_from_cam);

  // 2. Ray directions with z = 1 in the camera frame (the ray parameter t is the depth z): x
  //    depends on the column only, y on the row only (no distortion).
  std::vector<double> x_of_u(camera.width), y_of_v(camera.height);
  for (int u = 0; u < camera.width; ++u) x_of_u[u] = camera.unproject(u, 0, 1.0).x();
  for (int v = 0; v < camera.height; ++v) y_of_v[v] = camera.unproject(0, v, 1.0).y();

  // 3. Every row: the nearest hit of each pixel's ray, shaded; its depth and object id.
  const Eigen::Matrix3d world_from_cam_r = world_from_cam.linear();
  parallel_for(static_cast<std::size_t>(camera.height), threads, [&](std::size_t row) {
    const int v = static_cast<int>(row);
    auto* rgb = frame.rgb.ptr<cv::Vec3b>(v);
    auto* depth = frame.depth_m.ptr<float>(v);
    auto* label = frame.labels.ptr<std::uint16_t>(v);
    std::vector<const Candidate*> row_candidates;
    for (const auto& c : candidates)
      if (v >= c.v0 && v <= c.v1) row_candidates.push_back(&c);
    for (int u = 0; u < camera.width; ++u) {
      const Vec3 direction_in_cam(x_of_u[u], y_of_v[v], 1.0);
      const Vec3 direction = world_from_cam_r * direction_in_cam;
      const SurfaceHit hit = nearest_hit(row_candidates, u, direction);
      if (!hit.hit()) continue;
      rgb[u] = shaded_colour(scene, lights, hit, direction);
      depth[u] = static_cast<float>(hit.t);
      label[u] = static_cast<std::uint16_t>(hit.object->id);
    }
  });
  return frame;
}

}  // namespace objmap::sim

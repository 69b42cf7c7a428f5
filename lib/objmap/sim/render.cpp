#include "objmap/sim/render.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/sim/parallel.h"
#include "objmap/sim/texture.h"

namespace objmap::sim {

RenderedFrame render_frame(const Scene& scene, const Camera& camera, const Pose& world_from_cam,
                           int threads) {
  camera.check("synthetic camera");
  require(!camera.has_distortion(), "synthetic camera",
          "has distortion; the renderer casts rays through an undistorted pinhole");
  RenderedFrame frame;
  frame.rgb = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar::all(0));
  frame.depth_m = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar::all(0));
  frame.labels = cv::Mat(camera.height, camera.width, CV_16UC1, cv::Scalar::all(0));

  const Eigen::Matrix3d world_from_cam_r = world_from_cam.linear();
  const Vec3 light = scene.light_dir_world.normalized();
  const Vec3 fill = Vec3(-0.5, -0.7, 0.4).normalized();  // a weak second light from the other side

  // Screen-space culling: the pixel rectangle of each object's box (projected corners; the whole
  // image when a corner is behind the camera, e.g. the room around it).
  struct Candidate {
    const SceneObject* object;
    int u0, u1, v0, v1;
  };
  std::vector<Candidate> candidates;
  const Pose cam_from_world = world_from_cam.inverse();
  auto add = [&](const SceneObject& o) {
    Candidate c{&o, 0, camera.width - 1, 0, camera.height - 1};
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
      if (umax < -1.0 || vmax < -1.0 || umin > camera.width || vmin > camera.height) return;
      c.u0 = std::max(0, static_cast<int>(std::floor(umin)) - 1);
      c.u1 = std::min(camera.width - 1, static_cast<int>(std::ceil(umax)) + 1);
      c.v0 = std::max(0, static_cast<int>(std::floor(vmin)) - 1);
      c.v1 = std::min(camera.height - 1, static_cast<int>(std::ceil(vmax)) + 1);
    }
    candidates.push_back(c);
  };
  for (const auto& o : scene.structure) add(o);
  for (const auto& o : scene.objects) add(o);

  parallel_for(static_cast<std::size_t>(camera.height), threads, [&](std::size_t row) {
    const int v = static_cast<int>(row);
    auto* rgb = frame.rgb.ptr<cv::Vec3b>(v);
    auto* depth = frame.depth_m.ptr<float>(v);
    auto* label = frame.labels.ptr<std::uint16_t>(v);
    std::vector<const Candidate*> row_candidates;
    for (const auto& c : candidates)
      if (v >= c.v0 && v <= c.v1) row_candidates.push_back(&c);
    std::vector<const SceneObject*> pixel_objects;
    pixel_objects.reserve(row_candidates.size());
    for (int u = 0; u < camera.width; ++u) {
      pixel_objects.clear();
      for (const Candidate* c : row_candidates)
        if (u >= c->u0 && u <= c->u1) pixel_objects.push_back(c->object);
      // Direction with z = 1 in the camera frame: the ray parameter t is the depth z.
      const Vec3 direction_in_cam = camera.unproject(u, v, 1.0);
      Ray ray;
      ray.origin = world_from_cam.translation();
      ray.direction = world_from_cam_r * direction_in_cam;
      const SurfaceHit hit = cast_ray(pixel_objects, ray);
      if (!hit.hit()) continue;
      const Part& part = hit.object->parts[hit.part];
      const Eigen::Matrix3d& world_from_part_r = hit.object->world_from_part[hit.part].linear();
      Vec3 normal = world_from_part_r * hit.normal_in_part;
      if (normal.dot(ray.direction) > 0.0) normal = -normal;  // seen from inside (room walls)
      const double shade = scene.ambient +
                           (1.0 - scene.ambient) * std::max(0.0, normal.dot(light)) +
                           0.2 * std::max(0.0, normal.dot(fill));
      const Eigen::Vector3d colour =
          albedo(material_at(part, hit.normal_in_part), hit.point_in_part) * shade;
      auto to8 = [](double c) {
        return static_cast<std::uint8_t>(std::clamp(std::lround(c * 255.0), 0L, 255L));
      };
      rgb[u] = cv::Vec3b(to8(colour.z()), to8(colour.y()), to8(colour.x()));
      depth[u] = static_cast<float>(hit.t);
      label[u] = static_cast<std::uint16_t>(hit.object->id);
    }
  });
  return frame;
}

}  // namespace objmap::sim

#include "objmap/pose/visible.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "objmap/core/error.h"

namespace objmap::pose {

void VisibilityOptions::check() const {
  require(downsample >= 1, "VisibilityOptions.downsample", "must be >= 1");
  require(std::isfinite(point_size_m) && point_size_m > 0, "VisibilityOptions.point_size_m",
          "must be > 0");
  require(std::isfinite(depth_tolerance_m) && depth_tolerance_m >= 0,
          "VisibilityOptions.depth_tolerance_m", "must be >= 0");
  require(min_visible_points >= 1, "VisibilityOptions.min_visible_points", "must be >= 1");
}

std::vector<std::optional<Vec3>> visible_centroids(const std::vector<const PointCloud*>& models,
                                                   const Pose& world_from_cam, const Camera& camera,
                                                   const VisibilityOptions& options) {
  options.check();
  const int width = std::max(1, camera.width / options.downsample);
  const int height = std::max(1, camera.height / options.downsample);
  const double scale = 1.0 / options.downsample;
  const Pose cam_from_world = world_from_cam.inverse();
  constexpr float kFar = std::numeric_limits<float>::infinity();
  std::vector<float> zbuffer(static_cast<std::size_t>(width) * height, kFar);

  // 1. Project every model point; splat it as a square of its apparent size into the z-buffer.
  struct Projected {
    int u, v;
    float z;
    std::size_t index;  // into the model's points
  };
  std::vector<std::vector<Projected>> projected(models.size());
  for (std::size_t m = 0; m < models.size(); ++m) {
    projected[m].reserve(models[m]->size());
    for (std::size_t i = 0; i < models[m]->size(); ++i) {
      const Vec3 point_in_cam = cam_from_world * models[m]->points[i].cast<double>();
      if (point_in_cam.z() <= 0.05) continue;
      const Eigen::Vector2d pixel = camera.project(point_in_cam) * scale;
      const int u = static_cast<int>(std::floor(pixel.x()));
      const int v = static_cast<int>(std::floor(pixel.y()));
      if (u < 0 || v < 0 || u >= width || v >= height) continue;
      const float z = static_cast<float>(point_in_cam.z());
      projected[m].push_back({u, v, z, i});
      const int radius = static_cast<int>(
          std::floor(0.5 * camera.fx * scale * options.point_size_m / point_in_cam.z()));
      for (int dv = -radius; dv <= radius; ++dv)
        for (int du = -radius; du <= radius; ++du) {
          const int uu = u + du, vv = v + dv;
          if (uu < 0 || vv < 0 || uu >= width || vv >= height) continue;
          float& cell = zbuffer[static_cast<std::size_t>(vv) * width + uu];
          cell = std::min(cell, z);
        }
    }
  }
  // 2. A point is visible when it is within the tolerance of the nearest surface at its pixel.
  std::vector<std::optional<Vec3>> out(models.size());
  for (std::size_t m = 0; m < models.size(); ++m) {
    Vec3 sum = Vec3::Zero();
    int count = 0;
    for (const Projected& pr : projected[m]) {
      if (pr.z <= zbuffer[static_cast<std::size_t>(pr.v) * width + pr.u] +
                      static_cast<float>(options.depth_tolerance_m)) {
        sum += models[m]->points[pr.index].cast<double>();
        ++count;
      }
    }
    if (count >= options.min_visible_points) out[m] = sum / count;
  }
  return out;
}

}  // namespace objmap::pose

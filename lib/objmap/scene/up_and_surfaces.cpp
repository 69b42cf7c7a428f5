// The up direction and the support surfaces of one dense map in one pass (docs/benchmarks.md,
// "The scene step"): the map sampled once on the cameras' grid, its normals used by both.
#include <chrono>

#include "objmap/scene/sampled.h"

namespace objmap::scene {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

void find_up_and_surfaces(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                          const SceneOptions& options, SceneGraph& graph) {
  const UpOptions& uo = options.up;
  const SurfaceOptions& so = options.surfaces;
  auto t0 = Clock::now();
  const bool one_sample =
      so.enabled && !map_points.empty() && uo.sample_voxel_m == so.sample_voxel_m;
  if (!one_sample) {
    graph.up = estimate_up(cameras, map_points, uo);
    graph.seconds_up = seconds_since(t0);
    t0 = Clock::now();
    graph.surfaces = find_surfaces(map_points, graph.up.up, so);
    graph.seconds_surfaces = seconds_since(t0);
    return;
  }
  // The same sample and normals as estimate_up's, on the grid fixed by the cameras.
  const detail::GridFrame frame = detail::camera_frame(cameras);
  const detail::Cloud::Ptr sample = detail::sample_on_grid(map_points, so.sample_voxel_m, frame);
  const std::vector<Eigen::Vector3f> normals =
      detail::grid_normals(sample, so.sample_voxel_m, frame);
  graph.up = detail::estimate_up(cameras, sample, normals, uo);
  graph.seconds_up = seconds_since(t0);
  t0 = Clock::now();
  graph.surfaces = detail::find_surfaces(sample, normals, graph.up.up, so);
  graph.seconds_surfaces = seconds_since(t0);
}

}  // namespace objmap::scene

// The up direction and the support surfaces of one dense map in one pass (docs/benchmarks.md,
// "The scene step"): the map sampled once, the sample's normals computed beside the up's RANSAC.
#include <chrono>
#include <future>

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
  // The same sample as estimate_up's before it is thinned, and find_surfaces' (sample_on_grid).
  const detail::Cloud::Ptr sample = detail::sample_on_grid(map_points, so.sample_voxel_m);
  std::future<std::vector<Eigen::Vector3f>> normals = std::async(
      std::launch::async, [&] { return detail::grid_normals(sample, so.sample_voxel_m); });
  const bool auto_up = !parse_up(uo.mode, "--up");
  graph.up = detail::estimate_up(
      cameras,
      auto_up ? detail::thin(sample, static_cast<std::size_t>(uo.max_sample_points))
              : detail::Cloud::Ptr(new detail::Cloud),
      uo);
  graph.seconds_up = seconds_since(t0);
  t0 = Clock::now();
  graph.surfaces = detail::find_surfaces(sample, normals.get(), graph.up.up, so);
  graph.seconds_surfaces = seconds_since(t0);
}

}  // namespace objmap::scene

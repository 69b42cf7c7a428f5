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

struct SceneSample::Taken {
  std::vector<Pose> cameras;
  bool one_sample = false;
  detail::GridFrame frame;  // one_sample: the grid, and the map's sample on it
  detail::Cloud::Ptr sample;
  std::vector<Vec3f> points;  // otherwise: the map's points
  double seconds = 0.0;       // taking the sample
};

SceneSample::SceneSample(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                         const SceneOptions& options) {
  const auto t0 = Clock::now();
  auto taken = std::make_shared<Taken>();
  taken->cameras = cameras;
  const SurfaceOptions& so = options.surfaces;
  taken->one_sample =
      so.enabled && !map_points.empty() && options.up.sample_voxel_m == so.sample_voxel_m;
  if (taken->one_sample) {  // the same sample as estimate_up's, on the grid fixed by the cameras
    taken->frame = detail::camera_frame(cameras);
    taken->sample = detail::sample_on_grid(map_points, so.sample_voxel_m, taken->frame);
  } else {
    taken->points = map_points;
  }
  taken->seconds = seconds_since(t0);
  taken_ = std::move(taken);
}

void find_up_and_surfaces(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                          const SceneOptions& options, SceneGraph& graph) {
  find_up_and_surfaces(SceneSample(cameras, map_points, options), options, graph);
}

void find_up_and_surfaces(const SceneSample& sample, const SceneOptions& options,
                          SceneGraph& graph) {
  const SceneSample::Taken& taken = *sample.taken_;
  const UpOptions& uo = options.up;
  const SurfaceOptions& so = options.surfaces;
  auto t0 = Clock::now();
  if (!taken.one_sample) {
    graph.up = estimate_up(taken.cameras, taken.points, uo);
    graph.seconds_up = taken.seconds + seconds_since(t0);
    t0 = Clock::now();
    graph.surfaces = find_surfaces(taken.points, graph.up.up, so);
    graph.seconds_surfaces = seconds_since(t0);
    return;
  }
  const std::vector<Eigen::Vector3f> normals =
      detail::grid_normals(taken.sample, so.sample_voxel_m, taken.frame);
  graph.up = detail::estimate_up(taken.cameras, taken.sample, normals, uo);
  graph.seconds_up = taken.seconds + seconds_since(t0);
  t0 = Clock::now();
  graph.surfaces = detail::find_surfaces(taken.sample, normals, graph.up.up, so);
  graph.seconds_surfaces = seconds_since(t0);
}

}  // namespace objmap::scene

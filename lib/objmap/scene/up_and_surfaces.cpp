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

// The up and the surfaces share one sample of the map (the defaults).
bool one_sample(const std::vector<Vec3f>& map_points, const SceneOptions& options) {
  const SurfaceOptions& so = options.surfaces;
  return so.enabled && !map_points.empty() && options.up.sample_voxel_m == so.sample_voxel_m;
}

// Otherwise each samples the map its own way (`seconds_before`: time already spent, counted to
// the up's).
void on_points(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
               const SceneOptions& options, double seconds_before, SceneGraph& graph) {
  auto t0 = Clock::now();
  graph.up = estimate_up(cameras, map_points, options.up);
  graph.seconds_up = seconds_before + seconds_since(t0);
  t0 = Clock::now();
  graph.surfaces = find_surfaces(map_points, graph.up.up, options.surfaces);
  graph.seconds_surfaces = seconds_since(t0);
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
  taken->one_sample = one_sample(map_points, options);
  if (taken->one_sample) {  // the same sample as estimate_up's, on the grid fixed by the cameras
    taken->frame = detail::camera_frame(cameras);
    taken->sample =
        detail::sample_on_grid(map_points, options.surfaces.sample_voxel_m, taken->frame);
  } else {
    taken->points = map_points;
  }
  taken->seconds = seconds_since(t0);
  taken_ = std::move(taken);
}

void find_up_and_surfaces(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                          const SceneOptions& options, SceneGraph& graph) {
  if (!one_sample(map_points, options))  // the map read where it is, not copied into a sample
    on_points(cameras, map_points, options, 0.0, graph);
  else
    find_up_and_surfaces(SceneSample(cameras, map_points, options), options, graph);
}

void find_up_and_surfaces(const SceneSample& sample, const SceneOptions& options,
                          SceneGraph& graph) {
  const SceneSample::Taken& taken = *sample.taken_;
  if (!taken.one_sample)
    return on_points(taken.cameras, taken.points, options, taken.seconds, graph);
  const UpOptions& uo = options.up;
  const SurfaceOptions& so = options.surfaces;
  auto t0 = Clock::now();
  const std::vector<Eigen::Vector3f> normals =
      detail::grid_normals(taken.sample, so.sample_voxel_m, taken.frame);
  graph.up = detail::estimate_up(taken.cameras, taken.sample, normals, uo);
  graph.seconds_up = taken.seconds + seconds_since(t0);
  t0 = Clock::now();
  graph.surfaces = detail::find_surfaces(taken.sample, normals, graph.up.up, so);
  graph.seconds_surfaces = seconds_since(t0);
}

}  // namespace objmap::scene

// bench_scene: the parts of fuse's scene step (docs/scene.md, docs/benchmarks.md "The scene step")
// on the dense map of fr1_rpy_every4 (fused once with its ground truth at start-up): the 4 cm
// sample, its normals by objmap's grid against PCL's NormalEstimation (12 nearest by a kd-tree,
// what the grid replaced), the up from the normals and the surfaces on the sample.
//   OBJMAP_DATA=../shared/data build/bin/bench_scene
#include <benchmark/benchmark.h>
#include <pcl/features/normal_3d.h>
#include <pcl/search/kdtree.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "bench_data.h"
#include "objmap/io/ply.h"
#include "objmap/pipeline/fuse.h"
#include "objmap/scene/sampled.h"

namespace objmap::bench {
namespace {

namespace fs = std::filesystem;

struct Map {
  std::vector<Vec3f> points;
  scene::detail::Cloud::Ptr sample;
  bool ok = false;
};

// The dense map of fr1_rpy_every4 fused with its ground truth, and its sample on the 4 cm grid.
const Map& rpy_map() {
  static const Map map = [] {
    Map m;
    const fs::path dataset = data_dir() / "tum" / "fr1_rpy_every4";
    if (!fs::exists(dataset / "groundtruth.txt")) return m;
    pipeline::FuseOptions o;
    o.dataset = dataset;
    o.trajectory = dataset / "groundtruth.txt";
    o.segmentation = dataset / "detections_yolofastest";
    o.out = fs::temp_directory_path() / ("bench_scene_" + std::to_string(getpid()));
    o.scene.up.mode = "z";
    pipeline::run_fuse(o);
    m.points = io::read_ply(o.out / "map_dense.ply").points;
    fs::remove_all(o.out);
    m.sample = scene::detail::sample_on_grid(m.points, scene::SurfaceOptions{}.sample_voxel_m);
    m.ok = true;
    return m;
  }();
  return map;
}

#define NEED_MAP(state)                                             \
  const Map& map = rpy_map();                                       \
  if (!map.ok) {                                                    \
    state.SkipWithError("no tum/fr1_rpy_every4 under OBJMAP_DATA"); \
    return;                                                         \
  }

void BM_SampleOnGrid(benchmark::State& state) {
  NEED_MAP(state);
  for (auto _ : state)
    benchmark::DoNotOptimize(scene::detail::sample_on_grid(map.points, 0.04)->size());
  state.counters["sample"] = static_cast<double>(map.sample->size());
}

void BM_NormalsGrid(benchmark::State& state) {
  NEED_MAP(state);
  for (auto _ : state) benchmark::DoNotOptimize(scene::detail::grid_normals(map.sample, 0.04));
}

// PCL's normals: the plane of each point's 12 nearest sample points (a kd-tree).
void BM_NormalsPclKnn12(benchmark::State& state) {
  NEED_MAP(state);
  for (auto _ : state) {
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimate;
    estimate.setInputCloud(map.sample);
    estimate.setSearchMethod(
        pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
    estimate.setKSearch(12);
    pcl::PointCloud<pcl::Normal> normals;
    estimate.compute(normals);
    benchmark::DoNotOptimize(normals.size());
  }
}

// The up from the sample's normals (their densest direction, mean shift, the levels along it).
void BM_UpFromNormals(benchmark::State& state) {
  NEED_MAP(state);
  const scene::UpOptions o;
  const auto normals = scene::detail::grid_normals(map.sample, o.sample_voxel_m);
  for (auto _ : state)
    benchmark::DoNotOptimize(scene::detail::estimate_up({}, map.sample, normals, o).up);
}

void BM_SurfacesOnSample(benchmark::State& state) {
  NEED_MAP(state);
  const scene::SurfaceOptions o;
  const auto normals = scene::detail::grid_normals(map.sample, o.sample_voxel_m);
  for (auto _ : state)
    benchmark::DoNotOptimize(
        scene::detail::find_surfaces(map.sample, normals, Vec3::UnitZ(), o).size());
}

// The surfaces' patches: Euclidean clusters (6 cm, at least 10 points) of the sample's points, by
// objmap's grid of cells (what the scene step uses) and by PCL's EuclideanClusterExtraction with a
// kd-tree (what it replaced; the same clusters, tests/scene/clusters_test.cpp).
std::vector<Vec3f> sample_points(const Map& map) {
  std::vector<Vec3f> points;
  for (const auto& p : *map.sample) points.emplace_back(p.x, p.y, p.z);
  return points;
}

void BM_ClustersGrid(benchmark::State& state) {
  NEED_MAP(state);
  const std::vector<Vec3f> points = sample_points(map);
  std::size_t clusters = 0;
  for (auto _ : state) clusters = scene::detail::euclidean_clusters(points, 0.06, 10).size();
  state.counters["clusters"] = static_cast<double>(clusters);
}

void BM_ClustersPclKdTree(benchmark::State& state) {
  NEED_MAP(state);
  const std::vector<Vec3f> points = sample_points(map);
  std::size_t clusters = 0;
  for (auto _ : state) clusters = scene::detail::pcl_euclidean_clusters(points, 0.06, 10).size();
  state.counters["clusters"] = static_cast<double>(clusters);
}

BENCHMARK(BM_SampleOnGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NormalsGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NormalsPclKnn12)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpFromNormals)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SurfacesOnSample)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ClustersGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ClustersPclKdTree)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace objmap::bench

BENCHMARK_MAIN();

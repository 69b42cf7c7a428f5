// Hot paths of `objmap fuse` on 640×480 frames.
// Real frames come from $OBJMAP_DATA (default <repo>/../shared/data)/tum/fr1_rpy_every4; without
// them the frame benchmarks use a synthetic depth image (a tilted plane with a box).
//   build-*/bin/bench_fusion --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "bench_data.h"
#include "objmap/core/memory.h"
#include "objmap/filters/neighbour_distances.h"
#include "objmap/filters/outlier.h"
#include "objmap/fusion/frame_voxels.h"
#include "objmap/fusion/object_map.h"
#include "objmap/fusion/voxel_map.h"
#include "objmap/geometry/backproject.h"
#include "objmap/io/ply.h"
#include "objmap/io/png_fast.h"
#include "objmap/io/tum_dataset.h"
#include "objmap/segmentation/box_mask.h"
#include "objmap/segmentation/depth_gate.h"
#include "objmap/segmentation/mask_refine.h"
#include "objmap/segmentation/read.h"
#include "surface_cloud.h"

namespace fs = std::filesystem;
using namespace objmap;

namespace {

using objmap::bench::data_dir;

// The first `n` (rgb, depth) file pairs of fr1_rpy_every4 (by sorted file name), or none.
std::vector<std::pair<fs::path, fs::path>> real_frames(std::size_t n) {
  const fs::path dir = data_dir() / "tum" / "fr1_rpy_every4";
  std::vector<std::pair<fs::path, fs::path>> out;
  if (!fs::exists(dir / "rgb") || !fs::exists(dir / "depth")) return out;
  std::vector<fs::path> rgb, depth;
  for (const auto& e : fs::directory_iterator(dir / "rgb")) rgb.push_back(e.path());
  for (const auto& e : fs::directory_iterator(dir / "depth")) depth.push_back(e.path());
  std::sort(rgb.begin(), rgb.end());
  std::sort(depth.begin(), depth.end());
  for (std::size_t i = 0; i < std::min({n, rgb.size(), depth.size()}); ++i)
    out.emplace_back(rgb[i], depth[i]);
  return out;
}

struct Frame {
  cv::Mat bgr, depth;
  Pose world_from_cam = Pose::Identity();
};

// A real frame when the data is there, else a synthetic one.
const Frame& test_frame() {
  static const Frame frame = [] {
    Frame f;
    const auto files = real_frames(1);
    if (!files.empty()) {
      f.bgr = cv::imread(files[0].first.string(), cv::IMREAD_COLOR);
      f.depth = cv::imread(files[0].second.string(), cv::IMREAD_UNCHANGED);
    }
    if (f.depth.empty()) {
      f.bgr = cv::Mat(480, 640, CV_8UC3);
      f.depth = cv::Mat(480, 640, CV_16UC1);
      for (int v = 0; v < 480; ++v)
        for (int u = 0; u < 640; ++u) {
          const bool box = u > 250 && u < 400 && v > 200 && v < 330;
          f.depth.at<std::uint16_t>(v, u) =
              static_cast<std::uint16_t>(box ? 5000 : 6000 + 8 * v + (u * 7919 % 13 == 0 ? 0 : 1));
          f.bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(u % 256, v % 256, 77);
        }
    }
    f.world_from_cam.linear() =
        Eigen::AngleAxisd(0.4, Vec3(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
    f.world_from_cam.translation() = Vec3(1.3, 0.6, 1.5);
    return f;
  }();
  return frame;
}

const geometry::RayTable& rays() {
  static const geometry::RayTable table = geometry::make_ray_table(camera_preset("fr1"));
  return table;
}

// ---------------------------------------------------------------------------------------------
// Reference: decoding one frame's PNGs (what `fuse` must read anyway).

// Arg 0: OpenCV (cv::imdecode: libpng, zlib); arg 1: objmap's reader (io/png_fast.h, libdeflate),
// which `fuse` uses. The same pixels (tests/io/png_fast_test.cpp).
void BM_DecodeFramePngs(benchmark::State& state) {
  const auto files = real_frames(8);
  if (files.empty()) {
    state.SkipWithError("real data missing (OBJMAP_DATA)");
    return;
  }
  std::vector<std::vector<unsigned char>> rgb, depth;
  for (const auto& [r, d] : files) {
    std::ifstream fr(r, std::ios::binary), fd(d, std::ios::binary);
    rgb.emplace_back(std::istreambuf_iterator<char>(fr), std::istreambuf_iterator<char>());
    depth.emplace_back(std::istreambuf_iterator<char>(fd), std::istreambuf_iterator<char>());
  }
  const bool objmap_reader = state.range(0) == 1;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& r = rgb[i % rgb.size()];
    const auto& d = depth[i % depth.size()];
    cv::Mat a =
        objmap_reader ? io::decode_png_fast(r.data(), r.size()) : cv::imdecode(r, cv::IMREAD_COLOR);
    cv::Mat b = objmap_reader ? io::decode_png_fast(d.data(), d.size())
                              : cv::imdecode(d, cv::IMREAD_UNCHANGED);
    benchmark::DoNotOptimize(a.data);
    benchmark::DoNotOptimize(b.data);
    ++i;
  }
  state.SetLabel(std::string("rgb + depth PNG, 640x480, from memory, ") +
                 (objmap_reader ? "objmap (libdeflate)" : "OpenCV (libpng)"));
}
BENCHMARK(BM_DecodeFramePngs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// ---------------------------------------------------------------------------------------------
// Back-projection.

void BM_MakeRayTable(benchmark::State& state) {
  const Camera camera = camera_preset("fr1");
  for (auto _ : state) benchmark::DoNotOptimize(geometry::make_ray_table(camera).x_over_z.data());
}
BENCHMARK(BM_MakeRayTable)->Unit(benchmark::kMillisecond);

void BM_BackprojectFrame(benchmark::State& state) {
  const Frame& f = test_frame();
  geometry::BackprojectOptions options;
  options.stride = static_cast<int>(state.range(0));
  std::size_t points = 0;
  for (auto _ : state) {
    const auto r = geometry::backproject(rays(), {f.depth, f.world_from_cam, &f.bgr}, options);
    points = r.points_in_world.size();
    benchmark::DoNotOptimize(r.points_in_world.points.data());
  }
  state.counters["points"] = static_cast<double>(points);
}
BENCHMARK(BM_BackprojectFrame)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// ---------------------------------------------------------------------------------------------
// Dense voxel map: one back-projected frame inserted into a map that already holds it (steady
// state of a slowly moving camera).

void BM_VoxelMapInsertFrame(benchmark::State& state) {
  const Frame& f = test_frame();
  const auto cloud =
      geometry::backproject(rays(), {f.depth, f.world_from_cam, &f.bgr}).points_in_world;
  fusion::VoxelMap map({0.01, static_cast<int>(state.range(0))});
  map.insert(cloud);
  for (auto _ : state) map.insert(cloud);
  state.counters["points"] = static_cast<double>(cloud.size());
  state.counters["voxels"] = static_cast<double>(map.size());
  state.counters["Mpts/s"] = benchmark::Counter(
      static_cast<double>(cloud.size()) * state.iterations() / 1e6, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_VoxelMapInsertFrame)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The first n real frames, decoded (empty without the data).
std::vector<Frame> decoded_real_frames(std::size_t n) {
  std::vector<Frame> frames;
  for (const auto& [r, d] : real_frames(n))
    frames.push_back(
        {cv::imread(r.string(), cv::IMREAD_COLOR), cv::imread(d.string(), cv::IMREAD_UNCHANGED)});
  return frames;
}

// Back-projection + insertion, the whole per-frame dense-map work, on real consecutive frames
// (poses identity: the worst case for voxel reuse is a moving camera, the best a static one).
void BM_DenseMapRealFrames(benchmark::State& state) {
  const std::vector<Frame> frames = decoded_real_frames(16);
  if (frames.empty()) {
    state.SkipWithError("real data missing (OBJMAP_DATA)");
    return;
  }
  fusion::VoxelMap map({0.01, static_cast<int>(state.range(0))});
  std::size_t i = 0;
  for (auto _ : state) {
    const Frame& f = frames[i++ % frames.size()];
    const auto r = geometry::backproject(rays(), {f.depth, f.world_from_cam, &f.bgr});
    map.insert(r.points_in_world);
  }
  state.counters["voxels"] = static_cast<double>(map.size());
  state.counters["MB"] = static_cast<double>(map.memory_bytes()) / 1e6;
}
BENCHMARK(BM_DenseMapRealFrames)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same frames as fuse sums them (fusion/frame_voxels.h: back-projection and voxel sums in one
// pass over the depth image, no point cloud, no per-frame hash table), added to a 16-shard map.
void BM_FrameVoxelsRealFrames(benchmark::State& state) {
  const std::vector<Frame> frames = decoded_real_frames(16);
  if (frames.empty()) {
    state.SkipWithError("real data missing (OBJMAP_DATA)");
    return;
  }
  fusion::VoxelMap map({0.01, 1, 16});
  fusion::FrameVoxels voxels;
  std::size_t i = 0, entries = 0;
  for (auto _ : state) {
    const Frame& f = frames[i++ % frames.size()];
    fusion::frame_voxels(rays(), {f.depth, f.world_from_cam, &f.bgr}, {}, map, voxels);
    if (state.range(0) == 1) map.add(voxels);  // 0: the frame's sums only
    entries = voxels.entries();
  }
  state.counters["entries"] = static_cast<double>(entries);
  state.counters["voxels"] = static_cast<double>(map.size());
}
BENCHMARK(BM_FrameVoxelsRealFrames)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// ---------------------------------------------------------------------------------------------
// The outlier filter on 100k points (PCL's StatisticalOutlierRemoval on the same cloud:
// compare_pcl_sor.cpp).

void BM_OutlierObjmap100k(benchmark::State& state) {
  const PointCloud c = bench::surface_cloud(100000);
  filters::OutlierOptions options;
  options.threads = static_cast<int>(state.range(0));
  std::size_t kept = 0;
  for (auto _ : state) kept = filters::remove_outliers(c, options).kept.size();
  state.counters["kept"] = static_cast<double>(kept);
}
BENCHMARK(BM_OutlierObjmap100k)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The filter's k nearest (k = 20, 1 thread): the grid search against FLANN's kd-tree alone, on
// the 100k-point cloud above (Arg 0), on one object's record (Arg 1, voxel_record_cloud) and on
// the object PLYs of a fuse run, one call each (Arg 2: OBJMAP_BENCH_RECORDS=RUN/objects).
std::vector<PointCloud> neighbour_bench_clouds(std::int64_t which) {
  if (which == 0) return {bench::surface_cloud(100000)};
  if (which == 1) return {bench::voxel_record_cloud()};
  std::vector<PointCloud> clouds;
  const char* dir = std::getenv("OBJMAP_BENCH_RECORDS");
  if (!dir) return clouds;
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".ply") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) clouds.push_back(io::read_ply(f));
  return clouds;
}
template <typename Search>
void neighbour_bench(benchmark::State& state, Search&& search) {
  const std::vector<PointCloud> clouds = neighbour_bench_clouds(state.range(0));
  if (clouds.empty()) {
    state.SkipWithError("no clouds: OBJMAP_BENCH_RECORDS=RUN/objects");
    return;
  }
  std::size_t points = 0;
  for (const auto& c : clouds) points += c.size();
  for (auto _ : state)
    for (const auto& c : clouds) benchmark::DoNotOptimize(search(c));
  state.counters["points"] = static_cast<double>(points);
}
void BM_NeighbourDistancesGrid(benchmark::State& state) {
  neighbour_bench(state,
                  [](const PointCloud& c) { return filters::mean_neighbour_distances(c, 20, 1); });
}
BENCHMARK(BM_NeighbourDistancesGrid)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
void BM_NeighbourDistancesKdTree(benchmark::State& state) {
  neighbour_bench(state, [](const PointCloud& c) {
    return filters::mean_neighbour_distances_kdtree(c, 20, 1);
  });
}
BENCHMARK(BM_NeighbourDistancesKdTree)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// ---------------------------------------------------------------------------------------------
// Segmentation: masks from boxes, and reading a long box sequence.

// segmentation::mask_from_box for every detector box (detections_yolofastest) of the first 16
// frames of fr1_rpy_every4 on their depth images, as fuse makes the masks of box-only instances.
void BM_MaskFromBoxReal(benchmark::State& state) {
  struct Job {
    cv::Mat depth;
    std::vector<segmentation::Box> boxes;
  };
  static const std::vector<Job> jobs = [] {
    std::vector<Job> out;
    const fs::path dir = data_dir() / "tum" / "fr1_rpy_every4";
    if (!fs::exists(dir / "detections_yolofastest")) return out;
    const io::Dataset dataset = io::read_tum_dataset(dir);
    segmentation::ReadOptions read;
    read.image_width = 640;
    read.image_height = 480;
    const segmentation::Segmentation seg =
        segmentation::read_segmentation(dir / "detections_yolofastest", read);
    for (const auto& frame : seg.frames) {
      if (out.size() == 16) break;
      for (const auto& pair : dataset.frames) {
        if (std::abs(pair.rgb_timestamp - frame.timestamp) > 1e-3 || frame.instances.empty())
          continue;
        Job job{cv::imread(pair.depth_file.string(), cv::IMREAD_UNCHANGED), {}};
        for (const auto& instance : frame.instances) job.boxes.push_back(instance.bbox);
        out.push_back(std::move(job));
        break;
      }
    }
    return out;
  }();
  if (jobs.empty()) {
    state.SkipWithError("real data missing (OBJMAP_DATA)");
    return;
  }
  const Camera camera = camera_preset("fr1");
  std::size_t boxes = 0;
  double area = 0;
  for (const Job& job : jobs)
    for (const auto& box : job.boxes) {
      ++boxes;
      area += box.w * box.h;
    }
  for (auto _ : state)
    for (const Job& job : jobs)
      for (const auto& box : job.boxes)
        benchmark::DoNotOptimize(segmentation::mask_from_box(box, job.depth, camera, {}).pixels);
  state.counters["boxes"] = static_cast<double>(boxes);
  state.counters["px/box"] = area / static_cast<double>(boxes);
  // Milliseconds per box (Google Benchmark prints an inverted rate with an "s" after it).
  state.counters["ms/box"] =
      benchmark::Counter(static_cast<double>(boxes) * state.iterations() * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_MaskFromBoxReal)->Unit(benchmark::kMillisecond);

// The two clean-ups of a given mask on ycbv_0000_10f's label masks (30 masks, 18-22k pixels each,
// on their depth images): Arg 0 = refine_mask, Arg 1 = gate_mask_depth (the depth gate), as fuse
// applies them to every given mask.
void BM_CleanGivenMaskYcb(benchmark::State& state) {
  struct Job {
    cv::Mat depth;
    std::vector<segmentation::Mask> masks;
  };
  static const std::vector<Job> jobs = [] {
    std::vector<Job> out;
    const fs::path dir = data_dir() / "ycbv_0000_10f";
    if (!fs::exists(dir / "masks")) return out;
    const io::Dataset dataset = io::read_tum_dataset(dir);
    segmentation::ReadOptions read;
    read.image_width = 640;
    read.image_height = 480;
    const segmentation::Segmentation seg = segmentation::read_segmentation(dir / "masks", read);
    for (const auto& frame : seg.frames)
      for (const auto& pair : dataset.frames) {
        if (std::abs(pair.rgb_timestamp - frame.timestamp) > 1e-3) continue;
        Job job{cv::imread(pair.depth_file.string(), cv::IMREAD_UNCHANGED), {}};
        for (const auto& instance : frame.instances)
          if (instance.mask) job.masks.push_back(*instance.mask);
        out.push_back(std::move(job));
        break;
      }
    return out;
  }();
  if (jobs.empty()) {
    state.SkipWithError("real data missing (OBJMAP_DATA)");
    return;
  }
  Camera camera = camera_preset("fr1");
  camera.fx = 1066.778, camera.fy = 1067.487, camera.cx = 312.9869, camera.cy = 241.3109;
  camera.depth_factor = 10000.0;
  std::size_t masks = 0;
  for (const Job& job : jobs) masks += job.masks.size();
  for (auto _ : state)
    for (const Job& job : jobs)
      for (const auto& mask : job.masks) {
        const cv::Rect bounds = geometry::mask_bounds(mask);
        if (state.range(0) == 0)
          benchmark::DoNotOptimize(
              segmentation::refine_mask(mask, bounds, job.depth, camera).removed_pixels);
        else
          benchmark::DoNotOptimize(
              segmentation::gate_mask_depth(mask, bounds, job.depth, camera).removed_pixels);
      }
  state.counters["masks"] = static_cast<double>(masks);
  state.counters["ms/mask"] =
      benchmark::Counter(static_cast<double>(masks) * state.iterations() * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_CleanGivenMaskYcb)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Reading fr3_long_office_household's 2585 box files (17,225 boxes, COCO ids).
void BM_ReadBoxSegmentationFr3LongOffice(benchmark::State& state) {
  const fs::path dir =
      data_dir() / "tum" / "fr3_long_office_household_annotations" / "detections_yolo";
  if (!fs::exists(dir)) {
    state.SkipWithError("real data missing (OBJMAP_DATA)");
    return;
  }
  segmentation::ReadOptions read;
  read.image_width = 640;
  read.image_height = 480;
  std::size_t frames = 0;
  for (auto _ : state) frames = segmentation::read_segmentation(dir, read).frames.size();
  state.counters["frames"] = static_cast<double>(frames);
}
BENCHMARK(BM_ReadBoxSegmentationFr3LongOffice)->Unit(benchmark::kMillisecond);

// ---------------------------------------------------------------------------------------------
// Object map: one observation (a masked 160×120 region: ~19k points) against 20 objects.

// `count` objects of `class_name` added to `map`, each `points` moved `spacing` m further along x
// (track ids 100, 101, ...).
void add_objects(fusion::ObjectMap& map, const PointCloud& points, int count,
                 const std::string& class_name, float spacing) {
  for (int k = 0; k < count; ++k) {
    fusion::Observation o;
    o.class_name = class_name;
    o.track_id = 100 + k;
    for (const Vec3f& p : points.points)
      o.points_in_world.push_back(p + Vec3f(spacing * (k + 1), 0, 0));
    map.add_frame({o});
  }
}

void BM_ObjectMapAdd(benchmark::State& state) {
  const Frame& f = test_frame();
  segmentation::Mask mask;
  mask.width = 640;
  mask.height = 480;
  mask.data.assign(640 * 480, 0);
  for (int v = 180; v < 300; ++v)
    for (int u = 240; u < 400; ++u) mask.data[v * 640 + u] = 1;
  const auto points =
      geometry::backproject(rays(), {f.depth, f.world_from_cam, &f.bgr, &mask}).points_in_world;
  fusion::ObjectMap map;
  add_objects(map, points, 20, "book", 0.3f);  // 20 other objects, 30 cm apart
  fusion::Observation o;
  o.class_name = "cup";
  o.track_id = 1;
  o.points_in_world = points;
  for (auto _ : state) benchmark::DoNotOptimize(map.add_frame({o}).front().object_id);
  state.counters["points"] = static_cast<double>(points.size());
}
BENCHMARK(BM_ObjectMapAdd)->Unit(benchmark::kMillisecond);

// The copy of the object map objmap follow makes at every publish (its finish works on the copy
// while the keyframes go on): 8 objects of a whole frame's points each (~90k voxels, slot tables
// of several MB), copied and freed, with the allocator set as objmap's main sets it. The copy
// shares the objects' voxels (copy on write): BM_ObjectMapCopyThenSeeOne is what it costs later.
void BM_ObjectMapCopy(benchmark::State& state) {
  keep_freed_memory();
  const Frame& f = test_frame();
  const auto points =
      geometry::backproject(rays(), {f.depth, f.world_from_cam, &f.bgr}).points_in_world;
  fusion::ObjectMap map;
  add_objects(map, points, 8, "table", 5.0f);  // 8 objects, 5 m apart
  for (auto _ : state) {
    fusion::ObjectMap copy(map);
    benchmark::DoNotOptimize(copy.size());
  }
  state.counters["objects"] = static_cast<double>(map.size());
}
BENCHMARK(BM_ObjectMapCopy)->Unit(benchmark::kMillisecond)->UseRealTime();

// The copy, then the next keyframe's observation of one of its objects on the live map (a whole
// frame's points, as the objects are made): that object's voxels are copied then, as the copy
// still holds them; against BM_ObjectMapSeeOne, the same observation without a copy.
void object_map_see_one(benchmark::State& state, bool copy_first) {
  keep_freed_memory();
  const Frame& f = test_frame();
  const auto points =
      geometry::backproject(rays(), {f.depth, f.world_from_cam, &f.bgr}).points_in_world;
  fusion::ObjectMap map;
  add_objects(map, points, 8, "table", 5.0f);
  fusion::Observation o;
  o.class_name = "table";
  o.track_id = 100;
  for (const Vec3f& p : points.points) o.points_in_world.push_back(p + Vec3f(5.0f, 0, 0));
  for (auto _ : state) {
    std::optional<fusion::ObjectMap> copy;
    if (copy_first) copy.emplace(map);
    o.timestamp += 1.0;  // a keyframe of its own
    const fusion::AddResult added = map.add_frame({o}).front();
    if (added.object_id != 0) state.SkipWithError("the observation did not join object 0");
  }
  state.counters["objects"] = static_cast<double>(map.size());
}
void BM_ObjectMapCopyThenSeeOne(benchmark::State& state) { object_map_see_one(state, true); }
void BM_ObjectMapSeeOne(benchmark::State& state) { object_map_see_one(state, false); }
BENCHMARK(BM_ObjectMapCopyThenSeeOne)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ObjectMapSeeOne)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

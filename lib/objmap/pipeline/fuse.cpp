#include "objmap/pipeline/fuse.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <future>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <thread>

#include "objmap/core/error.h"
#include "objmap/core/parallel.h"
#include "objmap/core/version.h"
#include "objmap/fusion/frame_voxels.h"
#include "objmap/fusion/movers.h"
#include "objmap/fusion/palette.h"
#include "objmap/fusion/voxel_map.h"
#include "objmap/io/atomic.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/image.h"
#include "objmap/io/ply.h"
#include "objmap/io/trajectory.h"
#include "objmap/io/tum_dataset.h"
#include "objmap/pipeline/fuse_scene.h"
#include "objmap/segmentation/class_sizes.h"
#include "objmap/segmentation/instance_masks.h"
#include "objmap/segmentation/read.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

namespace {

// The dataset's own poses, written into the run folder when no --trajectory is given.
const char* const kDatasetTrajectory = "dataset_trajectory.txt";

using Clock = std::chrono::steady_clock;

// The worker threads of `requested` (0: the cores, at most 8: the objects are associated on one
// thread, ~15% of the work, so more workers would add memory, not speed).
int fuse_threads(int requested) {
  return requested > 0 ? requested : std::min(8, resolve_threads(0));
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

long peak_rss_kb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

// FNV-1a 64 of a file's bytes, as 16 hex digits (input provenance in run.json).
std::uint64_t fnv1a(const std::string& bytes, std::uint64_t h = 1469598103934665603ULL) {
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}
std::string read_all(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
std::string hex64(std::uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}
std::string file_checksum(const fs::path& file) { return hex64(fnv1a(read_all(file))); }
// Over the sorted relative names and contents of every file of a folder.
std::string folder_checksum(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::uint64_t h = 1469598103934665603ULL;
  for (const auto& f : files) {
    h = fnv1a(fs::relative(f, dir).generic_string(), h);
    h = fnv1a(read_all(f), h);
  }
  return hex64(h);
}

// A file-name-safe class name: "teddy bear" -> "teddy_bear".
std::string file_safe(const std::string& name) {
  std::string s;
  for (char c : name) s += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return s.empty() ? "object" : s;
}

// Where the instances of a keyframe come from: one canonical JSON file per frame (read lazily), or
// a segmentation read whole (box files, PNG images, the paper's txt layout).
struct SegmentationSource {
  std::vector<std::pair<double, fs::path>> files;  // canonical JSON: (timestamp, file), sorted
  segmentation::Segmentation whole;                // the other formats
  std::vector<double> stamps;                      // frame timestamps, sorted
};

// Hash shards of the dense map. The workers merge their keyframe's voxels into the dense map shard
// by shard, each shard strictly in keyframe order, so two workers merge different shards at once
// and every voxel sums its frames in the same order whatever the thread count.
constexpr int kDenseShards = 16;

// Who may merge into which shard of the dense map: shard s takes keyframe next[s] only.
class ShardedMergeOrder {
 public:
  explicit ShardedMergeOrder(std::size_t shards) : next_(shards, 0) {}

  // Merges keyframe `index` into every shard with merge(shard), in any order of the shards, each
  // shard once every earlier keyframe has been merged into it. Returns false (nothing more merged)
  // when the run failed.
  template <typename F>
  bool merge_in_order(std::size_t index, F&& merge) {
    const std::size_t n = next_.size();
    std::vector<bool> done(n, false);
    std::size_t left = n;
    std::unique_lock<std::mutex> lock(mutex_);
    while (left > 0) {
      std::size_t ready = n;
      for (std::size_t k = 0; k < n && ready == n && index < hold_; ++k) {
        const std::size_t s = (index * 5 + k) % n;  // neighbouring frames start on other shards
        if (!done[s] && next_[s] == index) ready = s;
      }
      if (failed_) return false;
      if (ready == n) {
        cv_.wait(lock);
        continue;
      }
      lock.unlock();
      try {
        merge(ready);
      } catch (...) {
        fail();
        throw;
      }
      lock.lock();
      done[ready] = true;
      --left;
      ++next_[ready];
      cv_.notify_all();
    }
    return true;
  }
  // Keyframes from `index` on wait (before their first shard) until hold(index') with a later
  // index' — the map is pruned between two keyframes — or fail().
  void hold(std::size_t index) {
    std::lock_guard<std::mutex> lock(mutex_);
    hold_ = index;
    cv_.notify_all();
  }
  // Releases every waiting worker (a keyframe failed; the run is abandoned).
  void fail() {
    std::lock_guard<std::mutex> lock(mutex_);
    failed_ = true;
    cv_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<std::size_t> next_;
  std::size_t hold_ = ~std::size_t{0};
  bool failed_ = false;
};

// Per-frame voxel sums for reuse: their buffers stay allocated from one keyframe to the next (no
// fresh, page-faulting megabytes per keyframe). At most one per worker in flight.
class FrameVoxelsPool {
 public:
  std::unique_ptr<fusion::FrameVoxels> take() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (free_.empty()) return std::make_unique<fusion::FrameVoxels>();
    auto frame = std::move(free_.back());
    free_.pop_back();
    return frame;
  }
  void give_back(std::unique_ptr<fusion::FrameVoxels> frame) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(frame));
  }

 private:
  std::mutex mutex_;
  std::vector<std::unique_ptr<fusion::FrameVoxels>> free_;
};

// What a worker hands back for one keyframe (its dense voxels are already in the dense map).
struct FrameWork {
  std::vector<fusion::Observation> observations;
  PointCloud scene_points;  // the scene model's rays (voxel means), with --mesh scene|all
  std::vector<PointCloud> model_points;  // per observation, its object model's (--mesh objects)
  cv::Mat depth;       // the raw depth image, for the dense map's pruning (fusion/dense_prune.h)
  cv::Mat view_depth;  // its thinned copy for the view log (fusion/visibility.h)
  std::uint64_t dense_points = 0;
  segmentation::InstanceMaskCounts masks;  // what the mask cleaning did to the instances
  std::size_t without_points = 0;          // kept instances with too few points in depth range
};

// The mask cleaning's options (segmentation/instance_masks.h) from the fuse's: the given masks'
// clean-ups take the fuse's depth range.
segmentation::InstanceMaskOptions instance_mask_options(const FuseOptions& options) {
  segmentation::InstanceMaskOptions o;
  o.min_score = options.min_instance_score;
  o.duplicate_overlap = options.duplicate_overlap;
  o.box = options.box_mask;
  o.refine = options.mask_refine;
  o.refine.min_depth_m = options.depth.min_depth_m;
  o.refine.max_depth_m = options.depth.max_depth_m;
  o.gate = options.depth_gate;
  o.gate.min_depth_m = options.depth.min_depth_m;
  o.gate.max_depth_m = options.depth.max_depth_m;
  return o;
}

// Back-projects one keyframe: the dense points summed by voxel (frame_voxels.h, so that voxels are
// merged, not pixels) and added to `dense` in keyframe order, and each instance's pixels
// into an observation. Without `dense` (and `order`, `pool`), the observations only.
FrameWork process_keyframe(const FuseOptions& options, const Camera& camera,
                           const geometry::RayTable& rays, const io::Dataset& dataset,
                           const io::FramePair& frame, const Keyframe& keyframe, int keyframe_index,
                           const segmentation::FrameSegmentation* seg, fusion::VoxelMap* dense,
                           ShardedMergeOrder* order, FrameVoxelsPool* pool) {
  FrameWork work;

  // 1. The images (checked: size, type).
  const cv::Mat bgr = io::read_frame_rgb(dataset, frame, camera.width, camera.height);
  const cv::Mat depth = io::read_frame_depth(dataset, frame, camera);
  if (dense && options.dense_prune.every_keyframes > 0) work.depth = depth;
  if (order && options.objects.min_detected_share > 0.0)
    work.view_depth = fusion::ViewLog(camera).thin(depth);

  // 2. Dense map: every valid pixel (eqs 11-15) with its colour.
  geometry::BackprojectOptions dense_options = options.depth;
  dense_options.stride = options.dense_stride;
  const geometry::DepthFrame dense_frame(depth, keyframe.world_from_cam, &bgr);
  if (dense) {
    std::unique_ptr<fusion::FrameVoxels> frame_voxels = pool->take();
    fusion::frame_voxels(rays, dense_frame, dense_options, *dense, *frame_voxels);
    work.dense_points = frame_voxels->points();
    order->merge_in_order(static_cast<std::size_t>(keyframe_index),
                          [&](std::size_t shard) { dense->add_shard(*frame_voxels, shard); });
    pool->give_back(std::move(frame_voxels));
  }

  // 2b. The scene model's rays: every valid pixel, averaged per scene-model voxel (in a fuse,
  //     which passes `order`; not for re-made observations).
  if (order && mesh::parse_mesh_selection(options.mesh.select, "mesh.select").scene)
    work.scene_points =
        mesh::voxel_means(geometry::backproject(rays, dense_frame, dense_options).points_in_world,
                          options.mesh.scene_voxel_m);

  // 3. Instances: the mask (given, or from the box and the depth), its pixels in the world.
  if (!seg) return work;
  // 3a. Each instance's cleaned mask and its bounds; one instance per object and keyframe (a
  //     second box of the same object is dropped).
  const std::vector<segmentation::InstanceMask> masks = segmentation::clean_instance_masks(
      *seg, depth, camera, instance_mask_options(options), work.masks);
  // 3b. The kept instances' pixels in the world, in the segmentation's order.
  for (const segmentation::InstanceMask& m : masks) {
    const geometry::DepthFrame instance_frame(depth, keyframe.world_from_cam, &bgr, &m.mask(),
                                              m.bounds);
    if (instance_frame.roi.empty()) {
      ++work.without_points;
      continue;
    }
    auto points = geometry::backproject(rays, instance_frame, options.depth);
    if (points.points_in_world.size() < static_cast<std::size_t>(options.objects.min_points)) {
      ++work.without_points;
      continue;
    }
    fusion::Observation obs;
    obs.timestamp = keyframe.timestamp;
    obs.track_id = m.instance->track_id;
    obs.class_name = m.instance->class_name;
    obs.score = m.instance->score;
    obs.points_in_world = std::move(points.points_in_world);
    obs.keyframe_index = keyframe_index;
    obs.centroid_in_cam = points.centroid_in_cam;
    obs.world_from_cam = keyframe.world_from_cam;
    if (order && mesh::parse_mesh_selection(options.mesh.select, "mesh.select").objects)
      work.model_points.push_back(model_points(obs, options.mesh));
    work.observations.push_back(std::move(obs));
  }
  return work;
}

// The dense map as a cloud (map_dense.ply): one point per voxel at its mean position with its mean
// colour, sorted by voxel key, and the keys (for the semantic colours). Frees the map.
struct DenseCloud {
  PointCloud cloud;
  std::vector<fusion::VoxelKey> keys;
};
DenseCloud take_dense_cloud(fusion::VoxelMap& dense, const fusion::VoxelMapOptions& options) {
  DenseCloud out;
  fusion::VoxelMap::VoxelPoints voxels = dense.take_sorted_points();  // frees the map
  dense = fusion::VoxelMap(options);
  const std::size_t n = voxels.size();
  out.cloud.points.resize(n);
  out.cloud.colors.resize(n);
  out.keys.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.cloud.points[i] = voxels[i].point;
    out.cloud.colors[i] = voxels[i].color();
    out.keys[i] = voxels[i].key;
  }
  return out;
}

// The semantic colours of the dense points (map_semantic.ply), as fusion::make_semantic_maps: a
// voxel holding a point of a confirmed object takes that object's class colour (its owner in
// fusion::voxel_owners), the others keep their mean colour.
std::vector<Rgb> semantic_colors(const DenseCloud& dense, double voxel_m,
                                 const std::vector<fusion::ObjectRecord>& records,
                                 const std::vector<Rgb>& record_color) {
  const geometry::VoxelHashTable<std::uint32_t> owner = fusion::voxel_owners(records, voxel_m);
  // The owned voxels (tens of thousands) are looked up in the dense keys (sorted, unique), rather
  // than each of the millions of dense voxels in `owner`.
  std::vector<Rgb> colors = dense.cloud.colors;
  owner.for_each([&](fusion::VoxelKey key, std::uint32_t slot) {
    const auto it = std::lower_bound(dense.keys.begin(), dense.keys.end(), key);
    if (it != dense.keys.end() && *it == key)
      colors[static_cast<std::size_t>(it - dense.keys.begin())] = record_color[slot - 1];
  });
  return colors;
}

// Leaves out of the dense map (and so of the semantic map) the voxels that hold a point of a
// sighting and of no map object: what moved is not the map. Its voxels of the keyframes where it
// was not detected stay. Returns the voxels left out.
std::size_t drop_sighting_voxels(DenseCloud& dense,
                                 const std::vector<fusion::ObjectRecord>& sightings,
                                 const std::vector<fusion::ObjectRecord>& objects, double voxel_m) {
  if (sightings.empty() || dense.keys.empty()) return 0;
  const geometry::VoxelHashTable<std::uint32_t> moving = fusion::voxel_owners(sightings, voxel_m);
  const geometry::VoxelHashTable<std::uint32_t> staying = fusion::voxel_owners(objects, voxel_m);
  std::vector<char> drop(dense.keys.size(), 0);
  moving.for_each([&](fusion::VoxelKey key, std::uint32_t) {
    if (staying.contains(key)) return;
    const auto it = std::lower_bound(dense.keys.begin(), dense.keys.end(), key);
    if (it != dense.keys.end() && *it == key)
      drop[static_cast<std::size_t>(it - dense.keys.begin())] = 1;
  });
  std::size_t kept = 0;
  for (std::size_t i = 0; i < dense.keys.size(); ++i) {
    if (drop[i]) continue;
    dense.cloud.points[kept] = dense.cloud.points[i];
    dense.cloud.colors[kept] = dense.cloud.colors[i];
    dense.keys[kept] = dense.keys[i];
    ++kept;
  }
  const std::size_t dropped = dense.keys.size() - kept;
  dense.cloud.points.resize(kept);
  dense.cloud.colors.resize(kept);
  dense.keys.resize(kept);
  return dropped;
}

ordered_json vec_json(const Vec3& v) { return ordered_json::array({v.x(), v.y(), v.z()}); }

ordered_json object_json(const fusion::ObjectRecord& r, const std::string& ply_name) {
  ordered_json o;
  o["id"] = r.id;
  o["class"] = r.class_name;
  ordered_json hist = ordered_json::object();
  for (const auto& [name, vote] : r.class_histogram)
    hist[name] = {{"count", vote.count}, {"score_sum", vote.score_sum}};
  o["class_histogram"] = hist;
  o["score"] = r.mean_score;
  o["centroid"] = vec_json(r.centroid);
  o["position"] = vec_json(r.position);
  o["aabb"] = {{"min", vec_json(r.aabb.min)}, {"max", vec_json(r.aabb.max)}};
  ordered_json rot = ordered_json::array();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rot.push_back(r.obb.rotation(i, j));
  o["obb"] = {{"center", vec_json(r.obb.center)},
              {"rotation", rot},
              {"half_extent", vec_json(r.obb.half_extent)}};
  o["points"] = {
      {"raw", r.points_raw},
      {"voxel_filtered", r.points_voxel},
      {"outlier_filtered", r.points_filtered},
      {"support_strip", r.points_support},
      {"outlier_threshold", std::isfinite(r.outlier_threshold) ? ordered_json(r.outlier_threshold)
                                                               : ordered_json(nullptr)}};
  o["observation_count"] = r.observations;
  o["view_count"] = r.views;
  o["frames_detected"] = r.frames_detected;
  o["frames_in_view"] =
      r.frames_in_view >= 0 ? ordered_json(r.frames_in_view) : ordered_json(nullptr);
  o["first_seen"] = r.first_seen;
  o["last_seen"] = r.last_seen;
  o["track_ids"] = r.track_ids;
  o["ply"] = ply_name;
  ordered_json obs = ordered_json::array();
  for (const auto& l : r.provenance) {
    ordered_json e;
    e["timestamp"] = l.timestamp;
    e["track_id"] = l.track_id ? ordered_json(*l.track_id) : ordered_json(nullptr);
    e["class"] = l.class_name;
    e["score"] = l.score;
    e["keyframe"] = l.keyframe_index ? ordered_json(*l.keyframe_index) : ordered_json(nullptr);
    e["points"] = l.points;
    e["centroid"] = vec_json(l.centroid_in_world);
    e["centroid_in_cam"] = l.centroid_in_cam ? vec_json(*l.centroid_in_cam) : ordered_json(nullptr);
    e["why"] = l.created ? "new" : "match";
    e["p_id"] = l.p_id;
    e["distance_m"] = l.distance_m;
    e["overlap"] = l.overlap;
    e["p"] = l.score_p;
    obs.push_back(e);
  }
  o["observations"] = obs;
  ordered_json merges = ordered_json::array();
  for (const auto& mlink : r.merges)
    merges.push_back({{"absorbed", mlink.absorbed},
                      {"p_id", mlink.p_id},
                      {"distance_m", mlink.distance_m},
                      {"overlap", mlink.overlap},
                      {"p", mlink.score_p},
                      {"rule", mlink.part              ? "parts of one instance"
                               : mlink.fragment        ? "fragment in box"
                               : mlink.class_confusion ? "class confusion"
                                                       : "same class"}});
  o["merged"] = merges;
  return o;
}

// run.json "duplicates": the suspected duplicates and why the merge pass kept each pair apart.
ordered_json duplicates_json(const fusion::DuplicateReport& report,
                             const fusion::DuplicateOptions& options,
                             const fusion::ObjectMapOptions& map_options) {
  ordered_json pairs = ordered_json::array();
  for (const fusion::DuplicatePair& p : report.pairs) {
    const fusion::MergeVerdict& v = p.merge;
    pairs.push_back({{"a", p.a},
                     {"b", p.b},
                     {"class", p.class_name},
                     {"obb_overlap", p.obb_overlap},
                     {"surface_distance_m", p.surface_distance_m},
                     {"touching_share", p.touching_share},
                     {"merge",
                      {{"p_id", v.p_id},
                       {"distance_m", v.distance_m},
                       {"overlap", v.overlap},
                       {"score_p", v.score_p},
                       {"shared_frames", v.shared_frames},
                       {"smaller_frames", v.smaller_frames}}},
                     {"merge_refused", fusion::to_string(v.refused)},
                     {"merge_reason", fusion::describe_refusal(v, map_options)}});
  }
  return {{"touch_distance_m", options.touch_distance_m},
          {"obb_samples_per_axis", options.obb_samples_per_axis},
          {"min_obb_overlap", options.min_obb_overlap},
          {"pairs_checked", report.pairs_checked},
          {"count", report.pairs.size()},
          {"pairs", pairs}};
}

}  // namespace

// What a fuse reads before the keyframes: the TUM folder, the camera, the trajectory, the
// segmentation, and the keyframes with their segmentation frames.
struct FuseInputs {
  io::Dataset dataset;
  Trajectory trajectory;
  segmentation::ReadOptions read;
  SegmentationSource seg_source;
  std::vector<std::ptrdiff_t> seg_of;  // each keyframe's segmentation frame, -1: none
  std::size_t with_seg = 0;            // keyframes with a segmentation frame
};

// Steps 1-2 of a fuse; fills the inputs' part of `result` (camera, frames, keyframes, times).
FuseInputs load_inputs(const FuseOptions& options, FuseResult& result) {
  FuseInputs in;
  // 1. Inputs: the TUM folder, the camera, the trajectory, the segmentation.
  auto t0 = Clock::now();
  in.dataset =
      io::read_dataset(options.dataset, {options.layout, options.max_diff_s, 30.0, options.topics});
  const io::Dataset& dataset = in.dataset;
  result.frames = dataset.frames.size();
  result.layout = dataset.layout;
  const io::CameraChoice choice = io::choose_camera(dataset, options.camera);
  result.camera = choice.camera;
  result.camera_reason = choice.reason;
  const Camera& camera = result.camera;
  if (options.trajectory.empty()) {
    // The recording's own poses (7-Scenes, ScanNet, Replica, Open3D, generic).
    require(!dataset.poses.empty(), "--trajectory",
            "missing, and the " + dataset.layout + " recording " + options.dataset.string() +
                " carries no camera poses; expected a TUM trajectory of a SLAM run");
    in.trajectory = dataset.poses;
    result.trajectory_source = "the dataset's own poses (" + dataset.poses.source + ")";
  } else {
    in.trajectory = io::read_trajectory(options.trajectory);
    result.trajectory_source = options.trajectory.string();
  }
  result.warnings.insert(result.warnings.end(), in.trajectory.warnings.begin(),
                         in.trajectory.warnings.end());
  const Trajectory& trajectory = in.trajectory;
  segmentation::ReadOptions& read = in.read;
  read.format = options.seg_format;
  read.image_width = camera.width;
  read.image_height = camera.height;
  read.default_class = options.default_class;
  read.check();
  // Canonical JSON frames carry full-image masks: they are read by the workers, one keyframe at a
  // time, so memory does not grow with the length of the sequence. Other formats are read whole.
  result.seg_format = options.seg_format == "auto"
                          ? segmentation::detect_format(options.segmentation)
                          : options.seg_format;
  SegmentationSource& seg_source = in.seg_source;
  if (result.seg_format == "json") {
    for (const auto& entry : fs::directory_iterator(options.segmentation)) {
      const fs::path& file = entry.path();
      double t = 0;
      if (entry.is_regular_file() && file.extension() == ".json" &&
          segmentation::parse_timestamp(file.stem().string(), t))
        seg_source.files.emplace_back(t, file);
    }
    std::sort(seg_source.files.begin(), seg_source.files.end());
    for (const auto& [t, file] : seg_source.files) seg_source.stamps.push_back(t);
  } else {
    read.format = result.seg_format;
    seg_source.whole = segmentation::read_segmentation(options.segmentation, read);
    for (const auto& frame : seg_source.whole.frames) seg_source.stamps.push_back(frame.timestamp);
  }
  require(!seg_source.stamps.empty(), options.segmentation.string(),
          "no segmentation frame; expected one file per rgb frame");
  result.times.push_back({"read inputs", seconds_since(t0)});

  // 2. Keyframes: the frames that have a pose (thinned by motion for a per-frame trajectory).
  t0 = Clock::now();
  KeyframeOptions kf = options.keyframes;
  kf.max_diff_s = options.max_diff_s;
  kf.min_keyframes = static_cast<std::size_t>(std::max(1, options.objects.min_observations));
  result.keyframes = select_keyframes(dataset, trajectory, kf);
  const auto& keyframes = result.keyframes.keyframes;

  // Each keyframe's segmentation frame: the one named by its rgb timestamp (within 1 ms).
  std::vector<std::ptrdiff_t>& seg_of = in.seg_of;
  seg_of.assign(keyframes.size(), -1);
  std::size_t& with_seg = in.with_seg;
  {
    std::size_t j = 0;
    const auto& stamps = seg_source.stamps;
    for (std::size_t i = 0; i < keyframes.size(); ++i) {
      const double t = keyframes[i].timestamp;
      while (j < stamps.size() && stamps[j] < t - 1e-3) ++j;
      if (j < stamps.size() && std::abs(stamps[j] - t) <= 1e-3) {
        seg_of[i] = static_cast<std::ptrdiff_t>(j);
        ++with_seg;
      }
    }
  }
  require(
      with_seg > 0, options.segmentation.string(),
      "no segmentation frame has the timestamp of one of the " + std::to_string(keyframes.size()) +
          " keyframes; expected files named by the rgb timestamps of " + options.dataset.string());
  result.times.push_back({"select keyframes", seconds_since(t0)});
  return in;
}

// Keyframe i's instances: read now (canonical JSON, into `lazy`) or taken from the whole
// segmentation; nullptr when the keyframe has no segmentation frame.
const segmentation::FrameSegmentation* keyframe_segmentation(
    const FuseInputs& in, std::size_t i, segmentation::FrameSegmentation& lazy) {
  if (in.seg_of[i] < 0) return nullptr;
  if (in.seg_source.files.empty()) return &in.seg_source.whole.frames[in.seg_of[i]];
  lazy = segmentation::read_frame_json(in.seg_source.files[in.seg_of[i]].second, in.read);
  return &lazy;
}

namespace {

// The dense map's options: voxels come from the workers via merge_shard; threads for the sort on
// export.
fusion::VoxelMapOptions dense_map_options(const FuseOptions& options, int threads) {
  fusion::VoxelMapOptions dense_options;
  dense_options.voxel_m = options.map_voxel_m;
  dense_options.threads = threads;  // for sorting on export; voxels come via merge_shard
  dense_options.shards = kDenseShards;
  return dense_options;
}

// The object map's options: a camera that hardly moves has one viewpoint, its frames are the views.
fusion::ObjectMapOptions object_map_options(const FuseOptions& options, bool still_camera) {
  fusion::ObjectMapOptions object_options = options.objects;
  object_options.overlap_measure =
      fusion::parse_overlap_measure(options.overlap_measure, "objects.overlap_measure");
  object_options.distance_score =
      fusion::parse_distance_score(options.distance_score, "objects.distance_score");
  object_options.confirmation =
      fusion::parse_confirmation(options.confirmation, "objects.confirmation");
  object_options.keep_points = options.outlier_on_points || options.voxel_nearest_centre;
  if (still_camera) {
    // A camera that hardly moves has one viewpoint: its frames are the views.
    object_options.view_min_translation_m = 0.0;
    object_options.view_min_rotation_deg = 0.0;
  }
  return object_options;
}

// A keyframe's counts into the run's.
void add_counts(const FrameWork& work, FuseResult& result) {
  result.dense_points_raw += work.dense_points;
  const segmentation::InstanceMaskCounts& m = work.masks;
  result.instances_seen += m.instances;
  result.instances_skipped_score += m.below_score;
  result.instances_from_box += m.from_box;
  result.instances_refined += m.refined;
  result.instances_duplicate += m.duplicates;
  result.mask_pixels_removed += m.refine_pixels_removed;
  result.instances_depth_gated += m.depth_gated;
  result.depth_gate_pixels_removed += m.gate_pixels_removed;
  result.instances_empty += m.empty + work.without_points;
}

// Step 3: back-project and fuse, keyframe by keyframe. Workers decode and back-project ahead (one
// keyframe more than threads in flight); this thread merges their results strictly in keyframe
// order, so the maps do not depend on the thread count. Without `dense`, the observations only.
// After every options.dense_prune.every_keyframes keyframes the dense map's noise is pruned, the
// next keyframes held back from the map meanwhile: always between the same two keyframes.
// The observations that joined objects go to `views` and each keyframe's depth to `scene`, when
// given, for the meshes; each keyframe's thinned depth to `view_log`, when given.
void fuse_keyframes(const FuseOptions& options, const FuseProgress& progress,
                    const FuseInputs& inputs, fusion::VoxelMap* dense, fusion::ObjectMap& objects,
                    ObjectViews* object_views, mesh::TsdfModel* scene, fusion::ViewLog* view_log,
                    FuseResult& result) {
  const Camera& camera = result.camera;
  const auto& keyframes = result.keyframes.keyframes;
  const geometry::RayTable rays = geometry::make_ray_table(camera, result.threads);
  ShardedMergeOrder merge_order(kDenseShards);
  FrameVoxelsPool frame_voxels;
  const std::size_t window = static_cast<std::size_t>(result.threads);
  const std::size_t prune_every =
      dense ? static_cast<std::size_t>(options.dense_prune.every_keyframes) : 0;
  fusion::RecentViews views(camera, prune_every);
  if (prune_every > 0) {
    dense->remember_new_voxels(options.dense_prune.rejudge);
    merge_order.hold(prune_every);
  }
  std::deque<std::future<FrameWork>> pending;
  std::size_t next = 0;
  auto launch = [&](std::size_t i) {
    return std::async(std::launch::async, [&, i] {
      try {
        // The keyframe's instances: read now (canonical JSON) or taken from the whole
        // segmentation.
        segmentation::FrameSegmentation lazy;
        const segmentation::FrameSegmentation* seg_frame = keyframe_segmentation(inputs, i, lazy);
        return process_keyframe(options, camera, rays, inputs.dataset,
                                inputs.dataset.frames[keyframes[i].frame], keyframes[i],
                                static_cast<int>(i), seg_frame, dense, &merge_order, &frame_voxels);
      } catch (...) {
        merge_order.fail();  // later keyframes must not wait for this one's merge
        throw;
      }
    });
  };
  auto drain = [&] {
    for (auto& f : pending)
      if (f.valid()) f.wait();
  };
  try {
    for (std::size_t done = 0; done < keyframes.size(); ++done) {
      while (next < keyframes.size() && pending.size() < window + 1)
        pending.push_back(launch(next++));
      FrameWork work = pending.front().get();
      pending.pop_front();
      if (prune_every > 0) {
        views.add(work.depth, keyframes[done].world_from_cam);
        work.depth.release();
        if ((done + 1) % prune_every == 0) {  // keyframes 0..done are in the map, done + 1 waits
          dense->prune_remembered([&](const std::vector<fusion::VoxelKey>& keys,
                                      const std::vector<const fusion::VoxelData*>& voxels,
                                      std::vector<std::uint8_t>& noise) {
            std::vector<Vec3> points(keys.size());
            std::vector<std::uint32_t> counts(keys.size());
            for (std::size_t i = 0; i < keys.size(); ++i) {
              points[i] = dense->mean_position(keys[i], *voxels[i]);
              counts[i] = voxels[i]->count;
            }
            if (options.dense_prune.peak_ratio > 0)
              views.judge_peaks(points, counts, *dense, options.dense_prune, noise);
            else
              views.judge(points, dense->voxel_m(), options.dense_prune, noise);
          });
          merge_order.hold(done + 1 + prune_every);
        }
      }
      add_counts(work, result);
      if (view_log && !work.view_depth.empty())
        view_log->add(keyframes[done].timestamp, std::move(work.view_depth),
                      keyframes[done].world_from_cam);
      // The keyframe's observations are associated together, best match first.
      const std::vector<fusion::AddResult> added = objects.add_frame(work.observations);
      for (std::size_t k = 0; k < added.size(); ++k) {
        if (added[k].object_id < 0) {
          ++(added[k].bleed      ? result.instances_bleed
             : added[k].spanning ? result.instances_spanning
                                 : result.instances_empty);
          continue;
        }
        ++result.observations;
        if (object_views)
          object_views->add(added[k].object_id, keyframes[done].timestamp,
                            keyframes[done].world_from_cam.translation(),
                            std::move(work.model_points[k]));
      }
      if (scene) scene->add({keyframes[done].world_from_cam.translation(), &work.scene_points});
      if (progress) progress(done + 1, keyframes.size());
    }
  } catch (...) {
    merge_order.fail();  // no worker may wait for a keyframe this thread will not release
    drain();
    throw;
  }
  if (dense) result.dense_voxels_pruned = dense->voxels_pruned();
}

// How each confirmed object's record is made: filters and position.
fusion::RecordOptions record_options(const FuseOptions& options, int threads) {
  fusion::RecordOptions r;
  r.confirmed_only = true;
  r.outlier_filter = options.outlier_filter;
  r.outlier = options.outlier;
  r.outlier.threads = threads;
  r.min_voxel_support = options.min_voxel_support;
  r.outlier_on_points = options.outlier_on_points;
  r.voxel_nearest_centre = options.voxel_nearest_centre;
  r.position_is_centroid = options.position_is_centroid;
  r.position_without_support = options.position_without_support;
  r.support_strip = options.support_strip;
  return r;
}

// The point counts of the records (Table 6).
void count_points(FuseResult& result) {
  result.object_points_raw = result.object_points_voxel = result.object_points_filtered = 0;
  for (const auto& r : result.objects) {
    result.object_points_raw += r.points_raw;
    result.object_points_voxel += r.points_voxel;
    result.object_points_filtered += r.points_filtered;
  }
}

// Each confirmed object's filtered record, and their point counts.
void make_records(const FuseOptions& options, const fusion::ObjectMap& objects,
                  FuseResult& result) {
  result.objects = objects.records(record_options(options, result.threads));
  count_points(result);
}

// Where each object was in view (with `view_log`), then each confirmed object's filtered record.
void judge_and_record(const FuseOptions& options, fusion::ObjectMap& objects,
                      const fusion::ViewLog* view_log, FuseResult& result) {
  result.objects_total = objects.size();
  if (view_log) {
    objects.judge_visibility(*view_log, options.visibility);
    result.objects_below_share = objects.below_share_count();
    result.detected_share_bar = objects.detected_share_bar();
  }
  make_records(options, objects, result);
}

// Step 4: the final merge pass (ID-switch repair) and the split of clusters seen apart, then where
// each object was in view and each confirmed object's filtered record.
void merge_and_filter_objects(const FuseOptions& options, fusion::ObjectMap& objects,
                              const fusion::ViewLog* view_log, FuseResult& result) {
  result.merges = objects.merge_pass();
  result.splits = objects.split_pass();
  judge_and_record(options, objects, view_log, result);
}

// Step 4c: with the up known, the objects wider than their class allows are cut (one mask over
// chairs packed along a table). When any is, its parts are judged in view and recorded (every
// object again only if the detected-share bar moved).
void cut_oversize_objects(const FuseOptions& options, const segmentation::ClassSizes& sizes,
                          fusion::ObjectMap& objects, const fusion::ViewLog* view_log,
                          FuseResult& result) {
  const auto t0 = Clock::now();
  result.oversize = objects.split_oversize(result.scene.up.up, sizes);
  result.part_joins = objects.join_parts(result.scene.up.up, sizes);
  std::set<int> cut;
  for (const fusion::SplitLink& link : result.oversize) {
    cut.insert(link.from);
    cut.insert(link.parts.begin(), link.parts.end());
  }
  for (const fusion::MergeLink& link : result.part_joins) cut.insert({link.into, link.absorbed});
  if (!cut.empty()) {
    const double bar = result.detected_share_bar;
    result.objects_total = objects.size();
    if (view_log) {
      objects.judge_visibility(*view_log, options.visibility, /*only_unjudged=*/true);
      result.objects_below_share = objects.below_share_count();
      result.detected_share_bar = objects.detected_share_bar();
    }
    if (result.detected_share_bar != bar) {
      make_records(options, objects, result);
    } else {
      std::vector<fusion::ObjectRecord> records;
      for (auto& r : result.objects)
        if (!cut.count(r.id)) records.push_back(std::move(r));
      for (auto& r : objects.records(record_options(options, result.threads), cut))
        records.push_back(std::move(r));
      std::sort(
          records.begin(), records.end(),
          [](const fusion::ObjectRecord& x, const fusion::ObjectRecord& y) { return x.id < y.id; });
      result.objects = std::move(records);
      count_points(result);
    }
  }
  result.times.push_back({"oversize objects", seconds_since(t0)});
}

// The point counts of the written maps (run.json "points").
struct MapPoints {
  std::size_t semantic = 0;
  std::size_t objects = 0;
};

// Step 5: the maps: map_dense.ply and the semantic map (the dense points with the objects'
// colours) on two more threads, the objects-only map and a PLY per object meanwhile; returns the
// objects' records of objects.json.
ordered_json write_maps(const FuseOptions& options, const fs::path& dir,
                        const io::PlyWriteOptions& ply, const DenseCloud& dense_cloud,
                        const FuseResult& result, MapPoints& points) {
  points.semantic = dense_cloud.cloud.size();
  std::vector<Rgb> record_color(result.objects.size());
  for (std::size_t i = 0; i < result.objects.size(); ++i)
    record_color[i] = fusion::class_color(result.objects[i].class_name);
  // Both read dense_cloud and neither changes it; declared after it, they are joined before it
  // goes, even when an exception unwinds.
  std::future<void> dense_write_future, semantic_future;
  if (options.dense_map) {
    dense_write_future = std::async(
        std::launch::async, [&] { io::write_ply(dir / "map_dense.ply", dense_cloud.cloud, ply); });
    semantic_future = std::async(std::launch::async, [&] {
      const std::vector<Rgb> colors =
          semantic_colors(dense_cloud, options.map_voxel_m, result.objects, record_color);
      io::write_ply(dir / "map_semantic.ply", dense_cloud.cloud, colors, ply);
    });
  }
  PointCloud objects_only;
  for (std::size_t i = 0; i < result.objects.size(); ++i) {
    if (!result.objects[i].confirmed) continue;
    for (const Vec3f& p : result.objects[i].cloud.points)
      objects_only.push_back(p, record_color[i]);
  }
  points.objects = objects_only.size();
  io::write_ply(dir / "map_objects.ply", objects_only, ply);
  objects_only = PointCloud();
  io::create_output_folders(dir / "objects");
  ordered_json objects_json = ordered_json::array();
  for (std::size_t i = 0; i < result.objects.size(); ++i) {
    const fusion::ObjectRecord& r = result.objects[i];
    const std::string stem = "objects/" + std::to_string(r.id) + "_" + file_safe(r.class_name);
    io::write_ply(dir / (stem + ".ply"), r.cloud, ply);
    objects_json.push_back(object_json(r, stem + ".ply"));
    if (i < result.object_meshes.size()) {
      const ObjectMesh& m = result.object_meshes[i];
      ordered_json mesh_json = {{"file", nullptr},
                                {"vertices", m.model.mesh.vertices.size()},
                                {"triangles", m.model.mesh.triangles.size()},
                                {"voxel_m", m.model.voxel_m},
                                {"views", m.views}};
      if (!m.model.mesh.empty()) {
        mesh_json["file"] = stem + "_mesh.ply";
        io::write_mesh_ply(dir / (stem + "_mesh.ply"), m.model.mesh, ply);
      }
      objects_json.back()["mesh"] = mesh_json;
    }
  }
  if (!result.scene_mesh.mesh.empty())
    io::write_mesh_ply(dir / "map_mesh.ply", result.scene_mesh.mesh, ply);
  if (options.dense_map) {
    dense_write_future.get();
    semantic_future.get();
  }
  return objects_json;
}

// objects.json: the records of the confirmed objects.
// A sighting of objects.json: a thing that moves by itself, where and when it was seen.
ordered_json sighting_json(const fusion::ObjectRecord& r) {
  return {{"id", r.id},
          {"class", r.class_name},
          {"score", r.mean_score},
          {"position", vec_json(r.position)},
          {"aabb", {{"min", vec_json(r.aabb.min)}, {"max", vec_json(r.aabb.max)}}},
          {"first_seen", r.first_seen},
          {"last_seen", r.last_seen},
          {"frames", r.frames_detected},
          {"observation_count", r.observations},
          {"track_ids", r.track_ids},
          {"points", r.points_filtered}};
}

void write_objects_json(const fs::path& dir, const ordered_json& objects_json,
                        const std::vector<fusion::ObjectRecord>& sightings,
                        const scene::SceneGraph& scene) {
  ordered_json doc;
  doc["schema_version"] = 1;
  doc["generator"] = std::string("objmap ") + objmap::version();
  doc["frame"] = "world";
  doc["units"] = "metres";
  doc["objects"] = objects_json;
  doc["sightings"] = ordered_json::array();
  for (const fusion::ObjectRecord& r : sightings) doc["sightings"].push_back(sighting_json(r));
  add_scene_json(scene, doc);
  io::write_file_atomic(dir / "objects.json", doc.dump(2) + "\n");
}

// run.json "inputs": the paths with their checksums, the camera and why it was chosen. The
// trajectory of a run on the dataset's own poses is the copy written into the run folder.
ordered_json inputs_json(const FuseOptions& options, const FuseInputs& inputs,
                         const FuseResult& result) {
  ordered_json dataset = {{"path", options.dataset.string()}, {"layout", result.layout}};
  if (!inputs.dataset.topics.empty()) dataset["topics"] = inputs.dataset.topics;
  if (result.layout == "tum") {
    dataset["rgb.txt"] = file_checksum(options.dataset / "rgb.txt");
    dataset["depth.txt"] = file_checksum(options.dataset / "depth.txt");
  } else {
    std::string names;
    for (const io::FramePair& f : inputs.dataset.frames)
      names += f.rgb_file.filename().string() + " " + f.depth_file.filename().string() + "\n";
    dataset["frames"] = hex64(fnv1a(names));
  }
  ordered_json trajectory;
  if (options.trajectory.empty()) {
    const std::string text = io::format_trajectory(inputs.trajectory);
    trajectory = {{"path", (options.out / kDatasetTrajectory).string()},
                  {"from", "dataset"},
                  {"source", inputs.trajectory.source},
                  {"checksum", hex64(fnv1a(text))}};
  } else {
    trajectory = {{"path", options.trajectory.string()},
                  {"checksum", file_checksum(options.trajectory)}};
  }
  return {{"dataset", dataset},
          {"trajectory", trajectory},
          {"segmentation",
           {{"path", options.segmentation.string()},
            {"format", result.seg_format},
            {"checksum", folder_checksum(options.segmentation)}}},
          {"camera", nlohmann::ordered_json::parse(io::camera_json(result.camera))},
          {"camera_reason", result.camera_reason}};
}

std::size_t mesh_triangles(const std::vector<ObjectMesh>& meshes) {
  std::size_t n = 0;
  for (const ObjectMesh& m : meshes) n += m.model.mesh.triangles.size();
  return n;
}

// run.json "counts": per stage.
ordered_json counts_json(const FuseInputs& inputs, const FuseResult& result) {
  return {
      {"frames", result.frames},
      {"frames_with_pose", result.keyframes.frames_with_pose},
      {"keyframe_mode", result.keyframes.mode},
      {"keyframe_mode_reason", result.keyframes.reason},
      {"keyframes", result.keyframes.keyframes.size()},
      {"keyframes_with_segmentation", inputs.with_seg},
      {"instances", result.instances_seen},
      {"instances_below_min_score", result.instances_skipped_score},
      {"instances_mask_from_box", result.instances_from_box},
      {"instances_mask_refined", result.instances_refined},
      {"instances_duplicate", result.instances_duplicate},
      {"mask_pixels_removed", result.mask_pixels_removed},
      {"instances_depth_gated", result.instances_depth_gated},
      {"depth_gate_pixels_removed", result.depth_gate_pixels_removed},
      {"instances_without_points", result.instances_empty},
      {"instances_bleed", result.instances_bleed},
      {"instances_spanning", result.instances_spanning},
      {"observations", result.observations},
      {"objects_before_confirmation", result.objects_total},
      {"objects_below_detected_share", result.objects_below_share},
      {"objects_confirmed", result.objects.size()},
      {"sightings", result.sightings.size()},
      {"merges", result.merges.size()},
      {"objects_split", result.splits.size()},
      {"objects_cut_for_size", result.oversize.size()},
      {"objects_joined_as_parts", result.part_joins.size()},
      {"object_meshes", std::count_if(result.object_meshes.begin(), result.object_meshes.end(),
                                      [](const ObjectMesh& m) { return !m.model.mesh.empty(); })},
      {"object_mesh_triangles", mesh_triangles(result.object_meshes)},
      {"scene_mesh_vertices", result.scene_mesh.mesh.vertices.size()},
      {"scene_mesh_triangles", result.scene_mesh.mesh.triangles.size()}};
}

// run.json "points": Table 6, the point counts and their reductions. The paper's Table 6 figure
// is reduction_objects_vs_dense (the objects-only map against the dense map); eq 18's own is
// reduction_eq18 (voxel-filtered -> outlier-filtered object points).
ordered_json points_json(const FuseResult& result, const MapPoints& maps) {
  const auto reduction = [](double before, double after) {
    return before > 0 ? 1.0 - after / before : 0.0;
  };
  return {
      {"dense_back_projected", result.dense_points_raw},
      {"dense_map", result.dense_points_map},
      {"dense_pruned", result.dense_voxels_pruned},
      {"dense_sightings", result.dense_voxels_of_sightings},
      {"objects_raw", result.object_points_raw},
      {"objects_voxel_filtered", result.object_points_voxel},
      {"objects_outlier_filtered", result.object_points_filtered},
      {"semantic_map", maps.semantic},
      {"objects_map", maps.objects},
      {"reduction_objects_voxel", reduction(result.object_points_raw, result.object_points_voxel)},
      {"reduction_objects_total",
       reduction(result.object_points_raw, result.object_points_filtered)},
      {"reduction_dense", reduction(result.dense_points_raw, result.dense_points_map)},
      {"reduction_eq18", reduction(result.object_points_voxel, result.object_points_filtered)},
      {"reduction_objects_vs_dense", reduction(result.dense_points_map, maps.objects)}};
}

// run.json "performance": time per stage and memory; the only part of the run folder that differs
// between two runs of the same inputs.
ordered_json performance_json(const FuseResult& result) {
  const auto& keyframes = result.keyframes.keyframes;
  ordered_json perf;
  for (const auto& t : result.times) perf["seconds"][t.stage] = t.seconds;
  perf["seconds"]["total"] = result.seconds_total;
  perf["ms_per_keyframe"] =
      keyframes.empty() ? 0.0 : 1000.0 * result.seconds_total / keyframes.size();
  perf["peak_rss_mb"] = result.peak_rss_kb / 1024.0;
  perf["threads"] = result.threads;
  return perf;
}

// run.json: options, inputs with checksums, counts per stage, Table 6, time per stage, memory.
void write_run_json(const fs::path& dir, const FuseOptions& options, const FuseInputs& inputs,
                    const fusion::ObjectMapOptions& object_options, const MapPoints& maps,
                    const FuseResult& result) {
  FuseOptions echo = options;
  ordered_json run;
  run["schema_version"] = 1;
  run["generator"] = std::string("objmap ") + objmap::version();
  run["command"] = "fuse";
  run["inputs"] = inputs_json(options, inputs, result);
  run["options"] = ordered_json::parse(config_to_json(fuse_config_fields(echo)));
  run["counts"] = counts_json(inputs, result);
  if (result.detected_share_bar > 0.0)
    run["confirmation"] = {{"detected_share_bar", result.detected_share_bar},
                           {"objects_below", result.objects_below_share}};
  run["points"] = points_json(result, maps);
  run["duplicates"] = duplicates_json(result.duplicates, options.duplicates, object_options);
  run["scene"] = scene_run_json(result.scene);
  run["performance"] = performance_json(result);
  io::write_file_atomic(dir / "run.json", run.dump(2) + "\n");
}

// Step 4a (docs/fusion.md, "Sightings"): the objects of a mover class are taken out of
// result.objects into result.sightings, so they stay out of the duplicates, the relations and the
// maps.
// Step 4e: the objects' meshes (with `object_views`) and the scene's (with `scene_model`, which
// is released).
void make_meshes(const FuseOptions& options, const fusion::ObjectMap& objects,
                 const ObjectViews* object_views, std::optional<mesh::TsdfModel>& scene_model,
                 FuseResult& result) {
  if (object_views) {
    const auto t0 = Clock::now();
    result.object_meshes =
        mesh_objects(result.objects, *object_views, objects, options.mesh,
                     0.5 * (result.camera.fx + result.camera.fy), result.threads);
    result.times.push_back({"object meshes", seconds_since(t0)});
  }
  if (scene_model) {
    const auto t0 = Clock::now();
    result.scene_mesh = scene_model->mesh();
    scene_model.reset();
    result.times.push_back(
        {"scene mesh (and its fusion's share after the keyframes)", seconds_since(t0)});
  }
}

void take_sightings(const FuseOptions& options, FuseResult& result) {
  result.sightings =
      fusion::take_movers(result.objects, fusion::parse_movers(options.movers, "objects.movers"));
}

}  // namespace

FuseResult run_fuse(const FuseOptions& options, const FuseProgress& progress) {
  options.check();
  io::require_not_an_input({"--out", options.out}, {{"--dataset", options.dataset},
                                                    {"--trajectory", options.trajectory},
                                                    {"--segmentation", options.segmentation}});
  io::require_replaceable(options.out, io::kRunFolder);  // before the work, not after it
  const segmentation::ClassSizes class_sizes =
      segmentation::ClassSizes::from_spec(options.class_sizes);
  const auto t_start = Clock::now();
  FuseResult result;
  // 1-2. Inputs (the TUM folder, the camera, the trajectory, the segmentation) and keyframes.
  const FuseInputs inputs = load_inputs(options, result);
  result.threads = fuse_threads(options.threads);

  // 3. Back-project and fuse, keyframe by keyframe, with the worker pipeline; the maps do not
  //    depend on the thread count.
  auto t0 = Clock::now();
  const fusion::VoxelMapOptions dense_options = dense_map_options(options, result.threads);
  fusion::VoxelMap dense(dense_options);
  const fusion::ObjectMapOptions object_options =
      object_map_options(options, result.keyframes.still_camera);
  fusion::ObjectMap objects(object_options);
  const mesh::MeshSelection meshes = mesh::parse_mesh_selection(options.mesh.select, "mesh.select");
  std::optional<ObjectViews> object_views;
  if (meshes.objects) object_views.emplace();
  std::optional<mesh::TsdfModel> scene_model;
  if (meshes.scene)
    scene_model.emplace(unbounded_box(), options.mesh.scene_voxel_m,
                        scene_tsdf_options(options.mesh));
  std::optional<fusion::ViewLog> view_log;
  if (object_options.min_detected_share > 0.0) view_log.emplace(result.camera);
  fuse_keyframes(options, progress, inputs, options.dense_map ? &dense : nullptr, objects,
                 object_views ? &*object_views : nullptr, scene_model ? &*scene_model : nullptr,
                 view_log ? &*view_log : nullptr, result);
  result.times.push_back({"back-project and fuse", seconds_since(t0)});

  // 4-5. The run folder is written under a temporary name and renamed when complete. The dense
  //      map's cloud, the up direction and the support surfaces (docs/scene.md) are made on a
  //      second thread meanwhile the objects are merged and filtered (they do not depend on each
  //      other).
  io::StagingDir staging(options.out, io::kRunFolder);
  const fs::path dir = staging.path();
  io::PlyWriteOptions ply;
  ply.comment = std::string("objmap ") + objmap::version();
  auto t_dense = Clock::now();
  double dense_seconds = 0.0;
  std::vector<Pose> cameras;
  for (const Keyframe& k : result.keyframes.keyframes) cameras.push_back(k.world_from_cam);
  std::future<DenseCloud> dense_future = std::async(std::launch::async, [&] {
    DenseCloud cloud = options.dense_map ? take_dense_cloud(dense, dense_options) : DenseCloud{};
    dense_seconds = seconds_since(t_dense);
    scene::find_up_and_surfaces(cameras, cloud.cloud.points, options.scene, result.scene);
    return cloud;
  });

  // 4. The final merge pass (ID-switch repair), then each confirmed object's filtered record.
  t0 = Clock::now();
  merge_and_filter_objects(options, objects, view_log ? &*view_log : nullptr, result);
  result.times.push_back({"merge and filter objects", seconds_since(t0)});

  DenseCloud dense_cloud = dense_future.get();
  result.times.push_back({"dense map (parallel to the objects)", dense_seconds});
  result.times.push_back({"up and surfaces (parallel to the objects)",
                          result.scene.seconds_up + result.scene.seconds_surfaces});
  for (const auto& w : result.scene.up.warnings) result.warnings.push_back("up direction: " + w);

  // 4a. Objects wider than their class allows are cut, now that the up is known.
  cut_oversize_objects(options, class_sizes, objects, view_log ? &*view_log : nullptr, result);

  // 4b. What moves is not the map: the objects of a mover class (a person, a dog) are sightings.
  take_sightings(options, result);
  result.dense_voxels_of_sightings =
      drop_sighting_voxels(dense_cloud, result.sightings, result.objects, options.map_voxel_m);

  // 4c. Suspected duplicates: confirmed objects of one class that overlap or touch, with the merge
  //     pass's reason for keeping them apart (no ground truth needed), on the boxes of
  //     the records (before the scene step turns them upright).
  t0 = Clock::now();
  result.duplicates = fusion::find_duplicates(result.objects, objects, options.duplicates);
  result.times.push_back({"duplicate check", seconds_since(t0)});

  // 4d. The objects' boxes stand on up; the surfaces that are objects' tops; the relations (on,
  //     near, above, under).
  relate_to_scene(result.objects, options.scene, record_options(options, result.threads),
                  result.scene);
  result.times.push_back({"boxes upright and relations", result.scene.seconds_relations});

  // 4e. The meshes: each object's TSDF model from the observations that joined it (merged objects
  //     union theirs), in its box; the scene's model, fused keyframe by keyframe, meshed.
  make_meshes(options, objects, object_views ? &*object_views : nullptr, scene_model, result);

  // 5. The maps (dense, semantic, objects, one PLY per object) and objects.json.
  t0 = Clock::now();
  result.dense_points_map = dense_cloud.cloud.size();
  MapPoints map_points;
  const ordered_json objects_json = write_maps(options, dir, ply, dense_cloud, result, map_points);
  dense_cloud = DenseCloud();
  write_objects_json(dir, objects_json, result.sightings, result.scene);
  result.times.push_back({"write outputs", seconds_since(t0)});
  result.seconds_total = seconds_since(t_start);
  result.peak_rss_kb = peak_rss_kb();

  // 5b. run.json: options, inputs with checksums, counts per stage, Table 6, time per stage,
  //     memory.
  write_run_json(dir, options, inputs, object_options, map_points, result);
  if (options.trajectory.empty())
    io::write_trajectory(dir / kDatasetTrajectory, inputs.trajectory,
                         "the camera poses of " + options.dataset.string() + " (" + result.layout +
                             " layout: " + inputs.trajectory.source + ")");
  staging.commit();
  return result;
}

std::vector<fusion::Observation> remake_observations(const FuseOptions& options,
                                                     const std::vector<int>& keyframe_indices) {
  {
    FuseOptions checked = options;  // nothing is written: `out` may be empty
    if (checked.out.empty()) checked.out = "unused";
    checked.check();
  }
  FuseResult result;
  const FuseInputs inputs = load_inputs(options, result);
  const auto& keyframes = result.keyframes.keyframes;
  for (int i : keyframe_indices)
    require(i >= 0 && static_cast<std::size_t>(i) < keyframes.size(), options.dataset.string(),
            "keyframe " + std::to_string(i) + " does not exist (" +
                std::to_string(keyframes.size()) +
                " keyframes); expected the inputs and options the run was fused with");
  const int threads = fuse_threads(options.threads);
  const geometry::RayTable rays = geometry::make_ray_table(result.camera, threads);
  std::vector<std::vector<fusion::Observation>> per_keyframe(keyframe_indices.size());
  parallel_for(keyframe_indices.size(), threads, [&](std::size_t j) {
    const std::size_t i = static_cast<std::size_t>(keyframe_indices[j]);
    segmentation::FrameSegmentation lazy;
    const segmentation::FrameSegmentation* seg = keyframe_segmentation(inputs, i, lazy);
    per_keyframe[j] = process_keyframe(options, result.camera, rays, inputs.dataset,
                                       inputs.dataset.frames[keyframes[i].frame], keyframes[i],
                                       static_cast<int>(i), seg, nullptr, nullptr, nullptr)
                          .observations;
  });
  std::vector<fusion::Observation> out;
  for (auto& v : per_keyframe)
    for (auto& o : v) out.push_back(std::move(o));
  return out;
}

}  // namespace objmap::pipeline

#include "objmap/pipeline/fuse_keyframes.h"

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "objmap/core/job_threads.h"
#include "objmap/core/parallel.h"
#include "objmap/fusion/frame_voxels.h"
#include "objmap/io/image.h"
#include "objmap/segmentation/instance_masks.h"

namespace objmap::pipeline {

namespace {

// Hash shards of the dense map. The workers merge their keyframe's voxels into the dense map shard
// by shard, each shard strictly in keyframe order, so two workers merge different shards at once
// and every voxel sums its frames in the same order whatever the thread count.
constexpr int kDenseShards = 16;

// Who may merge into which shard of the dense map: shard s takes keyframe next[s] only.
class ShardedMergeOrder {
 public:
  // `first`: the keyframe index each shard takes first.
  explicit ShardedMergeOrder(std::size_t shards, std::size_t first = 0) : next_(shards, first) {}

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
  std::vector<PackedPixelRuns> pixels;  // per observation, its pixels (KeyframeContext)
  std::unique_ptr<fusion::FrameVoxels> dense_voxels;  // summed, not yet in the dense map
  bool segmented = false;  // made with a segmentation frame (none: the dense map only)
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

// What every keyframe of a run shares: the options, the camera, its ray table, the recording, the
// mask cleaning's options and the meshes asked for (none for re-made observations), made once.
struct KeyframeContext {
  const FuseOptions& options;
  const Camera& camera;
  const geometry::RayTable& rays;
  const io::Dataset& dataset;
  segmentation::InstanceMaskOptions masks;  // instance_mask_options(options)
  mesh::MeshSelection meshes;               // the rays of the scene model, the objects' models
  bool view_depth = false;                  // keep the thinned depth for the view log
  bool keep_pixels = false;  // each observation's pixels as runs (objmap follow's loop closure)
};

// Where a keyframe's dense voxels go: the dense map, shard by shard in keyframe order, through a
// pooled frame buffer. Without an order, the worker only sums them (FrameWork::dense_voxels) and
// the caller adds them.
struct DenseMerge {
  fusion::VoxelMap& map;
  ShardedMergeOrder* order;
  FrameVoxelsPool& pool;
};

// Back-projects one keyframe: the dense points summed by voxel (frame_voxels.h, so that voxels are
// merged, not pixels) and added to the dense map in keyframe order, and each instance's pixels
// into an observation. Without `dense`, no dense map.
FrameWork process_keyframe(const KeyframeContext& ctx, const io::FramePair& frame,
                           const Keyframe& keyframe, int keyframe_index,
                           const segmentation::FrameSegmentation* seg, DenseMerge* dense) {
  const FuseOptions& options = ctx.options;
  const Camera& camera = ctx.camera;
  const geometry::RayTable& rays = ctx.rays;
  FrameWork work;

  // 1. The images (checked: size, type).
  const cv::Mat bgr = io::read_frame_rgb(ctx.dataset, frame, camera.width, camera.height);
  const cv::Mat depth = io::read_frame_depth(ctx.dataset, frame, camera);
  if (dense && options.dense_prune.every_keyframes > 0) work.depth = depth;
  if (ctx.view_depth) work.view_depth = fusion::ViewLog(camera).thin(depth);

  // 2. Dense map: every valid pixel (eqs 11-15) with its colour.
  geometry::BackprojectOptions dense_options = options.depth;
  dense_options.stride = options.dense_stride;
  const geometry::DepthFrame dense_frame(depth, keyframe.world_from_cam, &bgr);
  if (dense) {
    std::unique_ptr<fusion::FrameVoxels> frame_voxels = dense->pool.take();
    fusion::frame_voxels(rays, dense_frame, dense_options, dense->map, *frame_voxels);
    work.dense_points = frame_voxels->points();
    if (dense->order) {
      dense->order->merge_in_order(
          static_cast<std::size_t>(keyframe_index),
          [&](std::size_t shard) { dense->map.add_shard(*frame_voxels, shard); });
      dense->pool.give_back(std::move(frame_voxels));
    } else {
      work.dense_voxels = std::move(frame_voxels);
    }
  }

  // 2b. The scene model's rays: every valid pixel, averaged per scene-model voxel (in a fuse
  //     with a scene mesh; not for re-made observations).
  if (ctx.meshes.scene)
    work.scene_points =
        mesh::voxel_means(geometry::backproject(rays, dense_frame, dense_options).points_in_world,
                          options.mesh.scene_voxel_m);

  // 3. Instances: the mask (given, or from the box and the depth), its pixels in the world.
  if (!seg) return work;
  // 3a. Each instance's cleaned mask and its bounds; one instance per object and keyframe (a
  //     second box of the same object is dropped).
  const std::vector<segmentation::InstanceMask> masks =
      segmentation::clean_instance_masks(*seg, depth, camera, ctx.masks, work.masks);
  // 3b. The kept instances' pixels in the world, in the segmentation's order.
  for (const segmentation::InstanceMask& m : masks) {
    const geometry::DepthFrame instance_frame(depth, keyframe.world_from_cam, &bgr, &m.mask(),
                                              m.bounds);
    if (instance_frame.roi.empty()) {
      ++work.without_points;
      continue;
    }
    geometry::BackprojectOptions instance_options = options.depth;
    instance_options.pixel_indices = ctx.keep_pixels;
    auto points = geometry::backproject(rays, instance_frame, instance_options);
    if (points.points_in_world.size() < static_cast<std::size_t>(options.objects.min_points)) {
      ++work.without_points;
      continue;
    }
    fusion::Observation obs;
    obs.timestamp = keyframe.timestamp;
    obs.track_id = m.instance->track_id;
    obs.class_name = m.instance->class_name;
    obs.score = m.instance->score;
    if (ctx.keep_pixels)
      work.pixels.push_back(pack_pixel_runs(geometry::make_pixel_runs(
          points.pixel_index, depth, points.points_in_world.colors, instance_options.stride)));
    obs.points_in_world = std::move(points.points_in_world);
    obs.keyframe_index = keyframe_index;
    obs.centroid_in_cam = points.centroid_in_cam;
    obs.world_from_cam = keyframe.world_from_cam;
    if (ctx.meshes.objects) work.model_points.push_back(model_points(obs, options.mesh));
    work.observations.push_back(std::move(obs));
  }
  return work;
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

}  // namespace

int fuse_threads(int requested) {
  return requested > 0 ? requested : std::min(8, resolve_threads(0));
}

fusion::VoxelMapOptions dense_map_options(const FuseOptions& options, int threads) {
  fusion::VoxelMapOptions dense_options;
  dense_options.voxel_m = options.map_voxel_m;
  dense_options.threads = threads;  // for sorting on export; voxels come via merge_shard
  dense_options.shards = kDenseShards;
  return dense_options;
}

void fuse_keyframes(const FuseOptions& options, const FuseChoices& choices,
                    const FuseProgress& progress, const FuseInputs& inputs, fusion::VoxelMap* dense,
                    fusion::ObjectMap& objects, ObjectViews* object_views, mesh::TsdfModel* scene,
                    fusion::ViewLog* view_log, FuseResult& result) {
  const Camera& camera = result.camera;
  const auto& keyframes = result.keyframes.keyframes;
  const geometry::RayTable rays = geometry::make_ray_table(camera, result.threads);
  const KeyframeContext ctx{options,
                            camera,
                            rays,
                            inputs.dataset,
                            instance_mask_options(options),
                            choices.meshes,
                            options.objects.min_detected_share > 0.0};
  ShardedMergeOrder merge_order(kDenseShards);
  FrameVoxelsPool frame_voxels;
  std::optional<DenseMerge> dense_merge;
  if (dense) dense_merge.emplace(DenseMerge{*dense, &merge_order, frame_voxels});
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
  // As many threads as keyframes in flight: every job queued starts at once, as with a thread
  // per keyframe (a keyframe waiting for its turn to merge never holds back an earlier one).
  JobThreads<FrameWork> workers(window + 1);
  auto launch = [&](std::size_t i) {
    return workers.submit([&, i] {
      try {
        // The keyframe's instances: read now (canonical JSON) or taken from the whole
        // segmentation.
        segmentation::FrameSegmentation lazy;
        const segmentation::FrameSegmentation* seg_frame = keyframe_segmentation(inputs, i, lazy);
        return process_keyframe(ctx, inputs.dataset.frames[keyframes[i].frame], keyframes[i],
                                static_cast<int>(i), seg_frame,
                                dense_merge ? &*dense_merge : nullptr);
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
      count_added(added, result);
      for (std::size_t k = 0; k < added.size(); ++k) {
        if (added[k].object_id < 0) continue;
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

void count_added(const std::vector<fusion::AddResult>& added, FuseResult& result) {
  for (const fusion::AddResult& a : added) {
    if (a.object_id >= 0)
      ++result.observations;
    else
      ++(a.bleed      ? result.instances_bleed
         : a.spanning ? result.instances_spanning
                      : result.instances_empty);
  }
}

struct LiveKeyframes::Impl {
  Impl(const FuseOptions& options, const Camera& camera, const geometry::RayTable& rays,
       fusion::VoxelMap* dense, bool view_depth, int threads)
      : options(options),
        camera(camera),
        rays(rays),
        masks(instance_mask_options(options)),
        view_depth(view_depth),
        dense(dense),
        workers(static_cast<std::size_t>(std::max(1, threads))) {}
  const FuseOptions& options;
  const Camera& camera;
  const geometry::RayTable& rays;
  const segmentation::InstanceMaskOptions masks;
  const bool view_depth;
  fusion::VoxelMap* dense;
  FrameVoxelsPool pool;
  std::deque<std::future<FrameWork>> queued;
  JobThreads<FrameWork> workers;  // last: joined first, while the rest is still there
};

LiveKeyframes::LiveKeyframes(const FuseOptions& options, const Camera& camera,
                             const geometry::RayTable& rays, fusion::VoxelMap* dense,
                             bool view_depth, int threads)
    : impl_(std::make_unique<Impl>(options, camera, rays, dense, view_depth, threads)) {}

LiveKeyframes::~LiveKeyframes() { drop(); }

std::size_t LiveKeyframes::queued() const { return impl_->queued.size(); }

void LiveKeyframes::submit(const io::Dataset& dataset, const Keyframe& keyframe, int index,
                           std::function<std::optional<segmentation::FrameSegmentation>()> seg) {
  Impl& m = *impl_;
  m.queued.push_back(m.workers.submit([&m, &dataset, keyframe, index, seg = std::move(seg)] {
    const std::optional<segmentation::FrameSegmentation> instances = seg();
    const KeyframeContext ctx{
        m.options, m.camera, m.rays, dataset, m.masks, mesh::MeshSelection{}, m.view_depth, true};
    std::optional<DenseMerge> merge;  // summed here, added by take() in keyframe order
    if (m.dense) merge.emplace(DenseMerge{*m.dense, nullptr, m.pool});
    FrameWork work = process_keyframe(ctx, dataset.frames[keyframe.frame], keyframe, index,
                                      instances ? &*instances : nullptr, merge ? &*merge : nullptr);
    work.segmented = instances.has_value();
    return work;
  }));
}

LiveKeyframe LiveKeyframes::take(FuseResult& result) {
  Impl& m = *impl_;
  std::future<FrameWork> next = std::move(m.queued.front());
  m.queued.pop_front();
  FrameWork work = next.get();
  if (work.dense_voxels) {
    for (std::size_t shard = 0; shard < work.dense_voxels->shard_count(); ++shard)
      m.dense->add_shard(*work.dense_voxels, shard);
    m.pool.give_back(std::move(work.dense_voxels));
  }
  add_counts(work, result);
  return {std::move(work.observations), std::move(work.pixels), std::move(work.view_depth),
          work.segmented};
}

void LiveKeyframes::drop() {
  for (std::future<FrameWork>& f : impl_->queued) {
    try {
      FrameWork work = f.get();
      if (work.dense_voxels) impl_->pool.give_back(std::move(work.dense_voxels));
    } catch (const std::exception&) {  // a keyframe dropped unread: its error with it
    }
  }
  impl_->queued.clear();
}

std::vector<fusion::Observation> keyframe_observations(
    const FuseOptions& options, const Camera& camera, const geometry::RayTable& rays,
    const FuseInputs& inputs, const std::vector<Keyframe>& keyframes, std::size_t i) {
  segmentation::FrameSegmentation lazy;
  const segmentation::FrameSegmentation* seg = keyframe_segmentation(inputs, i, lazy);
  // No dense map, no meshes, no view log: the observations alone.
  const KeyframeContext ctx{
      options, camera, rays, inputs.dataset, instance_mask_options(options), mesh::MeshSelection{},
      false};
  return process_keyframe(ctx, inputs.dataset.frames[keyframes[i].frame], keyframes[i],
                          static_cast<int>(i), seg, nullptr)
      .observations;
}

}  // namespace objmap::pipeline

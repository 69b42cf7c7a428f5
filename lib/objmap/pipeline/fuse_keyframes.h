#pragma once
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "objmap/fusion/object_map.h"
#include "objmap/fusion/visibility.h"
#include "objmap/fusion/voxel_map.h"
#include "objmap/geometry/backproject.h"
#include "objmap/pipeline/fuse.h"
#include "objmap/pipeline/fuse_inputs.h"
#include "objmap/pipeline/packed_pixels.h"

// Step 3 of `objmap fuse`: the keyframe loop. Workers decode and back-project keyframes ahead
// (a pool of frame buffers, the dense map merged shard by shard in keyframe order); the calling
// thread associates their observations in keyframe order, so the maps do not depend on the thread
// count.
namespace objmap::pipeline {

// The worker threads of `requested` (0: the cores, at most 8: the objects are associated on one
// thread, ~15% of the work, so more workers would add memory, not speed).
int fuse_threads(int requested);

// The dense map's options: voxels come from the workers via merge_shard; threads for the sort on
// export.
fusion::VoxelMapOptions dense_map_options(const FuseOptions& options, int threads);

// Step 3: back-project and fuse, keyframe by keyframe. Workers decode and back-project ahead (one
// keyframe more than threads in flight); this thread merges their results strictly in keyframe
// order, so the maps do not depend on the thread count. Without `dense`, the observations only.
// After every options.dense_prune.every_keyframes keyframes the dense map's noise is pruned, the
// next keyframes held back from the map meanwhile: always between the same two keyframes.
// The observations that joined objects go to `views` and each keyframe's depth to `scene`, when
// given, for the meshes; each keyframe's thinned depth to `view_log`, when given.
void fuse_keyframes(const FuseOptions& options, const FuseChoices& choices,
                    const FuseProgress& progress, const FuseInputs& inputs, fusion::VoxelMap* dense,
                    fusion::ObjectMap& objects, ObjectViews* object_views, mesh::TsdfModel* scene,
                    fusion::ViewLog* view_log, FuseResult& result);

// The association's outcome per observation into the run's counts (observations, bleed, spanning,
// empty).
void count_added(const std::vector<fusion::AddResult>& added, FuseResult& result);

// objmap follow's keyframes, each made exactly as fuse_keyframes makes it: decoded and
// back-projected ahead on worker threads (submit), taken back in the order submitted on the calling
// thread (take), which adds their dense voxels to the dense map, so that it sums its keyframes in
// fuse's order. The options, camera, rays and dense map given must outlive it.
struct LiveKeyframe {
  std::vector<fusion::Observation> observations;  // not yet associated
  std::vector<PackedPixelRuns> pixels;            // each observation's pixels (packed_pixels.h)
  cv::Mat view_depth;                             // the thinned depth, for the view log
  bool segmented = false;                         // made with a segmentation frame
};
class LiveKeyframes {
 public:
  // `dense`: the dense map (null: none); `view_depth`: keep the thinned depths; `threads` workers.
  LiveKeyframes(const FuseOptions& options, const Camera& camera, const geometry::RayTable& rays,
                fusion::VoxelMap* dense, bool view_depth, int threads);
  ~LiveKeyframes();
  LiveKeyframes(const LiveKeyframes&) = delete;
  LiveKeyframes& operator=(const LiveKeyframes&) = delete;

  // Queues `keyframe` of `dataset` as the map's keyframe `index`. `instances` runs on the worker:
  // the keyframe's segmentation frame, or none. `dataset` must stay as it is until the keyframe is
  // taken or dropped.
  void submit(const io::Dataset& dataset, const Keyframe& keyframe, int index,
              std::function<std::optional<segmentation::FrameSegmentation>()> instances);
  std::size_t queued() const;
  // The oldest queued keyframe (one must be queued): its dense voxels added to the dense map, its
  // counts to `result`. Rethrows what its worker threw (InputError: a file not readable), nothing
  // added.
  LiveKeyframe take(FuseResult& result);
  // Every queued keyframe waited for and dropped, nothing added.
  void drop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Keyframe i's instance observations alone (no map), made exactly as fuse_keyframes makes them.
std::vector<fusion::Observation> keyframe_observations(
    const FuseOptions& options, const Camera& camera, const geometry::RayTable& rays,
    const FuseInputs& inputs, const std::vector<Keyframe>& keyframes, std::size_t i);

}  // namespace objmap::pipeline

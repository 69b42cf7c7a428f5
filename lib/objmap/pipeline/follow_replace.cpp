// objmap follow's loop closure: when the trajectory's past poses change, the observations of the
// keyframes mapped so far are made again from their pixels (kept as runs: each pixel's raw depth
// and colour) with their keyframes' new poses, so that they stay where they were in their camera's
// frame, and the object map is made again from them in keyframe order, as objmap fuse would make
// it with the new poses. No image is read again: the pixels are read back from follow's file. The
// dense map keeps the poses it was fused with.
#include <memory>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/geometry/pixel_runs.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/follow_state.h"
#include "objmap/pipeline/fuse_keyframes.h"
#include "objmap/pipeline/packed_pixels.h"

namespace objmap::pipeline {

void keep_for_replacing(FollowState& s, const Keyframe& keyframe,
                        std::vector<fusion::Observation> observations,
                        std::vector<PackedPixelRuns> pixels, const cv::Mat& view_depth) {
  require(pixels.size() == observations.size(), "follow",
          "a keyframe's observations came without their pixels");
  // The points themselves are let go: the packed runs hold ~2-2.5 bytes a point against 15, in a
  // file (docs/follow.md, "Memory").
  for (fusion::Observation& o : observations) o.points_in_world = PointCloud{};
  if (!s.kept_pixels) s.kept_pixels = std::make_unique<PackedPixelFile>(s.options.out);
  std::vector<PackedPixelFile::Entry> entries;
  entries.reserve(pixels.size());
  for (const PackedPixelRuns& p : pixels) entries.push_back(s.kept_pixels->append(p));
  s.status.kept_pixels_kb = static_cast<long>(s.kept_pixels->bytes() / 1024);
  s.kept.push_back({keyframe, std::move(observations), std::move(entries), view_depth});
}

void replace_after_loop_closure(FollowState& s) {
  if (!s.rewrite_pending || !s.maps) return;
  s.rewrite_pending = false;
  io::PoseLookupOptions lookup;
  lookup.max_diff_s = s.options.fuse.max_diff_s;
  lookup.interpolate = true;
  // 1. Each kept keyframe's new pose.
  for (std::size_t i = 0; i < s.kept.size(); ++i) {
    KeptKeyframe& k = s.kept[i];
    const std::optional<Pose> pose = io::lookup_pose(s.trajectory, k.keyframe.timestamp, lookup);
    if (!pose) continue;  // its pose went away: it stays where it was
    for (fusion::Observation& o : k.observations) o.world_from_cam = *pose;
    k.keyframe.world_from_cam = *pose;
    s.result.keyframes.keyframes[i].world_from_cam = *pose;
  }
  //    The keyframes selected and not fused yet are fused with theirs, and the motion rule goes on
  //    from the last one's.
  for (WaitingKeyframe& w : s.waiting)
    if (const auto pose = io::lookup_pose(s.trajectory, w.keyframe.timestamp, lookup))
      w.keyframe.world_from_cam = *pose;
  if (s.last_keyframe)
    if (const auto pose = io::lookup_pose(s.trajectory, s.last_keyframe->timestamp, lookup))
      s.last_keyframe->world_from_cam = *pose;
  // 2. The object map (and the view log) made again, keyframe by keyframe in their order, from
  //    the observations with their points made from their pixels with the keyframe's pose; the
  //    counts of the association replaced by the new ones.
  FuseResult& r = s.result;
  FuseResult counts;
  fusion::ObjectMap objects(s.maps->objects.options());
  objects.set_record_cache(s.record_cache);
  objects.set_pair_cache(s.pair_cache);
  objects.set_contact_cache(s.contact_cache);
  std::optional<fusion::ViewLog> view_log;
  if (s.maps->view_log) view_log.emplace(r.camera);
  for (const KeptKeyframe& k : s.kept) {
    if (view_log && !k.view_depth.empty())
      view_log->add(k.keyframe.timestamp, k.view_depth.clone(), k.keyframe.world_from_cam);
    std::vector<fusion::Observation> observations = k.observations;
    for (std::size_t j = 0; j < observations.size(); ++j)
      observations[j].points_in_world = geometry::points_from_runs(
          *s.rays, unpack_pixel_runs(s.kept_pixels->read(k.pixels[j])), k.keyframe.world_from_cam);
    count_added(objects.add_frame(observations), counts);
  }
  s.maps->objects = std::move(objects);
  s.maps->view_log = std::move(view_log);
  r.observations = counts.observations;
  r.instances_bleed = counts.instances_bleed;
  r.instances_spanning = counts.instances_spanning;
  r.instances_empty = r.instances_empty - s.empty_by_add + counts.instances_empty;
  s.empty_by_add = counts.instances_empty;
  ++s.status.replacements;
  s.unpublished.push_back(Clock::now());  // the moved map is published at the next turn
}

}  // namespace objmap::pipeline

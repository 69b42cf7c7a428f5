#pragma once
#include <cstddef>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "objmap/core/clock.h"
#include "objmap/fusion/record_cache.h"
#include "objmap/geometry/backproject.h"
#include "objmap/io/dataset.h"
#include "objmap/io/trajectory_tail.h"
#include "objmap/pipeline/dense_snapshot.h"
#include "objmap/pipeline/follow.h"
#include "objmap/pipeline/follow_detect.h"
#include "objmap/pipeline/fuse_keyframes.h"
#include "objmap/pipeline/fuse_maps.h"
#include "objmap/pipeline/packed_pixels.h"
#include "objmap/scene/scene.h"
#include "objmap/segmentation/class_sizes.h"
#include "objmap/segmentation/read.h"

// The steps of objmap follow (follow.cpp is their outline) and what carries from poll to poll.
namespace objmap::pipeline {

// A keyframe selected and not yet fused, with the time its frame was first seen.
struct WaitingKeyframe {
  Keyframe keyframe;
  Clock::time_point arrived;
};

// A keyframe mapped, kept for a loop closure: its observations as they were added, without their
// points, which are kept as the pixels they came from (made again with the keyframe's new pose; in
// FollowState::kept_pixels), and its thinned depth for the view log.
struct KeptKeyframe {
  Keyframe keyframe;
  std::vector<fusion::Observation> observations;  // points_in_world empty
  std::vector<PackedPixelFile::Entry> pixels;     // per observation
  cv::Mat view_depth;
};

// A publish's end: the objects of its map, when that map was renamed into place (the moment a
// reader sees it: the lag's end) and the keyframes of the dense map its up and surfaces were found
// on (fewer than its own when they are those of the publish before: start_publish).
struct PublishDone {
  std::size_t objects = 0;
  Clock::time_point committed;
  std::size_t scene_keyframes = 0;
  bool scene_complete = true;  // the up and surfaces of its own dense map
};

// A report's end: its time, or what went wrong (one line).
struct ReportDone {
  double seconds = 0.0;
  std::string error;
};

struct FollowState {
  FollowOptions options;  // options.fuse with dataset, out (OUT/map), trajectory, segmentation set
  FuseChoices choices;
  segmentation::ClassSizes class_sizes;
  Clock::time_point started = Clock::now();
  io::Dataset dataset;                       // the recording as last read
  std::unique_ptr<io::TrajectoryTail> tail;  // --trajectory; null: the layout's own poses
  Trajectory trajectory;                     // the poses as last read
  std::vector<Clock::time_point> arrived;    // each frame's first sighting
  std::vector<std::pair<double, std::filesystem::path>>
      segmentation;                          // DATASET/segmentation's frames, sorted
  segmentation::ReadOptions read;            // how they are read (the camera's image size)
  std::size_t with_seg = 0;                  // keyframes fused with a segmentation frame
  std::unique_ptr<LatestDetector> detector;  // --model
  std::set<double> skipped;                  // keyframes the detector did not reach
  std::map<double, segmentation::FrameSegmentation> detected;  // taken, not yet fused
  FuseResult result;                            // the camera, counts and keyframes fused so far
  std::optional<FuseMaps> maps;                 // made once the camera is known
  std::optional<DenseSnapshot> dense_snapshot;  // maps->dense's cloud, kept up to date
  // The records of the objects unchanged since a publish (maps->objects's).
  std::shared_ptr<fusion::RecordCache> record_cache = std::make_shared<fusion::RecordCache>();
  // The merge pass's pair scores of objects unchanged since a publish (maps->objects's).
  std::shared_ptr<fusion::PairCache> pair_cache = std::make_shared<fusion::PairCache>();
  // The duplicate check's surface contacts of clouds unchanged since a publish.
  std::shared_ptr<fusion::ContactCache> contact_cache = std::make_shared<fusion::ContactCache>();
  std::optional<geometry::RayTable> rays;
  // The keyframes decoding ahead (on s.options.fuse, result.camera, rays, maps->dense): declared
  // after them, so that its workers stop before they go.
  std::unique_ptr<LiveKeyframes> live;
  double retried_timestamp = -1.0;  // the keyframe whose read failed last
  std::deque<KeptKeyframe> kept;    // every keyframe mapped (loop closures; never copied)
  std::unique_ptr<PackedPixelFile> kept_pixels;  // their pixels, in OUT (made with the first)
  bool rewrite_pending = false;           // the trajectory's past poses changed since the last turn
  std::size_t empty_by_add = 0;           // instances_empty counted by the association
  std::vector<WaitingKeyframe> waiting;   // selected, not yet fused, in order
  std::optional<Keyframe> last_keyframe;  // the motion rule's reference
  std::vector<Clock::time_point> unpublished;  // arrival of the keyframes fused since the publish
  Clock::time_point last_news = Clock::now();  // last new frame or pose
  Clock::time_point last_publish = Clock::now();  // the last publish's start
  // The publish in flight: when it is done, its objects and the moment its map was in place.
  std::future<PublishDone> publishing;
  // The dense cloud's update on a thread of its own, and the up and surfaces of that cloud on
  // another (the next publish's: start_publish); each one at a time, waiting for the one before.
  std::future<void> dense_apply;
  std::future<void> scene_making;
  // The up and surfaces of the last publish's dense cloud (scene_making's), for the next publish.
  std::shared_future<std::shared_ptr<const scene::SceneGraph>> scene;
  std::size_t scene_keyframes = 0;  // the keyframes of the dense map `scene` is found on
  Clock::time_point scene_started;  // the start of the publish whose cloud `scene` is found on
  bool scene_complete = true;       // the last publish's up and surfaces were of its dense map
  std::vector<Clock::time_point> publishing_arrivals;  // the keyframes it brings in
  std::vector<double> lags;  // every published keyframe's lag (s), for the median
  Clock::time_point publish_started;
  // The report in flight (OUT/report), the publish it shows, and when the last one started.
  std::future<ReportDone> reporting;
  std::size_t reporting_publish = 0;
  std::optional<Clock::time_point> last_report;
  FollowStatus status;
};

// 0. The options checked, OUT made ready, the state's fuse options and trajectory source set.
FollowState start_follow(const FollowOptions& options);

// 1. The recording read again: its frames (new ones stamped with their arrival), the trajectory,
//    the segmentation's frame list. Returns true when something is new. Throws InputError when
//    the recording folder is gone.
bool read_recording(FollowState& s, const FollowEvents& events);

// 2. The frames whose pose is now known (or, with `ending`, every frame) decided: posed or not,
//    keyframe or not (fuse's motion rule, keyframe by keyframe).
void select_new_keyframes(FollowState& s, bool ending);

// 3. The waiting keyframes fused in order into the live maps, each once its segmentation frame
//    is there (or a later one is, or `ending`); a keyframe whose files do not decode yet is
//    retried at the next poll (dropped with a warning when `ending`).
void fuse_waiting_keyframes(FollowState& s, bool ending, const FollowEvents& events);

// 3b. A keyframe mapped kept for a loop closure (follow_replace.cpp).
void keep_for_replacing(FollowState& s, const Keyframe& keyframe,
                        std::vector<fusion::Observation> observations,
                        std::vector<PackedPixelRuns> pixels, const cv::Mat& view_depth);

// 3c. After a loop closure (the trajectory's past poses changed), the kept keyframes' observations
//     made again from their pixels with their new poses and the object map made again from them (no
//     image read again).
void replace_after_loop_closure(FollowState& s);

// 4. A copy of the maps finished as objmap fuse finishes them, written to OUT/map through a
//    staging folder, on a thread of its own while the keyframes go on (start_publish); when it is
//    done (finish_publish, waiting for it with `wait`; false when none was done), OUT/status.json
//    with the lag. publish: every keyframe published, to its end (the one in flight may do if
//    its up and surfaces were of its own dense map). A publish takes the up and surfaces last
//    found, on the dense cloud of a publish before, off its way (found again every
//    scene_every_s); `own_scene` (the last publish) waits for those of its own. The `last`
//    publish takes the live object map and view log instead of copying them (none is fused after).
void start_publish(FollowState& s, bool own_scene = false, bool last = false);
bool finish_publish(FollowState& s, const FollowEvents& events, bool wait);
bool publish_done(const FollowState& s);  // a publish in flight has its map in place
void publish(FollowState& s, const FollowEvents& events);

// 5. OUT/report (objmap report) of the map just published, on a thread of its own, when none is
//    in flight and report_every_s seconds have passed since the last one started: the report
//    reads hard links of OUT/map's files (the next publish replaces OUT/map meanwhile) and the
//    trajectory as follow has read it (its file is still being written). finish_report: its end
//    taken (waiting for it with `wait`), a failure a warning. report_last_map: at the end, the
//    report of the last map unless OUT/report shows it (follow_report.cpp).
void start_report_if_due(FollowState& s, const FollowEvents& events);
void finish_report(FollowState& s, const FollowEvents& events, bool wait);
void report_last_map(FollowState& s, const FollowEvents& events);

// OUT/status.json from s.status (atomically), its time and peak memory updated.
void write_status(FollowState& s);

}  // namespace objmap::pipeline

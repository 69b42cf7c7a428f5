#pragma once
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>

#include "objmap/pipeline/fuse.h"

// `objmap follow`: the map of a recording kept up to date while the recording is written
// (docs/follow.md). The recording folder is polled; each new frame with a pose is a keyframe or
// not by fuse's motion rule, each keyframe is fused into the live maps as it arrives (with its
// segmentation frame from DATASET/segmentation, or the instances a detector thread found on the
// newest keyframe with --model), and every publish_every_s seconds a copy of the maps is finished
// as `objmap fuse` finishes its maps (merges, filters, scene) and written to OUT/map through a
// staging folder and a rename; OUT/report is made again from a published map every
// report_every_s seconds; OUT/status.json says how far it got. When the trajectory's past
// poses change (a loop closure) the mapped observations are moved with them. It ends on
// DATASET/done or idle_exit_s without a new frame, with a last publish of everything.
namespace objmap::pipeline {

struct FollowOptions {
  std::filesystem::path dataset;     // the recording being written (any layout objmap reads)
  std::filesystem::path out;         // OUT: new, empty, or an earlier follow (status.json)
  std::filesystem::path trajectory;  // a TUM trajectory that grows; empty: the layout's poses
  // An instance segmentation model (objmap detect's): run on the newest keyframe whenever it is
  // free. Empty: the instances are read from DATASET/segmentation as they are written.
  std::filesystem::path model;
  std::string layout = "auto";   // the recording's layout (io/dataset.h)
  std::string camera;            // empty: camera.json, folder name or rgb.txt header
  double publish_every_s = 0.5;  // seconds between publish starts (when something is new)
  double idle_exit_s = 0.0;      // > 0: ends after this long without a new frame or pose
  double poll_s = 0.02;          // seconds between polls of the recording folder
  // OUT/report (objmap report of the map) made again, on a thread of its own, from a publish at
  // least this many seconds after the last report started, and from the last publish; 0: only
  // from the last.
  double report_every_s = 10.0;
  // The up direction and surfaces (the scene step: 0.2–0.5 s of a core on a dense map of millions
  // of points) found again, on a publish's dense cloud, for the publishes after it, when this many
  // seconds have passed since they were last found; 0: on every publish's cloud. The last publish
  // finds its own.
  double scene_every_s = 2.0;
  FuseOptions fuse;    // the fuse's options (dataset, out, trajectory set from above)
  void check() const;  // throws InputError naming the bad field
};

// OUT/status.json (schemas/follow_status.schema.json).
struct FollowStatus {
  std::string state = "waiting";   // waiting (no frame yet), following, finished
  std::string ended_by;            // finished: "done file" or "idle"
  std::size_t frames_seen = 0;     // frames of the recording read so far
  std::size_t frames_decided = 0;  // frames whose pose (or its absence) is known
  std::size_t frames_with_pose = 0;
  std::size_t keyframes_mapped = 0;       // fused into the live maps
  std::size_t keyframes_waiting = 0;      // selected, waiting for their segmentation or files
  std::size_t keyframes_dropped = 0;      // files that never decoded by the end
  std::size_t frames_skipped_detect = 0;  // keyframes the detector could not reach (--model)
  std::size_t frame_retries = 0;          // keyframe reads that failed and were retried
  std::size_t dataset_retries = 0;        // polls where the recording could not be read
  std::size_t trajectory_lines = 0;       // complete data lines of the trajectory
  std::size_t trajectory_malformed = 0;   // of them malformed: named, skipped
  std::size_t trajectory_rewrites = 0;    // polls that found past lines changed
  std::size_t replacements = 0;           // object maps made again with moved observations
  std::size_t publishes = 0;
  std::size_t objects = 0;            // in the last published map
  double lag_last_s = 0.0;            // last publish: the longest wait of a keyframe it brought in
  double lag_max_s = 0.0;             // the longest over all publishes
  double lag_median_s = 0.0;          // the median over every keyframe published so far
  double fuse_seconds = 0.0;          // spent fusing keyframes into the live maps
  double publish_seconds_last = 0.0;  // the last publish's time (finish and write the map)
  // The last publish: the keyframes of the dense map its up and surfaces were found on (those of
  // the publish before, made meanwhile; the last publish's are its own).
  std::size_t scene_keyframes = 0;
  std::size_t reports = 0;           // OUT/report made
  std::size_t report_publish = 0;    // the publish OUT/report shows (0: none yet)
  double report_seconds_last = 0.0;  // the last report's time
  double seconds = 0.0;              // since the start
  long peak_rss_kb = 0;
  // The pixels of the observations kept for a loop closure (docs/follow.md, "Memory"): the part
  // of follow's memory that grows with the recording's keyframes rather than with the map.
  long kept_pixels_kb = 0;
};

// What the command prints as it goes: a warning line (a malformed trajectory line, a frame
// retried) or a publish (`status` after it).
struct FollowEvents {
  std::function<void(const std::string& line)> warning;
  std::function<void(const FollowStatus& status)> published;
};

// Follows the recording until it ends. Throws InputError for bad input: an OUT that is not
// replaceable, a camera it cannot choose, the recording folder removed while following (OUT/map
// keeps the last published map).
FollowStatus run_follow(const FollowOptions& options, const FollowEvents& events = {});

}  // namespace objmap::pipeline

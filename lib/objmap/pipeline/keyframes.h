#pragma once
#include <string>
#include <vector>

#include "objmap/core/trajectory.h"
#include "objmap/io/tum_dataset.h"

namespace objmap::pipeline {

// Which frames are fused. With ORB-SLAM2's KeyFrameTrajectory.txt the frames that have a pose are
// its keyframes; a per-frame trajectory (CameraTrajectory.txt, groundtruth.txt) is thinned by
// motion, as a keyframe-based SLAM system would, or by a fixed stride.
struct KeyframeOptions {
  double max_diff_s = 0.02;         // a frame has a pose when one is within this many seconds
  std::string mode = "auto";        // auto | all | motion | stride. auto: "all" when the trajectory
                                    // gives a pose to at most half of the frames (a keyframe file),
                                    // else "motion"
  double min_translation_m = 0.05;  // motion: a new keyframe after this much translation ...
  double min_rotation_deg = 5.0;    // ... or this much rotation since the last keyframe
  int stride = 1;                   // stride: every stride-th frame that has a pose
  // auto: when motion keeps fewer keyframes than this (a short clip of a camera that hardly
  // moves), every frame that has a pose is a keyframe. fuse: the observations an object needs.
  std::size_t min_keyframes = 1;
  void check() const;  // throws InputError naming the bad field
};

struct Keyframe {
  std::size_t frame = 0;   // index into Dataset::frames
  double timestamp = 0.0;  // rgb timestamp
  Pose world_from_cam = Pose::Identity();
};

struct KeyframeSelection {
  std::vector<Keyframe> keyframes;
  std::size_t frames_with_pose = 0;
  std::string mode;    // the mode used (auto resolved)
  std::string reason;  // auto: why that mode, e.g. "a pose for 58 of 1227 frames"
  // The posed frames' motion keeps fewer keyframes than min_keyframes (whatever the mode): the
  // camera is still (auto then uses every posed frame; fuse counts each frame as a view).
  bool still_camera = false;
};

// Throws InputError naming the trajectory when no frame has a pose.
KeyframeSelection select_keyframes(const io::Dataset& dataset, const Trajectory& trajectory,
                                   const KeyframeOptions& options);

}  // namespace objmap::pipeline

#include "objmap/pipeline/keyframes.h"

#include <cmath>
#include <cstdio>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/io/trajectory.h"

namespace objmap::pipeline {

void KeyframeOptions::check() const {
  require(std::isfinite(max_diff_s) && max_diff_s > 0 && max_diff_s < 1, "keyframes.max_diff_s",
          "must be in (0, 1) s");
  require(mode == "auto" || mode == "all" || mode == "motion" || mode == "stride", "keyframes.mode",
          "'" + mode + "'; expected auto, all, motion or stride");
  require(std::isfinite(min_translation_m) && min_translation_m >= 0, "keyframes.min_translation_m",
          "must be >= 0");
  require(std::isfinite(min_rotation_deg) && min_rotation_deg >= 0, "keyframes.min_rotation_deg",
          "must be >= 0");
  require(stride >= 1, "keyframes.stride", "must be >= 1, got " + std::to_string(stride));
}

namespace {

std::string time_text(double t) {
  char text[64];
  std::snprintf(text, sizeof text, std::abs(t) < 1e11 ? "%.6f" : "%.6g", t);
  return text;
}

// No frame has a pose: the two time spans side by side, and a hint when the trajectory's
// timestamps look like another unit than seconds (nanoseconds, as many ROS tools write them).
InputError no_pose_error(const io::Dataset& dataset, const Trajectory& trajectory,
                         double max_diff_s) {
  char window[32];
  std::snprintf(window, sizeof window, "%g", max_diff_s);
  std::string text = "no pose within " + std::string(window) + " s of any of the " +
                     std::to_string(dataset.frames.size()) + " frames (";
  if (trajectory.empty()) {
    text += "no pose";
  } else {
    text += "poses " + time_text(trajectory.poses.front().timestamp) + " .. " +
            time_text(trajectory.poses.back().timestamp);
  }
  std::string hint;
  if (!dataset.frames.empty()) {
    const double first = dataset.frames.front().rgb_timestamp;
    text +=
        ", frames " + time_text(first) + " .. " + time_text(dataset.frames.back().rgb_timestamp);
    if (!trajectory.empty() && first > 0) {
      const double ratio = trajectory.poses.front().timestamp / first;
      for (const auto& [scale, unit] : {std::pair<double, const char*>{1e9, "nanoseconds"},
                                        {1e6, "microseconds"},
                                        {1e3, "milliseconds"}})
        if (ratio > scale / 3 && ratio < scale * 3) {
          hint = std::string(" in seconds (these look like ") + unit + ")";
          break;
        }
    }
  }
  return InputError(trajectory.source,
                    text + "); expected the trajectory of this sequence, timestamps" +
                        (hint.empty() ? " in seconds as in rgb.txt" : hint));
}

// The motion keyframes among `posed`: the first, then each frame that moved at least
// min_translation_m or turned at least min_rotation_deg since the last keyframe.
std::vector<Keyframe> motion_keyframes(const std::vector<Keyframe>& posed,
                                       const KeyframeOptions& options) {
  const double min_rotation_rad = options.min_rotation_deg * M_PI / 180.0;
  std::vector<Keyframe> kept{posed.front()};
  for (std::size_t i = 1; i < posed.size(); ++i) {
    const Pose last_from_this = kept.back().world_from_cam.inverse() * posed[i].world_from_cam;
    const double moved_m = last_from_this.translation().norm();
    const double turned_rad = Eigen::AngleAxisd(last_from_this.rotation()).angle();
    if (moved_m >= options.min_translation_m || turned_rad >= min_rotation_rad)
      kept.push_back(posed[i]);
  }
  return kept;
}

}  // namespace

KeyframeSelection select_keyframes(const io::Dataset& dataset, const Trajectory& trajectory,
                                   const KeyframeOptions& options) {
  options.check();
  io::PoseLookupOptions lookup;
  lookup.max_diff_s = options.max_diff_s;
  lookup.interpolate = true;

  // 1. Every frame that has a pose.
  std::vector<Keyframe> posed;
  for (std::size_t i = 0; i < dataset.frames.size(); ++i) {
    const double t = dataset.frames[i].rgb_timestamp;
    if (auto pose = io::lookup_pose(trajectory, t, lookup)) posed.push_back({i, t, *pose});
  }
  KeyframeSelection result;
  result.frames_with_pose = posed.size();
  if (posed.empty()) throw no_pose_error(dataset, trajectory, options.max_diff_s);

  // 2. The mode: a keyframe trajectory is used as it is.
  result.mode = options.mode;
  if (result.mode == "auto") {
    const bool keyframe_file = 2 * posed.size() <= dataset.frames.size();
    result.mode = keyframe_file ? "all" : "motion";
    result.reason = "a pose for " + std::string(keyframe_file ? "only " : "") +
                    std::to_string(posed.size()) + " of " + std::to_string(dataset.frames.size()) +
                    " frames: " + (keyframe_file ? "a keyframe trajectory" : "thinned by motion");
  }

  // 3. Motion: a new keyframe after enough translation or rotation since the last one. Computed
  //    whatever the mode: a camera whose motion keeps fewer keyframes than an object needs views
  //    is still (each frame then counts as a view, fusion::count_views).
  std::vector<Keyframe> moved = motion_keyframes(posed, options);
  result.still_camera = moved.size() < options.min_keyframes && moved.size() < posed.size();

  if (result.mode == "all") {
    result.keyframes = std::move(posed);
  } else if (result.mode == "stride") {
    for (std::size_t i = 0; i < posed.size(); i += options.stride)
      result.keyframes.push_back(posed[i]);
  } else if (options.mode == "auto" && result.still_camera) {
    // auto: a camera that hardly moves over a short clip leaves too few keyframes to confirm
    // anything; every posed frame is used then.
    result.reason = "motion kept " + std::to_string(moved.size()) + " of the " +
                    std::to_string(posed.size()) + " posed frames, fewer than the " +
                    std::to_string(options.min_keyframes) + " needed: every posed frame";
    result.mode = "all";
    result.keyframes = std::move(posed);
  } else {
    result.keyframes = std::move(moved);
  }
  return result;
}

}  // namespace objmap::pipeline

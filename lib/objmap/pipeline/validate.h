#pragma once
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "objmap/core/camera.h"

namespace objmap::pipeline {

// `objmap validate`: reads every input of a run the way `fuse` will and reports what it found, or
// throws InputError at the first thing that is wrong.
struct ValidateOptions {
  std::filesystem::path dataset;       // recording folder in any layout (io/dataset.h)
  std::string layout = "auto";         // its layout: auto (detected), a name or a layout JSON
  std::string topics;                  // rosbag: "COLOR,DEPTH" image topics (empty: chosen)
  std::filesystem::path trajectory;    // optional: TUM trajectory (world_from_cam)
  std::filesystem::path segmentation;  // optional: segmentation folder (any supported format)
  std::string camera;                  // empty: camera.json in the folder, else a preset by name
  std::string seg_format = "auto";     // segmentation format, or auto-detect
  double max_diff_s = 0.02;            // rgb/depth and frame/pose association window
  bool check_all_images = true;        // decode every image (false: only the first pair)
  void check() const;
};

struct TimeSpan {
  double first = 0.0;
  double last = 0.0;
  double duration() const { return last - first; }
};

struct DatasetSummary {
  std::size_t rgb_rows = 0;
  std::size_t depth_rows = 0;
  std::size_t pairs = 0;  // associated rgb/depth pairs
  bool rgb_only = false;  // the folder has rgb.txt but no depth.txt (a listing without images)
  TimeSpan frames_span;
  std::string recorded_from;      // "# file:" header of rgb.txt
  std::string layout;             // the layout read
  std::size_t dataset_poses = 0;  // the layout's own camera poses (0: none)
  std::size_t lost_poses = 0;     // frames dropped because their pose marks lost tracking
  Camera camera;
  std::string camera_reason;
  std::size_t images_checked = 0;  // pairs whose rgb and depth were decoded and checked

  // Trajectory (when given).
  bool has_trajectory = false;
  std::size_t poses = 0;
  TimeSpan trajectory_span;
  std::size_t frames_with_pose = 0;

  // Segmentation (when given).
  bool has_segmentation = false;
  std::string seg_format;
  std::size_t seg_frames = 0;
  std::size_t seg_frames_matched =
      0;  // segmentation frames whose timestamp is an associated rgb frame
  std::size_t instances = 0;
  std::size_t instances_with_mask = 0;
  std::size_t instances_with_track = 0;
  std::map<std::string, std::size_t> instances_per_class;
};

using Progress = std::function<void(std::size_t done, std::size_t total)>;

DatasetSummary validate_dataset(const ValidateOptions& options, const Progress& progress = {});

}  // namespace objmap::pipeline

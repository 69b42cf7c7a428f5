#include "objmap/pipeline/fuse_inputs.h"

#include <algorithm>
#include <string>

#include "objmap/core/clock.h"
#include "objmap/core/error.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/trajectory.h"

namespace objmap::pipeline {

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
  // Canonical JSON frames are read by the workers, one keyframe at a time; other formats whole
  // (segmentation_frames.h).
  result.seg_format = options.seg_format == "auto"
                          ? segmentation::detect_format(options.segmentation)
                          : options.seg_format;
  if (result.seg_format != "json") read.format = result.seg_format;
  in.seg_source = list_segmentation_frames(options.segmentation, result.seg_format, read);
  require(!in.seg_source.stamps.empty(), options.segmentation.string(),
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
  in.seg_of = match_segmentation_frames(in.seg_source.stamps, keyframes, in.with_seg);
  require(
      in.with_seg > 0, options.segmentation.string(),
      "no segmentation frame has the timestamp of one of the " + std::to_string(keyframes.size()) +
          " keyframes; expected files named by the rgb timestamps of " + options.dataset.string());
  result.times.push_back({"select keyframes", seconds_since(t0)});
  return in;
}

const segmentation::FrameSegmentation* keyframe_segmentation(
    const FuseInputs& in, std::size_t i, segmentation::FrameSegmentation& lazy) {
  return segmentation_frame(in.seg_source, in.read, in.seg_of[i], lazy);
}

}  // namespace objmap::pipeline

#include "objmap/pipeline/validate.h"

#include <algorithm>
#include <cmath>

#include "objmap/core/error.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/image.h"
#include "objmap/io/text_lines.h"
#include "objmap/io/trajectory.h"
#include "objmap/io/tum_dataset.h"
#include "objmap/segmentation/read.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

void ValidateOptions::check() const {
  require(!dataset.empty(), "--dataset", "missing; expected a TUM RGB-D folder");
  require(std::isfinite(max_diff_s) && max_diff_s > 0.0 && max_diff_s < 1.0, "--max-diff",
          "must be in (0, 1) s, got " + std::to_string(max_diff_s));
}

namespace {

std::string span_text(const TimeSpan& s) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.6f .. %.6f", s.first, s.last);
  return buf;
}

// Index of the frame whose rgb timestamp is nearest to t, when within tolerance.
std::optional<std::size_t> nearest_frame(const std::vector<double>& sorted_stamps, double t,
                                         double tolerance) {
  auto it = std::lower_bound(sorted_stamps.begin(), sorted_stamps.end(), t);
  std::optional<std::size_t> best;
  double best_diff = tolerance;
  for (auto c : {it, it == sorted_stamps.begin() ? it : it - 1}) {
    if (c == sorted_stamps.end()) continue;
    const double diff = std::abs(*c - t);
    if (diff <= best_diff) {
      best_diff = diff;
      best = static_cast<std::size_t>(c - sorted_stamps.begin());
    }
  }
  return best;
}

}  // namespace

DatasetSummary validate_dataset(const ValidateOptions& options, const Progress& progress) {
  options.check();
  DatasetSummary s;

  // 1. The TUM folder: rgb.txt, depth.txt, association, files present. A folder with rgb.txt alone
  //    (a detection stream without images, such as the fr3_long_office annotations) is summarised
  //    on its rgb stamps.
  std::vector<double> stamps;
  const bool rgb_only = (options.layout == "auto" || options.layout == "tum") &&
                        !fs::exists(options.dataset / "depth.txt") &&
                        fs::exists(options.dataset / "rgb.txt");
  io::Dataset dataset;
  if (rgb_only) {
    io::LineReader in(options.dataset / "rgb.txt");
    while (in.next()) {
      in.expect_fields(2, "timestamp filename");
      const double t = in.number(0, "timestamp");
      require(stamps.empty() || t > stamps.back(), in.where(),
              "timestamp not after the previous one; expected increasing timestamps");
      stamps.push_back(t);
    }
    require(!stamps.empty(), (options.dataset / "rgb.txt").string(),
            "no image listed; expected lines 'timestamp filename'");
    s.rgb_only = true;
    s.rgb_rows = stamps.size();
    s.recorded_from = io::recorded_from_header(options.dataset / "rgb.txt");
    s.frames_span = {stamps.front(), stamps.back()};
  } else {
    dataset = io::read_dataset(options.dataset,
                               {options.layout, options.max_diff_s, 30.0, options.topics});
    s.layout = dataset.layout;
    s.dataset_poses = dataset.poses.size();
    s.lost_poses = dataset.lost_poses;
    s.rgb_rows = dataset.rgb_rows;
    s.depth_rows = dataset.depth_rows;
    s.pairs = dataset.frames.size();
    s.recorded_from = dataset.recorded_from;
    require(s.pairs > 0, options.dataset.string(),
            "no rgb/depth pair within " + std::to_string(options.max_diff_s) +
                " s; expected associated rgb.txt and depth.txt");
    s.frames_span = {dataset.frames.front().rgb_timestamp, dataset.frames.back().rgb_timestamp};
    for (const auto& f : dataset.frames) stamps.push_back(f.rgb_timestamp);
  }

  // 2. The camera: given, camera.json in the folder, or a preset from the folder's name.
  const io::CameraChoice choice = rgb_only ? io::choose_camera(options.dataset, options.camera)
                                           : io::choose_camera(dataset, options.camera);
  s.camera = choice.camera;
  s.camera_reason = choice.reason;

  // 3. The images: decodable, the camera's size, 16-bit single-channel depth.
  const std::size_t to_check =
      rgb_only ? 0 : (options.check_all_images ? dataset.frames.size() : 1);
  for (std::size_t i = 0; i < to_check; ++i) {
    const auto& f = dataset.frames[i];
    io::read_frame_rgb(dataset, f, s.camera.width, s.camera.height);
    io::read_frame_depth(dataset, f, s.camera);
    ++s.images_checked;
    if (progress) progress(i + 1, to_check);
  }

  // 4. The trajectory: which frames have a pose.
  if (!options.trajectory.empty()) {
    const Trajectory trajectory = io::read_trajectory(options.trajectory);
    require(!trajectory.empty(), options.trajectory.string(),
            "no pose; expected rows 'timestamp tx ty tz qx qy qz qw'");
    s.has_trajectory = true;
    s.poses = trajectory.size();
    s.trajectory_span = {trajectory.poses.front().timestamp, trajectory.poses.back().timestamp};
    io::PoseLookupOptions lookup;
    lookup.max_diff_s = options.max_diff_s;
    for (double t : stamps)
      if (io::lookup_pose(trajectory, t, lookup)) ++s.frames_with_pose;
    require(s.frames_with_pose > 0, options.trajectory.string(),
            "overlaps no frame: poses span " + span_text(s.trajectory_span) + ", frames span " +
                span_text(s.frames_span) + "; expected a trajectory of this sequence");
  }

  // 5. The segmentation: format, frames matched to rgb frames, instances per class.
  if (!options.segmentation.empty()) {
    segmentation::ReadOptions read;
    read.format = options.seg_format;
    read.image_width = s.camera.width;
    read.image_height = s.camera.height;
    const segmentation::Segmentation seg =
        segmentation::read_segmentation(options.segmentation, read);
    s.has_segmentation = true;
    s.seg_format = seg.format;
    s.seg_frames = seg.frames.size();
    require(s.seg_frames > 0, options.segmentation.string(),
            "no segmentation frame; expected one file per rgb frame");
    for (const auto& frame : seg.frames) {
      if (nearest_frame(stamps, frame.timestamp, 1e-3)) ++s.seg_frames_matched;
      for (const auto& inst : frame.instances) {
        ++s.instances;
        if (inst.mask) ++s.instances_with_mask;
        if (inst.track_id) ++s.instances_with_track;
        ++s.instances_per_class[inst.class_name];
      }
    }
    require(s.seg_frames_matched > 0, options.segmentation.string(),
            "no segmentation frame has the timestamp of an rgb frame of " +
                options.dataset.string() + "; expected files named by rgb timestamp");
  }
  return s;
}

}  // namespace objmap::pipeline

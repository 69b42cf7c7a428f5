// objmap validate: reads a dataset, trajectory and segmentation the way fuse will and prints a
// summary.
#include <cstdio>
#include <memory>

#include "command.h"
#include "objmap/pipeline/validate.h"
#include "progress.h"

namespace objmap::app {
namespace {

void run_validate(const pipeline::ValidateOptions& options) {
  std::unique_ptr<ProgressBar> bar;
  const auto summary =
      pipeline::validate_dataset(options, [&](std::size_t done, std::size_t total) {
        if (!bar) bar = std::make_unique<ProgressBar>("images", total);
        bar->update(done);
      });
  if (bar) bar->finish();

  const auto& s = summary;
  const std::size_t n_frames = s.rgb_only ? s.rgb_rows : s.pairs;
  std::printf("dataset       %s%s%s\n", options.dataset.c_str(),
              s.layout.empty() ? "" : (" (" + s.layout + " layout)").c_str(),
              s.recorded_from.empty() ? "" : (" (recorded from " + s.recorded_from + ")").c_str());
  if (s.dataset_poses > 0)
    std::printf("poses         %zu of the recording's own (%zu frames dropped: lost tracking)\n",
                s.dataset_poses, s.lost_poses);
  if (s.rgb_only)
    std::printf("frames        %zu rgb, no depth.txt (a listing without images: not checked)\n",
                s.rgb_rows);
  else
    std::printf("frames        %zu rgb, %zu depth, %zu associated pairs (max diff %.3f s)\n",
                s.rgb_rows, s.depth_rows, s.pairs, options.max_diff_s);
  std::printf("time span     %.6f .. %.6f (%.2f s, %.1f Hz)\n", s.frames_span.first,
              s.frames_span.last, s.frames_span.duration(),
              s.frames_span.duration() > 0 ? (n_frames - 1) / s.frames_span.duration() : 0.0);
  std::printf("camera        %s: fx %.3f fy %.3f cx %.3f cy %.3f, %dx%d, depth factor %g%s\n",
              s.camera.name.c_str(), s.camera.fx, s.camera.fy, s.camera.cx, s.camera.cy,
              s.camera.width, s.camera.height, s.camera.depth_factor,
              s.camera.has_distortion() ? ", distortion" : "");
  std::printf("              (%s)\n", s.camera_reason.c_str());
  std::printf("images        %zu of %zu pairs decoded and checked\n", s.images_checked, s.pairs);
  if (s.has_trajectory) {
    std::printf("trajectory    %s: %zu poses, %.6f .. %.6f\n", options.trajectory.c_str(), s.poses,
                s.trajectory_span.first, s.trajectory_span.last);
    std::printf("coverage      %zu of %zu frames have a pose within %.3f s (%.1f%%)\n",
                s.frames_with_pose, n_frames, options.max_diff_s,
                100.0 * s.frames_with_pose / static_cast<double>(n_frames));
  }
  if (s.has_segmentation) {
    std::printf("segmentation  %s: format %s, %zu frames, %zu of them rgb frames of the dataset\n",
                options.segmentation.c_str(), s.seg_format.c_str(), s.seg_frames,
                s.seg_frames_matched);
    std::printf("instances     %zu (%zu with a mask, %zu with a track id)\n", s.instances,
                s.instances_with_mask, s.instances_with_track);
    for (const auto& [name, count] : s.instances_per_class)
      std::printf("  %-20s %zu\n", name.c_str(), count);
  }
  std::printf("ok\n");
}

void setup_validate(CLI::App& app) {
  auto options = std::make_shared<pipeline::ValidateOptions>();
  auto* cmd = app.add_subcommand(
      "validate",
      "Check a TUM RGB-D folder, a trajectory and a segmentation the way 'fuse' reads them, and "
      "print "
      "a summary (frames, associated pairs, time span, camera, trajectory and segmentation "
      "coverage, "
      "instances per class). Exit 2 with one line at the first thing that is wrong.");
  cmd->add_option("--dataset", options->dataset, kDatasetHelp)->required();
  cmd->add_option("--layout", options->layout, kLayoutHelp)->capture_default_str();
  cmd->add_option("--topics", options->topics, kTopicsHelp);
  cmd->add_option("--trajectory", options->trajectory,
                  "trajectory in TUM format (t tx ty tz qx qy qz qw, world_from_cam)");
  cmd->add_option("--segmentation", options->segmentation,
                  "segmentation folder (canonical JSON, PNG instance images, paper txt, box txt)");
  cmd->add_option("--camera", options->camera,
                  "preset fr1|fr2|fr3, an ORB-SLAM2 settings .yaml or a camera .json; default: "
                  "camera.json in the dataset, else from the folder name or rgb.txt header");
  cmd->add_option("--seg-format", options->seg_format,
                  "auto|json|png|txt-paper|boxes-named|boxes-coco|boxes-xywh")
      ->capture_default_str();
  cmd->add_option("--max-diff", options->max_diff_s, "association window in seconds")
      ->capture_default_str();
  cmd->add_flag("!--quick", options->check_all_images,
                "decode only the first image pair instead of all");
  cmd->callback([options] { run_validate(*options); });
}

}  // namespace

OBJMAP_COMMAND(10, "validate", setup_validate);

}  // namespace objmap::app

// objmap fuse: the object-oriented semantic map from a trajectory, RGB-D frames and instances.
#include <cstdio>
#include <memory>

#include "command.h"
#include "config_flags.h"
#include "objmap/pipeline/correct.h"
#include "objmap/pipeline/fuse.h"
#include "progress.h"

namespace objmap::app {
namespace {

void print_summary(const pipeline::FuseOptions& options, const pipeline::FuseResult& r) {
  for (const auto& w : r.warnings) std::fprintf(stderr, "objmap: warning: %s\n", w.c_str());
  std::printf("camera      %s (%s)\n", r.camera.name.c_str(), r.camera_reason.c_str());
  const auto& kf = r.keyframes;
  std::printf("keyframes   %zu of %zu frames (%zu with a pose; mode %s%s%s)\n", kf.keyframes.size(),
              r.frames, kf.frames_with_pose, kf.mode.c_str(), kf.reason.empty() ? "" : ": ",
              kf.reason.c_str());
  if (kf.keyframes.size() < static_cast<std::size_t>(options.objects.min_observations))
    std::printf(
        "            only %zu keyframe(s): an object needs %d observations to be "
        "confirmed (--keyframes all, or a smaller --kf-translation / --kf-rotation)\n",
        kf.keyframes.size(), options.objects.min_observations);
  std::printf(
      "instances   %zu (format %s; %zu masks from boxes, %zu given masks refined (-%llu pixels), "
      "%zu depth-gated (-%llu pixels), %zu duplicates dropped, %zu without usable points, %zu on "
      "another of their class)\n",
      r.instances_seen, r.seg_format.c_str(), r.instances_from_box, r.instances_refined,
      static_cast<unsigned long long>(r.mask_pixels_removed), r.instances_depth_gated,
      static_cast<unsigned long long>(r.depth_gate_pixels_removed), r.instances_duplicate,
      r.instances_empty, r.instances_bleed);
  // A run that cannot have objects says why, rather than leaving an empty table to puzzle over.
  if (r.instances_seen == 0)
    std::printf(
        "            none in the keyframes' segmentation frames: no objects, the dense map "
        "only\n");
  else if (r.instances_skipped_score == r.instances_seen)
    std::printf("            all %zu below --min-score %g: no objects, the dense map only\n",
                r.instances_seen, options.min_instance_score);
  std::printf("objects     %zu confirmed of %zu (%zu merged by the final pass", r.objects.size(),
              r.objects_total, r.merges.size());
  if (r.objects_below_share > 0)
    std::printf("; %zu detected in under %.0f%% of the keyframes that had them in view",
                r.objects_below_share, 100.0 * r.detected_share_bar);
  std::printf(")\n");
  if (!r.duplicates.pairs.empty())
    std::printf("            suspected duplicates: %zu (run.json \"duplicates\", objmap report)\n",
                r.duplicates.pairs.size());
  std::printf("\n  %4s  %-16s %9s %9s %9s  %8s  %5s\n", "id", "class", "x", "y", "z", "points",
              "obs");
  for (const auto& o : r.objects)
    std::printf("  %4d  %-16s %9.3f %9.3f %9.3f  %8zu  %5d\n", o.id, o.class_name.c_str(),
                o.centroid.x(), o.centroid.y(), o.centroid.z(), o.points_filtered, o.observations);
  const auto pct = [](double before, double after) {
    return before > 0 ? 100.0 * (1.0 - after / before) : 0.0;
  };
  if (options.dense_map)
    std::printf(
        "\npoints      dense: %llu back-projected -> %zu in the map (1 voxel = 1 point; %llu noise "
        "voxels pruned)\n",
        static_cast<unsigned long long>(r.dense_points_raw), r.dense_points_map,
        static_cast<unsigned long long>(r.dense_voxels_pruned));
  else
    std::printf("\npoints      dense: none (--dense-map false)\n");
  std::printf("            objects: %zu -> %zu voxel-filtered -> %zu outlier-filtered (-%.1f%%)\n",
              r.object_points_raw, r.object_points_voxel, r.object_points_filtered,
              pct(r.object_points_raw, r.object_points_filtered));
  const std::size_t n_kf = kf.keyframes.size();
  std::printf("time        %.2f s (%.1f ms per keyframe), peak memory %.0f MB\n", r.seconds_total,
              n_kf ? 1000.0 * r.seconds_total / n_kf : 0.0, r.peak_rss_kb / 1024.0);
  std::printf("written     %s/{objects.json, objects/, %smap_objects.ply, run.json}\n",
              options.out.c_str(), options.dense_map ? "map_dense.ply, map_semantic.ply, " : "");
}

void setup_fuse(CLI::App& app) {
  auto options = std::make_shared<pipeline::FuseOptions>();
  auto config = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "fuse",
      "Build the object-oriented semantic map (paper 3.2-3.3): back-project the keyframes "
      "(given masks cleaned of spill and of depth off the object's band), associate each "
      "instance with an object by track ID, centroid distance and voxel overlap (eq 22), "
      "confirm objects seen from >= 3 viewpoints, filter outliers (eq 18); --method paper: the "
      "paper's rules as it states them (docs/fusion.md). Writes "
      "OUT/objects.json, "
      "OUT/objects/<id>_<class>.ply, OUT/map_dense.ply, OUT/map_semantic.ply, OUT/map_objects.ply, "
      "OUT/run.json (the two dense maps not with --dense-map false).");
  cmd->add_option("--dataset", options->dataset, kDatasetHelp)->required();
  cmd->add_option("--layout", options->layout, kLayoutHelp)->capture_default_str();
  cmd->add_option("--topics", options->topics, kTopicsHelp);
  cmd->add_option(
      "--trajectory", options->trajectory,
      "trajectory, TUM format (ORB-SLAM2 KeyFrameTrajectory.txt / CameraTrajectory.txt, "
      "groundtruth.txt); optional where the recording carries its own poses (7-Scenes, ScanNet, "
      "Replica, Open3D, generic): they are used and copied to OUT/dataset_trajectory.txt");
  cmd->add_option("--segmentation", options->segmentation,
                  "segmentation folder (canonical JSON, PNG instance images, paper txt, box txt)")
      ->required();
  cmd->add_option("--out", options->out,
                  "run folder to write (an earlier run there is replaced when complete; any other "
                  "folder is refused)")
      ->required();
  cmd->add_option(
      "--camera", options->camera,
      "preset fr1|fr2|fr3, ORB-SLAM2 .yaml or camera .json (default: camera.json in the "
      "dataset, else from the folder name or rgb.txt header)");
  cmd->add_option("--config", *config,
                  "JSON file with any of the options below (keys as in run.json 'options'); flags "
                  "given on the command line win");
  auto correct = std::make_shared<bool>(false);
  auto correct_method = std::make_shared<std::string>("graph");
  cmd->add_flag("--correct-poses", *correct,
                "fuse, correct the keyframe poses with the objects (objmap correct), fuse again: "
                "OUT also gets trajectory_corrected.txt and correction.json");
  auto* correct_method_opt =
      cmd->add_option("--correct-method", *correct_method,
                      "with --correct-poses: graph or paper (default with --method paper: paper)")
          ->check(CLI::IsMember({"graph", "paper"}))
          ->capture_default_str();
  auto flags = std::make_shared<ConfigFlags>(
      cmd, [](pipeline::FuseOptions& o) { return pipeline::fuse_config_fields(o); }, *options);
  cmd->callback([options, config, flags, correct, correct_method, correct_method_opt] {
    flags->apply_config(*config, *options);
    // --method paper: the paper's value of every option not given (as a flag or in --config).
    check_naming_flags([&] { flags->apply_preset(*options, pipeline::set_method_preset); },
                       {{"method", "method (--method)"}});
    if (options->method == "paper" && correct_method_opt->count() == 0) *correct_method = "paper";
    flags->check(*options);
    std::unique_ptr<ProgressBar> bar;
    std::size_t last = 0;
    const auto progress = [&](std::size_t done, std::size_t total) {
      if (!bar || done < last) {  // a new pass (--correct-poses fuses twice)
        if (bar) bar->finish();
        bar = std::make_unique<ProgressBar>("fuse", total, "keyframes");
      }
      last = done;
      bar->update(done);
    };
    if (*correct) {
      pipeline::CorrectOptions co;
      co.correction.method = *correct_method;
      co.threads = options->threads;
      const auto corrected = pipeline::run_fuse_and_correct(*options, co, progress);
      if (bar) bar->finish();
      if (corrected.refused_map) print_summary(*options, corrected.fuse);
      std::printf("correction  %s: %s\n", corrected.correction.method.c_str(),
                  corrected.reason.c_str());
      std::printf("written     %s/{trajectory_corrected.txt, correction.json}\n",
                  options->out.c_str());
      return;
    }
    const auto result = pipeline::run_fuse(*options, progress);
    if (bar) bar->finish();
    print_summary(*options, result);
  });
}

}  // namespace

OBJMAP_COMMAND(40, "fuse", setup_fuse);

}  // namespace objmap::app

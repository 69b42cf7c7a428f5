// objmap track: gives every instance of a segmentation a track id with DeepSORT (Kalman filter,
// Mahalanobis gate, colour appearance, matching cascade, IoU stage, Hungarian assignment), and
// writes the tracked segmentation in the canonical format plus tracks.json.
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "command.h"
#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/dataset.h"
#include "objmap/io/image.h"
#include "objmap/io/trajectory.h"
#include "objmap/segmentation/read.h"
#include "objmap/segmentation/write.h"
#include "objmap/track/track_segmentation.h"
#include "progress.h"

namespace objmap::app {
namespace {

namespace fs = std::filesystem;

struct TrackCommand {
  std::string dataset;
  std::string layout = "auto";
  std::string topics;
  std::string segmentation;
  std::string out;
  std::string seg_format = "auto";
  std::string trajectory;  // on: the 3D gate
  std::string camera;
  bool no_appearance = false;
  bool same_class = false;
  bool online_output = false;
  track::TrackOptions options;
  track::Position3dOptions position;
};

// What track did: the tracker's inputs and the tracks, on stdout.
void print_track_summary(const TrackCommand& cmd, const std::string& format,
                         const track::TrackResult& result, const std::string& camera_reason) {
  const track::TrackOptions& o = cmd.options;
  const track::LengthStats len = track::length_stats(result.tracks);
  std::map<std::string, int> per_class;
  for (const auto& t : result.tracks) ++per_class[t.class_name];
  std::printf("wrote         %s (%zu frame files, tracks.json)\n", cmd.out.c_str(), result.frames);
  std::printf("input         %s: format %s, %zu frames, %zu instances\n", cmd.segmentation.c_str(),
              format.c_str(), result.frames, result.instances);
  std::printf("appearance    %s\n", result.used_appearance ? "colour histograms of the rgb images"
                                    : cmd.no_appearance
                                        ? "off (--no-appearance): motion and IoU only"
                                        : "off (the dataset has no images): motion and IoU only");
  if (result.used_gate_3d) {
    std::printf(
        "3d gate       %.2f m (growing %.2f m/s after a 3D update; last %d positions), camera "
        "%s\n",
        o.tracker.gate_3d_m, o.tracker.gate_3d_speed_mps, o.tracker.gate_3d_history,
        camera_reason.c_str());
    std::printf("              %zu frames with a pose, %zu without (tracked without the gate)\n",
                result.frames_with_pose, result.frames_without_pose);
    std::printf(
        "              %zu of %zu instances with a 3D position (%zu through box masks; no box "
        "mask %zu, too few depth pixels %zu)\n",
        result.instances_with_position, result.instances, result.instances_mask_from_box,
        result.instances_no_mask_from_box, result.instances_few_depth_pixels);
  } else {
    std::printf("3d gate       off (no --trajectory)\n");
  }
  std::printf("tracks        %zu confirmed of %zu started (n_init %d, max_age %d)\n",
              result.tracks.size(), result.tracks_started, o.tracker.n_init, o.tracker.max_age);
  std::printf("instances     %zu of %zu with a track id (%.1f%%)\n", result.instances_tracked,
              result.instances,
              result.instances ? 100.0 * result.instances_tracked / result.instances : 0.0);
  if (len.count > 0)
    std::printf("length        mean %.1f, median %zu, min %zu, max %zu frames\n", len.mean,
                len.median, len.min, len.max);
  for (const auto& [name, n] : per_class) std::printf("  %-20s %d tracks\n", name.c_str(), n);
}

void run_track(TrackCommand& cmd) {
  track::TrackOptions& o = cmd.options;
  o.tracker.same_class_only = cmd.same_class;
  o.label_tentative_history = !cmd.online_output;
  check_naming_flags([&] { o.check(); },
                     {{"TrackerOptions.gate_3d_m", "--gate-3d-m"},
                      {"TrackerOptions.gate_3d_speed_mps", "--gate-3d-speed"},
                      {"TrackerOptions.gate_3d_history", "--gate-3d-history"},
                      {"TrackerOptions.max_age", "--max-age"},
                      {"TrackerOptions.n_init", "--n-init"},
                      {"TrackerOptions.max_cosine_distance", "--max-cosine-distance"},
                      {"TrackerOptions.lambda", "--lambda"},
                      {"TrackerOptions.max_iou_distance", "--max-iou-distance"},
                      {"TrackerOptions.min_score", "--min-score"},
                      {"KalmanOptions.std_weight_position", "--std-position"},
                      {"KalmanOptions.std_weight_velocity", "--std-velocity"}});
  io::require_not_an_input({"--out", cmd.out}, {{"--dataset", cmd.dataset},
                                                {"--segmentation", cmd.segmentation},
                                                {"--trajectory", cmd.trajectory},
                                                {"--camera", cmd.camera}});
  io::require_replaceable(cmd.out, io::kSegmentationFolder);  // before the work, not after it
  require(fs::is_directory(cmd.dataset) || io::is_rosbag_file(cmd.dataset), cmd.dataset,
          "no such folder; expected a recording folder (TUM rgb.txt, or another layout) or a ROS "
          "1 .bag");
  segmentation::ReadOptions read;
  read.format = cmd.seg_format;
  // The frames are read, tracked and written one at a time (a window of n_init frames in memory).
  const segmentation::FrameReader input(cmd.segmentation, read);
  std::vector<double> timestamps;
  for (const segmentation::FrameEntry& e : input.frames()) timestamps.push_back(e.timestamp);
  // A TUM folder gives every frame rgb.txt lists (it may hold rgb.txt alone); other layouts
  // their frames as fuse reads them.
  const bool listing = io::is_tum_listing(cmd.dataset, cmd.layout);
  std::optional<io::Dataset> dataset;
  if (!listing || !cmd.trajectory.empty())
    dataset = io::read_dataset(cmd.dataset, {cmd.layout, 0.02, 30.0, cmd.topics});
  const track::FrameImages images = listing ? track::find_frame_images(cmd.dataset, input.frames())
                                            : track::find_frame_images(*dataset, input.frames());
  // Appearance needs the rgb images; a stream of boxes without images is tracked on motion alone.
  o.tracker.use_appearance = !cmd.no_appearance && images.has_images;

  // The 3D gate: the instances' robust centroids from the depth images and the trajectory.
  o.tracker.use_gate_3d = !cmd.trajectory.empty();
  track::FramePositionsFn positions;
  std::string camera_reason;
  if (o.tracker.use_gate_3d) {
    const io::CameraChoice choice = io::choose_camera(*dataset, cmd.camera);
    camera_reason = choice.reason;
    const Trajectory trajectory = io::read_trajectory(cmd.trajectory);
    positions =
        track::depth_positions(*dataset, timestamps, trajectory, choice.camera, cmd.position);
  }

  io::StagingDir staging(cmd.out, io::kSegmentationFolder);
  segmentation::require_distinct_frame_names(staging.path(), timestamps);
  std::unique_ptr<ProgressBar> bar;
  const track::TrackResult result = track::track_stream(
      {cmd.segmentation, input.size(), [&](std::size_t i) { return input.read(i); }},
      [&](std::size_t, segmentation::FrameSegmentation&& frame) {
        segmentation::write_frame_json(
            staging.path() / segmentation::frame_file_name(frame.timestamp), frame);
      },
      o,
      [&](std::size_t i) {
        return listing ? io::read_rgb(images.files[i], 0, 0)
                       : io::read_frame_rgb(*dataset, dataset->frames[images.rows[i]], 0, 0);
      },
      [&](std::size_t done, std::size_t total) {
        if (!bar) bar = std::make_unique<ProgressBar>("track", total);
        bar->update(done);
      },
      positions);
  if (bar) bar->finish();
  io::write_file_atomic(staging.path() / "tracks.json", track::tracks_json(result));
  staging.commit();
  print_track_summary(cmd, input.format(), result, camera_reason);
}

void setup_track(CLI::App& app) {
  auto cmd = std::make_shared<TrackCommand>();
  track::TrackerOptions& t = cmd->options.tracker;
  auto* c = app.add_subcommand(
      "track",
      "Give the instances of a segmentation track ids with DeepSORT (Kalman filter on the box, "
      "Mahalanobis gate, colour appearance, matching cascade, IoU matching, Hungarian "
      "assignment). Writes the canonical segmentation with track_id and tracks.json.");
  c->add_option(
       "--dataset", cmd->dataset,
       std::string(kDatasetHelp) + "; a TUM folder may hold rgb.txt alone (appearance then off)")
      ->required();
  c->add_option("--layout", cmd->layout, kLayoutHelp)->capture_default_str();
  c->add_option("--topics", cmd->topics, kTopicsHelp);
  c->add_option("--segmentation", cmd->segmentation,
                "segmentation folder (any supported format; input track ids are ignored)")
      ->required();
  c->add_option("--out", cmd->out,
                "output segmentation folder (an earlier segmentation there is replaced; any other "
                "folder is refused)")
      ->required();
  c->add_option("--seg-format", cmd->seg_format,
                "auto|json|png|txt-paper|boxes-named|boxes-coco|boxes-xywh")
      ->capture_default_str();
  c->add_flag("--no-appearance", cmd->no_appearance,
              "match on motion (Mahalanobis) and IoU only, even when images exist");
  c->add_flag("--same-class", cmd->same_class,
              "a detection only joins a track of its own class (default: any class; the track's "
              "class is the majority vote)");
  c->add_flag("--online-output", cmd->online_output,
              "label only detections made while their track was confirmed (DeepSORT's online "
              "output); default: a confirmed track's first tentative detections too");
  c->add_option("--trajectory", cmd->trajectory,
                "camera trajectory (TUM format, world_from_cam): turns the 3D gate on (needs the "
                "depth images of --dataset)");
  c->add_option("--camera", cmd->camera,
                "camera for the 3D gate: preset fr1|fr2|fr3 or a .json/.yaml file (default: from "
                "the dataset, as fuse)");
  c->add_option("--gate-3d-m", t.gate_3d_m,
                "3D gate: a detection joins a track only within this distance (m) of the track's "
                "last 3D position")
      ->capture_default_str();
  c->add_option("--gate-3d-speed", t.gate_3d_speed_mps,
                "3D gate: the radius grows with this speed bound (m/s) times the time since the "
                "track's last 3D position")
      ->capture_default_str();
  c->add_option("--gate-3d-history", t.gate_3d_history,
                "3D gate: within the radius of any of the track's last N 3D positions")
      ->capture_default_str();
  c->add_option("--max-age", t.max_age, "frames a lost confirmed track survives")
      ->capture_default_str();
  c->add_option("--n-init", t.n_init, "hits to confirm a track")->capture_default_str();
  c->add_option("--max-cosine-distance", t.max_cosine_distance,
                "appearance threshold of the matching cascade")
      ->capture_default_str();
  c->add_option("--lambda", t.lambda,
                "weight of the Mahalanobis distance in the cascade cost (DeepSORT eq 5)")
      ->capture_default_str();
  c->add_option("--max-iou-distance", t.max_iou_distance, "IoU stage threshold on 1 - IoU")
      ->capture_default_str();
  c->add_option("--std-position", t.kalman.std_weight_position,
                "Kalman position noise std as a fraction of the box height")
      ->capture_default_str();
  c->add_option("--std-velocity", t.kalman.std_weight_velocity,
                "Kalman velocity noise std as a fraction of the box height")
      ->capture_default_str();
  c->add_option("--min-score", t.min_score, "detections below this score are not tracked")
      ->capture_default_str();
  c->callback([cmd] { run_track(*cmd); });
}

}  // namespace

OBJMAP_COMMAND(30, "track", setup_track);

}  // namespace objmap::app

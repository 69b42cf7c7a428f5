// objmap follow: the map of a recording kept up to date while it is written (docs/follow.md).
#include <algorithm>
#include <cstdio>
#include <memory>

#include "command.h"
#include "objmap/core/memory.h"
#include "objmap/pipeline/follow.h"
#include "objmap/pipeline/fuse_keyframes.h"

namespace objmap::app {
namespace {

void follow_and_print(const pipeline::FollowOptions& options) {
  pipeline::FollowEvents events;
  events.warning = [](const std::string& line) {
    std::fprintf(stderr, "warning: %s\n", line.c_str());
  };
  events.published = [](const pipeline::FollowStatus& s) {
    std::fprintf(stderr, "published     %zu objects, %zu keyframes of %zu frames, lag %.2f s\n",
                 s.objects, s.keyframes_mapped, s.frames_seen, s.lag_last_s);
  };
  // As many heaps as workers: freed memory kept in a heap per short-lived thread (the publishes',
  // the dense applies', the reports') is what grew follow's peak with the recording.
  limit_malloc_arenas(std::max(2, pipeline::fuse_threads(options.fuse.threads)));
  const pipeline::FollowStatus s = pipeline::run_follow(options, events);
  std::printf("followed      %zu frames, %zu with a pose, %zu keyframes mapped (%zu dropped)\n",
              s.frames_seen, s.frames_with_pose, s.keyframes_mapped, s.keyframes_dropped);
  std::printf("ended by      %s after %.1f s, %zu publishes\n", s.ended_by.c_str(), s.seconds,
              s.publishes);
  std::printf("objects       %zu\n", s.objects);
  std::printf("lag           last %.2f s, median %.2f s, max %.2f s\n", s.lag_last_s,
              s.lag_median_s, s.lag_max_s);
  std::printf("trajectory    %zu lines, %zu malformed (skipped), %zu rewrites\n",
              s.trajectory_lines, s.trajectory_malformed, s.trajectory_rewrites);
  std::printf("skipped       %zu frames by detect, %zu frame reads retried\n",
              s.frames_skipped_detect, s.frame_retries);
  std::printf("peak memory   %.1f MB\n", static_cast<double>(s.peak_rss_kb) / 1024.0);
  std::printf("map           %s\n", (options.out / "map").c_str());
  if (s.reports > 0)
    std::printf("report        %s (of publish %zu; %zu reports)\n",
                (options.out / "report" / "report.html").c_str(), s.report_publish, s.reports);
}

void setup_follow(CLI::App& app) {
  auto o = std::make_shared<pipeline::FollowOptions>();
  CLI::App* c = app.add_subcommand(
      "follow",
      "Keeps the object map of a recording up to date while the recording is written: polls the "
      "folder, fuses each new keyframe as it arrives, and every --publish-every seconds writes "
      "OUT/map (objects.json, the object PLYs, map_semantic.ply) atomically, OUT/report every "
      "--report-every seconds, and OUT/status.json. "
      "Ends on DATASET/done or --idle-exit (docs/follow.md).");
  c->add_option("--dataset", o->dataset, kDatasetHelp)->required();
  c->add_option("--out", o->out, "the run folder: new, empty or an earlier follow")->required();
  c->add_option("--trajectory", o->trajectory,
                "a TUM trajectory (world_from_cam) that grows line by line as the SLAM writes it "
                "(default: the recording's own poses)");
  c->add_option("--model", o->model,
                "an instance segmentation model as objmap detect takes (YOLOv5/v8-seg ONNX, ...), "
                "run on the newest keyframe whenever it is free (the keyframes it cannot reach are "
                "skipped and counted); default: the instances of DATASET/segmentation");
  c->add_option("--layout", o->layout, kLayoutHelp)->capture_default_str();
  c->add_option("--camera", o->camera, "preset, ORB-SLAM2 YAML or JSON (default as objmap fuse)");
  c->add_option("--publish-every", o->publish_every_s,
                "seconds between the starts of two publishes, when a keyframe is new (a publish "
                "takes ~0.5 s on a 30 s walk-through and uses the second core: on a busy machine "
                "2 leaves more to the rest)")
      ->capture_default_str();
  c->add_option("--idle-exit", o->idle_exit_s,
                "end after this many seconds without a new frame or pose (0: only DATASET/done)")
      ->capture_default_str();
  c->add_option("--poll", o->poll_s,
                "seconds between two reads of the recording folder (a new frame waits for the "
                "next read; each read lists the whole recording again)")
      ->capture_default_str();
  c->add_option("--report-every", o->report_every_s,
                "seconds between two reports (OUT/report, objmap report of the map just "
                "published, made on a thread of its own: ~1 s of one core on a 30 s walk-through); "
                "0: only the report of the last map")
      ->capture_default_str();
  c->add_option("--scene-every", o->scene_every_s,
                "seconds between two findings of the up direction and the surfaces on a "
                "published dense map (the publishes in between take the last ones found; the last "
                "publish finds its own); 0: on every publish's")
      ->capture_default_str();
  c->add_option("--threads", o->fuse.threads, "worker threads, 0 = all cores")
      ->capture_default_str();
  c->callback([o] { follow_and_print(*o); });
}

}  // namespace

OBJMAP_COMMAND(84, "follow", setup_follow);

}  // namespace objmap::app

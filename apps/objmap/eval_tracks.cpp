// objmap eval tracks: CLEAR-MOT and identity metrics of a tracked segmentation against a
// ground-truth segmentation. setup_eval_tracks() is called by the `eval` group (eval.cpp).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "command.h"
#include "objmap/eval/tracks.h"
#include "objmap/io/atomic.h"
#include "objmap/segmentation/read.h"

namespace objmap::app {

namespace {

struct EvalTracksArgs {
  std::string gt_dir;
  std::string est_dir;
  std::string json_file;  // empty: not written
  eval::TrackEvalOptions options;
};

void run_eval_tracks(const EvalTracksArgs& args) {
  check_naming_flags([&] { args.options.check(); }, {{"TrackEvalOptions.min_iou", "--min-iou"}});
  io::require_not_an_input({"--json", args.json_file},
                           {{"--gt", args.gt_dir}, {"--est", args.est_dir}});
  const segmentation::Segmentation gt = segmentation::read_segmentation(args.gt_dir);
  const segmentation::Segmentation est = segmentation::read_segmentation(args.est_dir);
  const eval::TrackEvalResult r = eval::evaluate_tracks(gt, est, args.options);
  if (!args.json_file.empty())
    io::write_file_atomic(args.json_file, eval::tracks_eval_json(r, args.options));

  std::printf("TRACKS  %s  vs  %s\n", args.est_dir.c_str(), args.gt_dir.c_str());
  std::printf("  frames      %zu (%zu estimated frames without ground truth ignored)\n", r.frames,
              r.est_frames_unmatched);
  std::printf("  objects     %zu gt tracks, %zu estimated tracks (IoU >= %g%s)\n", r.gt_tracks,
              r.est_tracks, args.options.min_iou, args.options.same_class ? ", same class" : "");
  std::printf("  instances   %zu gt, %zu estimated with a track id (%zu without, ignored)\n",
              r.gt_instances, r.est_instances, r.est_untracked);
  std::printf("  MOTA        %.4f  (misses %zu, false positives %zu, id switches %zu)\n", r.mota,
              r.misses, r.false_positives, r.id_switches);
  std::printf("  MOTP        %.4f  (mean IoU of %zu matches)\n", r.motp, r.matches);
  std::printf("  IDF1        %.4f  (IDP %.4f, IDR %.4f)\n", r.idf1, r.idp, r.idr);
  std::printf("  MT/PT/ML    %zu / %zu / %zu   fragmentations %zu\n", r.mostly_tracked,
              r.partially_tracked, r.mostly_lost, r.fragmentations);
}

}  // namespace

void setup_eval_tracks(CLI::App& eval_app) {
  auto args = std::make_shared<EvalTracksArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "tracks",
      "Tracking metrics of a tracked segmentation against ground truth: CLEAR-MOT (MOTA, MOTP as "
      "mean IoU, ID switches, fragmentations, mostly tracked/lost) and IDF1, per frame with IoU "
      ">= --min-iou matching (mask IoU when both have masks, else boxes)");
  cmd->add_option("--gt", args->gt_dir, "Ground-truth segmentation (track_id = true object id)")
      ->required();
  cmd->add_option("--est", args->est_dir, "Tracked segmentation (e.g. the output of objmap track)")
      ->required();
  cmd->add_option("--min-iou", args->options.min_iou, "IoU a matched pair needs")
      ->capture_default_str();
  cmd->add_flag("--same-class", args->options.same_class, "a match also needs the same class");
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args] { run_eval_tracks(*args); });
}

}  // namespace objmap::app

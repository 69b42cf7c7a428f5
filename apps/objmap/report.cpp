// objmap report: one self-contained HTML page (and a Markdown summary) of a fuse run: the semantic
// map seen from above with the objects, the trajectories coloured by their error, the error over
// time, a thumbnail per object and the paper's tables.
#include <cstdio>
#include <memory>

#include "command.h"
#include "objmap/core/error.h"
#include "objmap/pipeline/report.h"
#include "objmap/pipeline/report_diff.h"

namespace objmap::app {
namespace {

namespace fs = std::filesystem;
using pipeline::ReportOptions;

// The summary on stdout: the figures, the notes, what was written where.
void print_report_summary(const report::PageContent& page, const fs::path& out) {
  std::printf("%s\n", report::summary_line(page).c_str());
  for (const std::string& note : page.notes) std::printf("note: %s\n", note.c_str());
  std::printf("written     %s/{report.md, topview.png%s%s%s, thumbnails/ (%zu)}\n", out.c_str(),
              page.trajectory_plot.bytes.empty() ? "" : ", trajectory.svg",
              page.ate_plot.bytes.empty() ? "" : ", ate.svg",
              page.scene_graph.bytes.empty() ? "" : ", scene_graph.svg", page.objects.size());
  std::printf("report      %s\n", (out / "report.html").c_str());
}

void print_diff_report_summary(const report::DiffPageContent& page, const fs::path& out) {
  std::printf("%s\n", page.summary.c_str());
  for (const std::string& note : page.notes) std::printf("note: %s\n", note.c_str());
  std::printf("written     %s/{report.md, thumbnails/ (%zu)}\n", out.c_str(),
              2 * page.changes.size());
  std::printf("report      %s\n", (out / "report.html").c_str());
}

void run_report_command(const ReportOptions& options, const std::string& diff) {
  require(!options.run.empty() || !diff.empty(), "report",
          "no input; expected --run RUN (objmap fuse) or --diff DIFF (objmap diff)");
  if (diff.empty()) {
    const pipeline::ReportResult result = pipeline::run_report(options);
    print_report_summary(result.page, result.out);
    return;
  }
  pipeline::DiffReportOptions d;
  d.diff = diff;
  d.out = options.out;
  d.thumbnail_px = options.thumbnail_px;
  d.view_points = options.view_points;
  const pipeline::DiffReportResult result = pipeline::run_diff_report(d);
  print_diff_report_summary(result.page, result.out);
}

void setup_report(CLI::App& app) {
  auto options = std::make_shared<ReportOptions>();
  auto diff = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "report",
      "A self-contained HTML page of a fuse run (OUT/report.html) and a Markdown summary with its "
      "pictures: the semantic map seen from above with every object's box and label, the "
      "trajectories coloured by their absolute error and the error over time (when a ground "
      "truth is known), a thumbnail per object, and the tables (objects, objects per class, "
      "centroid errors against ground-truth objects, point reduction).\n"
      "With --diff DIFF instead of --run: the page of objmap diff's result (DIFF/report): the "
      "registration (transform, fitness, uncertainty), a row per change with the object as each "
      "run saw it, and the 3D view with both maps (B's registered into A's frame, tinted) and an "
      "arrow per moved object.");
  auto* run = cmd->add_option("--run", options->run, "the folder written by 'objmap fuse'");
  auto* diff_flag =
      cmd->add_option("--diff", *diff, "or the folder written by 'objmap diff' (or its diff.json)")
          ->excludes(run);
  cmd->add_option("--out", options->out, "output folder (default RUN/report, DIFF/report)");
  auto* gt = cmd->add_option(
      "--gt", options->gt,
      "ground-truth trajectory (default: groundtruth.txt of the run's dataset, unless "
      "the run was fused with that very file)");
  gt->excludes(diff_flag);
  cmd->add_option("--corrected", options->corrected,
                  "corrected trajectory (default: RUN/trajectory_corrected.txt when present)")
      ->excludes(diff_flag);
  auto* gt_objects = cmd->add_option(
      "--gt-objects", options->gt_objects,
      "ground-truth objects for Tables 3-5 (default: objects_gt.json of the run's dataset when "
      "present): objects_gt.json or a cuboid list");
  gt_objects->excludes(diff_flag);
  cmd->add_option("--reference", options->reference,
                  "or a reference map RUN_GT/objects.json (fused with the ground-truth trajectory)")
      ->excludes(gt_objects)
      ->excludes(diff_flag);
  cmd->add_option("--gt-class", options->gt_class, "class of the objects of a cuboid list")
      ->capture_default_str();
  cmd->add_option("--up", options->up,
                  "the world's up for the pictures: auto (the run's up direction, objects.json "
                  "gravity_from_world; z for a run without it), or an axis x, y or z")
      ->capture_default_str();
  cmd->add_option("--pixel", options->pixel_m, "top view resolution, metres per pixel")
      ->capture_default_str();
  cmd->add_option("--thumbnail", options->thumbnail_px, "thumbnail side, pixels")
      ->capture_default_str();
  cmd->add_option("--view-points", options->view_points,
                  "the 3D view draws the semantic map thinned to at most this many points")
      ->capture_default_str();
  cmd->callback([options, diff] { run_report_command(*options, *diff); });
}

}  // namespace

OBJMAP_COMMAND(80, "report", setup_report);

}  // namespace objmap::app

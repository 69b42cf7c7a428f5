// objmap eval: evaluation against ground truth, a group of subcommands. Each subcommand is an
// options struct, a setup_eval_<name>(CLI::App& eval) that declares its flags and a
// run_eval_<name>() that does the work. To add one, write those three below and list
// setup_eval_<name> in kEvalSubcommands.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "command.h"
#include "objmap/core/format.h"
#include "objmap/eval/ate.h"
#include "objmap/eval/json.h"
#include "objmap/eval/objects.h"
#include "objmap/eval/rpe.h"
#include "objmap/io/atomic.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/trajectory.h"

namespace objmap::app {

// apps/objmap/eval_tracks.cpp: `objmap eval tracks` (CLEAR-MOT and IDF1).
void setup_eval_tracks(CLI::App& eval_app);
// apps/objmap/eval_masks.cpp: `objmap eval masks` (mask quality without ground truth).
void setup_eval_masks(CLI::App& eval_app);
// apps/objmap/eval_scene.cpp: `objmap eval scene` (up, support surfaces, `on` relations).
void setup_eval_scene(CLI::App& eval_app);
// apps/objmap/eval_surface.cpp: `objmap eval surface` (meshes and clouds against true models).
void setup_eval_surface(CLI::App& eval_app);
// apps/objmap/eval_diff.cpp: `objmap eval diff` (objmap diff against a second visit's truth).
void setup_eval_diff(CLI::App& eval_app);

namespace {

// A trajectory, its reader's warnings (a repeated timestamp) on stderr, one line each.
Trajectory read_trajectory_warning(const std::string& file) {
  Trajectory t = io::read_trajectory(file);
  for (const auto& w : t.warnings) std::fprintf(stderr, "objmap: warning: %s\n", w.c_str());
  return t;
}

// One row "  rmse    0.013473" per statistic; `columns` are printed side by side.
void print_stats_rows(std::ostream& out, const std::vector<const eval::ErrorStats*>& columns) {
  const auto row = [&](const char* name, double eval::ErrorStats::*field) {
    char label[16];
    std::snprintf(label, sizeof(label), "  %-8s", name);
    out << label;
    for (const eval::ErrorStats* s : columns) {
      char cell[32];
      std::snprintf(cell, sizeof(cell), "%16.6f", s->*field);
      out << cell;
    }
    out << "\n";
  };
  row("rmse", &eval::ErrorStats::rmse);
  row("mean", &eval::ErrorStats::mean);
  row("median", &eval::ErrorStats::median);
  row("std", &eval::ErrorStats::stddev);
  row("min", &eval::ErrorStats::min);
  row("max", &eval::ErrorStats::max);
}

// ---- objmap eval ate
// ------------------------------------------------------------------------------

struct EvalAteArgs {
  std::string gt_file;
  std::string est_file;
  eval::AteOptions options;
  std::string save_aligned_file;  // empty: not written
  std::string json_file;          // empty: not written
};

void run_eval_ate(const EvalAteArgs& args) {
  check_naming_flags(
      [&] { args.options.check(); },  // bad options before reading the files
      {{"AteOptions.max_diff_s", "--max-diff"}, {"AteOptions.offset_s", "--offset"}});
  const std::vector<io::NamedPath> inputs{{"--gt", args.gt_file}, {"--est", args.est_file}};
  io::require_not_an_input({"--json", args.json_file}, inputs);
  io::require_not_an_input({"--save-aligned", args.save_aligned_file}, inputs);
  const Trajectory gt = read_trajectory_warning(args.gt_file);
  const Trajectory est = read_trajectory_warning(args.est_file);
  const eval::AteResult result = eval::evaluate_ate(gt, est, args.options);

  const eval::Similarity& a = result.gt_from_est;
  if (!args.save_aligned_file.empty())
    io::write_trajectory(args.save_aligned_file, result.aligned,
                         "objmap eval ate: " + args.est_file + " aligned onto " + args.gt_file +
                             "\n" + (args.options.with_scale ? "sim3" : "se3") +
                             " alignment, scale " + number_text(a.scale));
  if (!args.json_file.empty())
    io::write_file_atomic(args.json_file, eval::ate_json(result, args.options));

  std::cout << "ATE  " << args.est_file << "  vs  " << args.gt_file << "\n"
            << "  pairs   " << result.stats.count
            << " (max_diff " + number_text(args.options.max_diff_s) << " s, offset "
            << number_text(args.options.offset_s) << " s)\n"
            << "  align   " << (args.options.with_scale ? "sim3" : "se3") << ", scale "
            << fixed_text(a.scale, 6) << ", translation [" << fixed_text(a.translation.x(), 4)
            << ", " << fixed_text(a.translation.y(), 4) << ", " << fixed_text(a.translation.z(), 4)
            << "] m\n"
            << "  translational error [m]\n";
  print_stats_rows(std::cout, {&result.stats});
}

void setup_eval_ate(CLI::App& eval_app) {
  auto args = std::make_shared<EvalAteArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "ate",
      "Absolute trajectory error (as TUM's evaluate_ate.py): associate stamps, align the "
      "estimate onto the ground truth (rigid; --scale: with scale), position error statistics");
  cmd->add_option("--gt", args->gt_file, "Ground-truth trajectory (TUM format)")->required();
  cmd->add_option("--est", args->est_file, "Estimated trajectory (TUM format)")->required();
  cmd->add_option("--max-diff", args->options.max_diff_s,
                  "Largest stamp difference of a pose pair, seconds")
      ->capture_default_str();
  cmd->add_option("--offset", args->options.offset_s,
                  "Time offset added to the estimate's stamps, seconds")
      ->capture_default_str();
  cmd->add_flag("--scale", args->options.with_scale,
                "Also estimate a scale (Sim(3), Umeyama), e.g. for monocular runs");
  cmd->add_option("--save-aligned", args->save_aligned_file,
                  "Write the aligned estimate here (TUM format)");
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args] { run_eval_ate(*args); });
}

// ---- objmap eval rpe
// ------------------------------------------------------------------------------

struct EvalRpeArgs {
  std::string gt_file;
  std::string est_file;
  eval::RpeOptions options;
  std::string delta_unit = "s";
  double max_diff_s = 0.0;  // used only when --max-diff is given (max_diff_given)
  bool max_diff_given = false;
  std::string json_file;
};

void run_eval_rpe(EvalRpeArgs args) {
  args.options.delta_unit = eval::parse_delta_unit(args.delta_unit);
  if (args.max_diff_given) args.options.max_diff_s = args.max_diff_s;
  check_naming_flags([&] { args.options.check(); },  // bad options before reading the files
                     {{"RpeOptions.delta", "--delta"},
                      {"RpeOptions.offset_s", "--offset"},
                      {"RpeOptions.max_diff_s", "--max-diff"}});
  io::require_not_an_input({"--json", args.json_file},
                           {{"--gt", args.gt_file}, {"--est", args.est_file}});
  const Trajectory gt = read_trajectory_warning(args.gt_file);
  const Trajectory est = read_trajectory_warning(args.est_file);
  const eval::RpeResult result = eval::evaluate_rpe(gt, est, args.options);
  if (!args.json_file.empty())
    io::write_file_atomic(args.json_file, eval::rpe_json(result, args.options));

  std::cout << "RPE  " << args.est_file << "  vs  " << args.gt_file << "\n"
            << "  pairs   " << result.pairs.size() << " (delta " << number_text(args.options.delta)
            << " " << eval::to_string(args.options.delta_unit) << ", max_diff "
            << fixed_text(result.max_diff_s, 4) << " s, offset "
            << number_text(args.options.offset_s) << " s)\n"
            << "          translational [m]  rotational [deg]\n";
  print_stats_rows(std::cout, {&result.translational_m, &result.rotational_deg});
}

void setup_eval_rpe(CLI::App& eval_app) {
  auto args = std::make_shared<EvalRpeArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "rpe",
      "Relative pose error (as TUM's evaluate_rpe.py --fixed_delta): error of the motion "
      "over delta, translational and rotational statistics");
  cmd->add_option("--gt", args->gt_file, "Ground-truth trajectory (TUM format)")->required();
  cmd->add_option("--est", args->est_file, "Estimated trajectory (TUM format)")->required();
  cmd->add_option("--delta", args->options.delta, "Length of the compared motions, in --delta-unit")
      ->capture_default_str();
  cmd->add_option("--delta-unit", args->delta_unit,
                  "s (seconds), m (metres travelled), rad or deg (rotation), f (frames)")
      ->capture_default_str();
  cmd->add_option("--offset", args->options.offset_s,
                  "Time offset added to the estimate's stamps, seconds")
      ->capture_default_str();
  CLI::Option* max_diff = cmd->add_option(
      "--max-diff", args->max_diff_s,
      "Largest stamp difference between an estimate pose and its ground-truth pose, "
      "seconds (default: 2 x the median ground-truth interval, as evaluate_rpe.py)");
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args, max_diff] {
    args->max_diff_given = max_diff->count() > 0;
    run_eval_rpe(*args);
  });
}

// ---- objmap eval objects
// --------------------------------------------------------------------------

struct EvalObjectsArgs {
  std::string map_file;             // RUN/objects.json
  std::string gt_objects_file;      // objects_gt.json or a cuboid list; or
  std::string reference_file;       // RUN_GT/objects.json
  std::string gt_class = "object";  // class of cuboid-list objects (they carry none)
  std::string run_dir;              // empty: the folder of --map, if it has run.json
  std::string json_file;            // empty: not written
  std::string align = "none";       // none, trajectory or objects
  std::string gt_trajectory_file, trajectory_file;  // --align trajectory
  eval::ObjectEvalOptions options;
};

// --align: how the map is brought into the reference's frame (checked flags first).
eval::ObjectAlignment find_alignment(const EvalObjectsArgs& args,
                                     const std::vector<io::MappedObject>& map,
                                     const std::vector<eval::ReferenceObject>& reference) {
  if (args.align == "trajectory")
    return eval::align_by_trajectories(read_trajectory_warning(args.gt_trajectory_file),
                                       read_trajectory_warning(args.trajectory_file));
  if (args.align == "objects") return eval::align_by_objects(map, reference, args.options.gate_m);
  return eval::ObjectAlignment{};
}

void check_align_flags(const EvalObjectsArgs& args) {
  const bool trajectories = !args.gt_trajectory_file.empty() || !args.trajectory_file.empty();
  if (args.align == "trajectory" &&
      (args.gt_trajectory_file.empty() || args.trajectory_file.empty()))
    throw CLI::ValidationError("--align trajectory",
                               "needs --gt-trajectory GT.txt and --trajectory EST.txt (the "
                               "trajectory the map was fused with)");
  if (args.align != "trajectory" && trajectories)
    throw CLI::ValidationError(
        "--gt-trajectory/--trajectory",
        "given with --align " + args.align + "; expected them only with --align trajectory");
}

void run_eval_objects(const EvalObjectsArgs& args) {
  if (args.gt_objects_file.empty() == args.reference_file.empty())
    throw CLI::ValidationError("eval objects",
                               "give one of --gt-objects F or --reference RUN_GT/objects.json");
  check_naming_flags([&] { args.options.check(); }, {{"ObjectEvalOptions.gate_m", "--gate"}});
  check_align_flags(args);
  io::require_not_an_input({"--json", args.json_file},
                           {{"--map", args.map_file},
                            {"--gt-objects", args.gt_objects_file},
                            {"--reference", args.reference_file},
                            {"--run", args.run_dir},
                            {"--gt-trajectory", args.gt_trajectory_file},
                            {"--trajectory", args.trajectory_file}});
  eval::ObjectEvalReport report;
  report.options = args.options;
  report.map_source = args.map_file;
  const std::vector<io::MappedObject> map = io::read_objects_json(args.map_file);
  std::vector<eval::ReferenceObject> reference;
  if (!args.gt_objects_file.empty()) {
    report.mode = "ground_truth";
    report.reference_source = args.gt_objects_file;
    reference = eval::read_objects_gt(args.gt_objects_file, args.gt_class);
  } else {
    report.mode = "reference";
    report.reference_source = args.reference_file;
    reference = eval::to_reference(io::read_objects_json(args.reference_file));
  }
  // Table 6: --run RUN, else the folder of --map when it holds run.json.
  namespace fs = std::filesystem;
  if (!args.run_dir.empty()) {
    report.points = eval::read_point_counts(fs::path(args.run_dir) / "run.json");
  } else {
    const fs::path beside = fs::path(args.map_file).parent_path() / "run.json";
    if (fs::exists(beside)) report.points = eval::read_point_counts(beside);
  }
  report.alignment = find_alignment(args, map, reference);
  report.result = eval::evaluate_objects(
      report.alignment.method == "none"
          ? map
          : eval::transform_objects(map, report.alignment.reference_from_map),
      reference, args.options);
  if (!args.json_file.empty())
    io::write_file_atomic(args.json_file, eval::objects_eval_json(report));
  std::cout << eval::objects_eval_text(report);
}

void setup_eval_objects(CLI::App& eval_app) {
  auto args = std::make_shared<EvalObjectsArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "objects",
      "Object map against ground-truth objects or a reference map (paper Tables 3-6): counts per "
      "class, centroid errors of objects matched one-to-one by class, precision/recall, 3D IoU, "
      "point reduction");
  cmd->add_option("--map", args->map_file, "The evaluated map: RUN/objects.json of objmap fuse")
      ->required();
  CLI::Option* gt = cmd->add_option(
      "--gt-objects", args->gt_objects_file,
      "Ground-truth objects: objects_gt.json (objmap synth) or a cuboid list "
      "\"x y z yaw half_x half_y half_z\" per line (e.g. fr3_cabinet objects_gt.txt)");
  CLI::Option* ref = cmd->add_option(
      "--reference", args->reference_file,
      "Reference map: RUN_GT/objects.json fused with the ground-truth trajectory (the paper's "
      "protocol of Tables 4-5)");
  gt->excludes(ref);
  cmd->add_option("--gt-class", args->gt_class,
                  "Class of the objects of a cuboid list (they carry none)")
      ->capture_default_str();
  cmd->add_option("--gate", args->options.gate_m,
                  "Largest centroid distance of a matched pair, metres")
      ->capture_default_str();
  cmd->add_option("--run", args->run_dir,
                  "Run folder whose run.json gives Table 6 (default: the folder of --map)");
  cmd->add_option("--align", args->align,
                  "Bring a map of another frame into the reference's by SE(3) before evaluating: "
                  "'trajectory' (eval ate's alignment of --trajectory onto --gt-trajectory) or "
                  "'objects' (Umeyama on the objects matched by class; needs 3)")
      ->check(CLI::IsMember({"none", "trajectory", "objects"}))
      ->capture_default_str();
  cmd->add_option("--gt-trajectory", args->gt_trajectory_file,
                  "--align trajectory: the ground-truth trajectory (the reference's frame)");
  cmd->add_option("--trajectory", args->trajectory_file,
                  "--align trajectory: the trajectory the map was fused with (the map's frame)");
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args] { run_eval_objects(*args); });
}

// ---- the group
// ------------------------------------------------------------------------------------

// The subcommands of `objmap eval`, in --help order.
const SetupFn kEvalSubcommands[] = {setup_eval_ate,   setup_eval_rpe,     setup_eval_objects,
                                    setup_eval_scene, setup_eval_surface, setup_eval_tracks,
                                    setup_eval_masks, setup_eval_diff};

void setup_eval(CLI::App& app) {
  CLI::App* eval_app = app.add_subcommand(
      "eval",
      "Evaluate against ground truth: trajectories (ate, rpe), objects, scene structure, "
      "tracks; and masks without it");
  eval_app->require_subcommand(1);
  for (const SetupFn& setup : kEvalSubcommands) setup(*eval_app);
}

}  // namespace

OBJMAP_COMMAND(60, "eval", setup_eval);

}  // namespace objmap::app

// objmap eval scene: the up direction, support surfaces and `on` relations of an object map
// against the ground truth of objmap synth. setup_eval_scene() is called by the `eval` group
// (eval.cpp).
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "command.h"
#include "objmap/eval/ate.h"
#include "objmap/eval/objects.h"
#include "objmap/eval/scene.h"
#include "objmap/io/atomic.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/scene_json.h"
#include "objmap/io/trajectory.h"

namespace objmap::app {

namespace {

namespace fs = std::filesystem;

struct EvalSceneArgs {
  std::string run;            // RUN folder (its objects.json) or an objects.json
  std::string gt_file;        // objects_gt.json
  std::string gt_trajectory;  // with `trajectory`: bring the map into the ground truth's frame
  std::string trajectory;
  std::string json_file;  // empty: not written
  eval::ObjectEvalOptions options;
};

std::string objects_json_of(const std::string& run) {
  return fs::is_directory(run) ? (fs::path(run) / "objects.json").string() : run;
}

// The SE(3) that `eval ate` finds between the run's trajectory and the ground truth's.
eval::SceneAlignment align_run(const EvalSceneArgs& args) {
  const eval::AteResult ate =
      eval::evaluate_ate(io::read_trajectory(args.gt_trajectory),
                         io::read_trajectory(args.trajectory), eval::AteOptions{});
  return {args.gt_trajectory, args.trajectory, ate.gt_from_est, ate.stats};
}

void run_eval_scene(const EvalSceneArgs& args) {
  check_naming_flags([&] { args.options.check(); }, {{"ObjectEvalOptions.gate_m", "--gate"}});
  const std::string objects_file = objects_json_of(args.run);
  io::require_not_an_input({"--json", args.json_file}, {{"--run", objects_file},
                                                        {"--gt", args.gt_file},
                                                        {"--gt-trajectory", args.gt_trajectory},
                                                        {"--trajectory", args.trajectory}});
  eval::SceneEvalReport report;
  report.map_source = objects_file;
  report.gt_source = args.gt_file;
  report.options = args.options;
  // The scene fields first: a run fused without them is named by its missing field.
  eval::SceneDescription map_scene = io::read_map_scene(objects_file);
  std::vector<io::MappedObject> map_objects = io::read_objects_json(objects_file);
  const eval::SceneDescription gt_scene = io::read_gt_scene(args.gt_file);
  const std::vector<eval::ReferenceObject> gt_objects = eval::read_objects_gt(args.gt_file);
  if (!args.trajectory.empty()) {
    report.alignment = align_run(args);
    map_scene = eval::transform_scene(map_scene, report.alignment->gt_from_map);
    map_objects = eval::transform_objects(map_objects, report.alignment->gt_from_map);
  }
  report.result = eval::evaluate_scene(map_objects, map_scene, gt_objects, gt_scene, args.options);
  if (!args.json_file.empty()) io::write_file_atomic(args.json_file, eval::scene_eval_json(report));
  std::cout << eval::scene_eval_text(report);
}

}  // namespace

void setup_eval_scene(CLI::App& eval_app) {
  auto args = std::make_shared<EvalSceneArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "scene",
      "Scene structure of a map against objmap synth's ground truth: up-vector angle error, "
      "floor and table surfaces found and their height errors, precision and recall of the "
      "objects' 'on' relations");
  cmd->add_option("--run", args->run, "Run folder of objmap fuse (its objects.json) or the file")
      ->required();
  cmd->add_option("--gt", args->gt_file, "Ground truth: objects_gt.json of objmap synth")
      ->required();
  CLI::Option* gt_trajectory = cmd->add_option(
      "--gt-trajectory", args->gt_trajectory,
      "Ground-truth trajectory (TUM); with --trajectory the map is brought into its frame");
  CLI::Option* trajectory =
      cmd->add_option("--trajectory", args->trajectory,
                      "The trajectory the run was fused with (TUM), e.g. estimated_slam_frame.txt");
  gt_trajectory->needs(trajectory);
  trajectory->needs(gt_trajectory);
  cmd->add_option("--gate", args->options.gate_m,
                  "Largest centroid distance of a matched object pair, metres (as eval objects)")
      ->capture_default_str();
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args] { run_eval_scene(*args); });
}

}  // namespace objmap::app

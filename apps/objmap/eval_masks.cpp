// objmap eval masks: how well each object of a fuse run agrees with its own masks, without ground
// truth (pipeline/mask_check.h).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "command.h"
#include "objmap/io/atomic.h"
#include "objmap/pipeline/mask_check.h"

namespace objmap::app {

namespace {

struct EvalMasksArgs {
  std::string run;
  std::string json_file;  // empty: not written
  pipeline::MaskCheckOptions options;
};

std::string masks_json(const pipeline::MaskCheckResult& r, const EvalMasksArgs& args) {
  nlohmann::ordered_json doc;
  doc["run"] = args.run;
  doc["depth_tolerance_m"] = args.options.depth_tolerance_m;
  doc["depth_tolerance_per_m"] = args.options.depth_tolerance_per_m;
  doc["share"] = r.share;
  doc["visible"] = r.visible;
  doc["inside"] = r.inside;
  doc["unmatched_observations"] = r.unmatched_observations;
  nlohmann::ordered_json objects = nlohmann::ordered_json::array();
  for (const auto& o : r.objects)
    objects.push_back({{"id", o.id},
                       {"class", o.class_name},
                       {"keyframes", o.keyframes},
                       {"visible", o.visible},
                       {"inside", o.inside},
                       {"share", o.share}});
  doc["objects"] = objects;
  return doc.dump(2) + "\n";
}

void run_eval_masks(const EvalMasksArgs& args) {
  check_naming_flags([&] { args.options.check(); },
                     {{"MaskCheckOptions.depth_tolerance_m", "--depth-tolerance"}});
  io::require_not_an_input({"--json", args.json_file}, {{"--run", args.run}});
  const pipeline::MaskCheckResult r = pipeline::check_run_masks(args.run, args.options);
  if (!args.json_file.empty()) io::write_file_atomic(args.json_file, masks_json(r, args));
  std::printf(
      "masks of %s: %.1f%% of the objects' seen points inside their own masks (%zu of %zu)\n",
      args.run.c_str(), 100.0 * r.share, r.inside, r.visible);
  if (r.unmatched_observations > 0)
    std::printf("            %zu observations whose instance was not found again\n",
                r.unmatched_observations);
  std::printf("\n  %4s  %-16s %9s %9s %7s\n", "id", "class", "keyframes", "seen", "inside");
  for (const auto& o : r.objects)
    std::printf("  %4d  %-16s %9zu %9zu %6.1f%%\n", o.id, o.class_name.c_str(), o.keyframes,
                o.visible, 100.0 * o.share);
}

}  // namespace

void setup_eval_masks(CLI::App& eval_app) {
  auto args = std::make_shared<EvalMasksArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "masks",
      "Mask quality without ground truth: each object of a fuse run projected into the keyframes "
      "where it was observed; the share of its seen points (depth-checked) inside that "
      "observation's mask (given masks as the segmentation has them, box-only instances with the "
      "mask fuse makes from the box)");
  cmd->add_option("--run", args->run, "a folder written by objmap fuse (run.json, objects.json)")
      ->required();
  cmd->add_option("--depth-tolerance", args->options.depth_tolerance_m,
                  "a projected point is seen when the depth image is within this (+2% of its "
                  "depth) of it, m")
      ->capture_default_str();
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args] { run_eval_masks(*args); });
}

}  // namespace objmap::app

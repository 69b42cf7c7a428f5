// objmap run: from a recording to a map and a report in one command. Each stage is the objmap
// command of its name (detect -> track -> fuse, with the scene -> report), run as its own process
// with its output in its own folder under RUN; a stage whose inputs and options are those of its
// last run is reused.
#include <cstdio>
#include <memory>
#include <string>

#include "command.h"
#include "objmap/pipeline/run.h"

namespace objmap::app {
namespace {

// Each stage's line as it goes ("detect   running ... done in 3.2 s  OUT/detect"), then where the
// map and the report are.
void run_run(const pipeline::RunOptions& options) {
  const pipeline::RunResult result = pipeline::run_stages(
      options, [](const pipeline::RunStage& stage, const std::string& what, double seconds) {
        if (what == "reused")
          std::printf("%-8s reused      %s\n", stage.name.c_str(), stage.out.c_str());
        else if (what == "running")
          std::printf("%-8s running ... ", stage.name.c_str());
        else if (what == "failed")
          std::printf("failed\n");
        else
          std::printf("done in %.1f s  %s\n", seconds, stage.out.c_str());
        std::fflush(stdout);
      });
  std::printf("map         %s\n", result.objects.c_str());
  std::printf("report      %s\n", result.report.c_str());
  std::printf("ask         objmap query --run %s \"cup on table\"\n", result.map.c_str());
}

void setup_run(CLI::App& app) {
  auto cmd = std::make_shared<pipeline::RunOptions>();
  CLI::App* c = app.add_subcommand(
      "run",
      "From a recording to a map and a report: detect -> track -> fuse (with the scene) -> "
      "report, each stage's output in its own folder under OUT (detect/, track/, map/, report/; "
      "logs/ has each stage's output). Run again, only the stages whose inputs or options "
      "changed run; the others are reused (OUT/stages.json records them). No model? Export one: "
      "`yolo export model=yolov8n-seg.pt format=onnx` (Ultralytics), or see docs/cli.md.");
  c->add_option("--dataset", cmd->dataset, kDatasetHelp)->required();
  c->add_option("--layout", cmd->layout, kLayoutHelp)->capture_default_str();
  c->add_option("--topics", cmd->topics, kTopicsHelp);
  c->add_option("--model", cmd->model,
                "detector: an Ultralytics YOLOv5-seg / YOLOv8-seg .onnx export (masks), a "
                "Darknet .weights or a TF Mask R-CNN .pb (as objmap detect)")
      ->required();
  c->add_option("--out", cmd->out,
                "output folder (created; an earlier objmap run output is "
                "updated, any other folder refused)")
      ->required();
  c->add_option("--trajectory", cmd->trajectory,
                "SLAM trajectory (TUM format); default: the recording's own poses");
  c->add_option("--camera", cmd->camera, "camera preset or file (default: as fuse chooses)");
  c->add_option("--classes", cmd->classes,
                "detect --classes: a comma list, 'paper' (the paper's eight) or 'all' (default)");
  c->add_option("--fuse-config", cmd->fuse_config, "fuse --config: a JSON of fuse options");
  c->add_flag("--force", cmd->force, "run every stage again");
  c->callback([cmd] { run_run(*cmd); });
}

}  // namespace

OBJMAP_COMMAND(5, "run", setup_run);

}  // namespace objmap::app

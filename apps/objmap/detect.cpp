// objmap detect: runs a detector through OpenCV's dnn module over the rgb frames of a TUM folder
// (Darknet YOLO such as Yolo-Fastest: boxes; TensorFlow Mask R-CNN: instance masks) and writes the
// canonical segmentation, one <timestamp>.json per rgb frame.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <string>
#include <vector>

#include "command.h"
#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/io/trajectory.h"
#include "objmap/io/tum_dataset.h"
#include "objmap/pipeline/keyframes.h"
#include "objmap/segmentation/detect.h"
#include "objmap/segmentation/write.h"
#include "progress.h"

namespace objmap::app {
namespace {

namespace fs = std::filesystem;

struct DetectCommand {
  std::string dataset;
  std::string layout = "auto";
  std::string topics;
  std::string out;
  std::string model;
  std::string config;
  std::string classes_file;
  std::string classes;  // comma list, "paper", "all", or empty = every class
  bool nms_per_class = false;
  std::string frames = "all";  // all | keyframes
  std::string trajectory;      // --frames keyframes: the trajectory fuse will be given
  int threads = 0;             // OpenCV's threads for the network, 0 = the cores
  segmentation::DetectOptions options;
};

// Runs of fewer frames get no progress bar.
constexpr std::size_t kProgressMinFrames = 20;

std::vector<std::string> split_classes(const std::string& list) {
  std::vector<std::string> names;
  std::string current;
  for (char c : list + ",") {
    if (c != ',') {
      current.push_back(c);
      continue;
    }
    names.push_back(current);
    current.clear();
  }
  return names;
}

// The frames to run the network on: every rgb frame (what track needs), or only those that fuse
// will take as keyframes with this trajectory (fuse's default selection: a keyframe trajectory's
// frames, else motion-thinned, every frame for a still camera).
std::vector<segmentation::DetectFrame> frames_to_detect(const DetectCommand& cmd) {
  require(cmd.frames == "all" || cmd.frames == "keyframes", "--frames",
          "'" + cmd.frames + "'; expected all or keyframes");
  // A TUM folder: every frame rgb.txt lists; other layouts: their frames as fuse reads them.
  const bool listing = io::is_tum_listing(cmd.dataset, cmd.layout);
  io::DatasetOptions options;
  options.layout = cmd.layout;
  options.topics = cmd.topics;
  std::vector<segmentation::DetectFrame> frames;
  if (listing) {
    frames = segmentation::list_rgb_frames(cmd.dataset);
  } else {
    const auto dataset =
        std::make_shared<const io::Dataset>(io::read_dataset(cmd.dataset, options));
    for (const io::FramePair& f : dataset->frames)
      frames.push_back({f.rgb_timestamp, f.rgb_file,
                        [dataset, f] { return io::read_frame_rgb(*dataset, f, 0, 0); }});
  }
  if (cmd.frames == "all") {
    require(cmd.trajectory.empty(), "--trajectory",
            "is used with --frames keyframes only; expected no trajectory with --frames all");
    return frames;
  }
  require(!cmd.trajectory.empty(), "--trajectory",
          "missing; --frames keyframes needs the trajectory that fuse will be given");
  const auto dataset = std::make_shared<const io::Dataset>(io::read_dataset(cmd.dataset, options));
  pipeline::KeyframeOptions keyframes;
  keyframes.min_keyframes = 3;  // fuse's default: the views an object needs
  const pipeline::KeyframeSelection selection =
      pipeline::select_keyframes(*dataset, io::read_trajectory(cmd.trajectory), keyframes);
  std::vector<segmentation::DetectFrame> kept;
  for (const auto& keyframe : selection.keyframes) {
    const io::FramePair& f = dataset->frames[keyframe.frame];
    kept.push_back({keyframe.timestamp, f.rgb_file,
                    [dataset, f] { return io::read_frame_rgb(*dataset, f, 0, 0); }});
  }
  return kept;
}

void run_detect(DetectCommand& cmd) {
  // OpenCV's dnn may log warnings on stderr; the user sees objmap's lines only.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
  io::require_not_an_input({"--out", cmd.out}, {{"--dataset", cmd.dataset},
                                                {"--model", cmd.model},
                                                {"--config", cmd.config},
                                                {"--classes-file", cmd.classes_file},
                                                {"--trajectory", cmd.trajectory}});
  io::require_replaceable(cmd.out, io::kSegmentationFolder);  // before the work, not after it
  segmentation::DetectOptions& o = cmd.options;
  o.model = cmd.model;
  o.config = cmd.config;
  o.classes_file = cmd.classes_file;
  o.nms_across_classes = !cmd.nms_per_class;
  if (cmd.classes == "all") {
    o.classes.clear();
  } else if (cmd.classes == "paper") {
    o.classes = segmentation::paper_detect_classes();
  } else if (!cmd.classes.empty()) {
    o.classes = split_classes(cmd.classes);
  }
  require(fs::is_directory(cmd.dataset) || io::is_rosbag_file(cmd.dataset), cmd.dataset,
          "no such folder; expected a recording folder (TUM rgb.txt, or another layout) or a ROS "
          "1 .bag");
  require(cmd.threads >= 0 && cmd.threads <= 64, "--threads",
          "must be in [0, 64] (0: the cores), got " + std::to_string(cmd.threads));
  if (cmd.threads > 0) cv::setNumThreads(cmd.threads);
  o.threads = cmd.threads;

  // The model first (its errors before any progress output), then the frames.
  const auto load_start = std::chrono::steady_clock::now();
  std::unique_ptr<segmentation::Detector> detector;
  // The library names an option by its field; the user knows it by its flag.
  check_naming_flags([&] { detector = std::make_unique<segmentation::Detector>(o); },
                     {{"DetectOptions.classes", "--classes"},
                      {"DetectOptions.score_threshold", "--score-threshold"},
                      {"DetectOptions.nms_threshold", "--nms-threshold"},
                      {"DetectOptions.mask_threshold", "--mask-threshold"},
                      {"DetectOptions.backend", "--backend"},
                      {"DetectOptions.threads", "--threads"},
                      {"DetectOptions.input_width/input_height", "--input-width/--input-height"}});
  const double load_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - load_start).count();
  const std::vector<segmentation::DetectFrame> frames = frames_to_detect(cmd);
  // A bar for long runs only: a short run's error (e.g. no detections) stays the one line on
  // stderr.
  std::unique_ptr<ProgressBar> bar;
  if (frames.size() >= kProgressMinFrames)
    bar = std::make_unique<ProgressBar>("detect", frames.size());
  const segmentation::DetectResult result = segmentation::detect_frames(
      *detector, frames, cmd.dataset, [&](std::size_t done, std::size_t /*total*/) {
        if (bar) bar->update(done);
      });
  if (bar) bar->finish();

  io::StagingDir staging(cmd.out, io::kSegmentationFolder);
  segmentation::write_segmentation(staging.path(), result.segmentation);
  staging.commit();

  const auto& m = result.model;
  std::printf("wrote       %s (%zu frame files)\n", cmd.out.c_str(),
              result.segmentation.frames.size());
  const std::string files =
      m.config == m.model ? m.model.string() : m.model.string() + " + " + m.config.string();
  std::printf("model       %s: %s, input %d x %d, %zu classes, run by %s\n",
              segmentation::model_kind_name(m.kind).c_str(), files.c_str(), m.input_width,
              m.input_height, m.class_names.size(), m.backend.c_str());
  std::string kept;
  if (m.kept_class_ids.size() == m.class_names.size()) {
    kept = "all";
  } else {
    for (std::size_t i = 0; i < m.kept_class_ids.size(); ++i)
      kept += (i ? ", " : "") + m.class_names[static_cast<std::size_t>(m.kept_class_ids[i])];
  }
  std::printf("classes     %s (score >= %.2f, NMS IoU %.2f %s)\n", kept.c_str(), o.score_threshold,
              o.nms_threshold, o.nms_across_classes ? "across classes" : "per class");
  std::printf("frames      %zu, %zu with detections\n", result.frames,
              result.frames_with_detections);
  std::printf("instances   %zu (%s)\n", result.instances,
              m.kind == segmentation::ModelKind::kDarknetYolo ? "boxes" : "boxes with masks");
  for (const auto& [name, n] : result.instances_per_class)
    std::printf("  %-20s %zu\n", name.c_str(), n);
  std::printf("time        %.2f s loading the model, %.2f s for the frames (%.1f ms per frame)\n",
              load_seconds, result.seconds,
              result.frames ? 1000.0 * result.seconds / result.frames : 0.0);
}

void setup_detect(CLI::App& app) {
  auto cmd = std::make_shared<DetectCommand>();
  segmentation::DetectOptions& o = cmd->options;
  auto* c = app.add_subcommand(
      "detect",
      "Detect objects in the rgb frames of a TUM folder with OpenCV's dnn module and write the "
      "canonical segmentation (SEG/<timestamp>.json). Models: Darknet YOLO (.weights + .cfg, "
      "e.g. Yolo-Fastest; boxes), TensorFlow Mask R-CNN (frozen_inference_graph.pb + .pbtxt; "
      "instance masks) or an Ultralytics YOLOv5-seg / YOLOv8-seg ONNX export (.onnx; instance "
      "masks). Nothing is downloaded (docs/cli.md says how to get or export the models).");
  c->add_option("--dataset", cmd->dataset,
                std::string(kDatasetHelp) + "; a TUM folder may hold rgb.txt and rgb/ alone")
      ->required();
  c->add_option("--layout", cmd->layout, kLayoutHelp)->capture_default_str();
  c->add_option("--topics", cmd->topics, kTopicsHelp);
  c->add_option("--model", cmd->model,
                "model weights: Darknet .weights, TensorFlow Mask R-CNN .pb, or an Ultralytics "
                "YOLOv5-seg / YOLOv8-seg export .onnx (the whole network in one file)")
      ->required();
  c->add_option("--config", cmd->config,
                "network description: Darknet .cfg (default: the model's name with .cfg) or the "
                ".pbtxt text graph (required for .pb)");
  c->add_option("--classes-file", cmd->classes_file,
                "class names, one per line, line i = class id i-1 (default: built-in COCO-80 for "
                "Darknet and ONNX, COCO-90 for Mask R-CNN)");
  c->add_option("--classes", cmd->classes,
                "comma-separated classes to keep, 'paper' (the paper's eight: chair, cup, tv "
                "monitor, teddy bear, bottle, book, keyboard, mouse, the benchmark tables' preset) "
                "or 'all' (default: every class the model knows)");
  c->add_option("--score-threshold", o.score_threshold, "minimum class score of a detection")
      ->capture_default_str();
  c->add_option(
       "--nms-threshold", o.nms_threshold,
       "non-maximum suppression: of two boxes overlapping with IoU above this the weaker goes")
      ->capture_default_str();
  c->add_flag("--nms-per-class", cmd->nms_per_class,
              "suppress overlapping boxes within each class only (default: across classes, one "
              "box per object)");
  c->add_option("--input-width", o.input_width,
                "network input width in pixels (0: the model's, e.g. the cfg's width, the ONNX "
                "graph's input; Mask R-CNN 800)")
      ->capture_default_str();
  c->add_option("--input-height", o.input_height, "network input height in pixels (0: the model's)")
      ->capture_default_str();
  c->add_option("--mask-threshold", o.mask_threshold,
                "Mask R-CNN and ONNX segmentation: mask value above which a pixel is the object's")
      ->capture_default_str();
  c->add_option("--frames", cmd->frames,
                "all: every rgb frame (what track needs); keyframes: only the frames fuse will "
                "take as keyframes with --trajectory (the network runs once per frame that needs "
                "it)")
      ->capture_default_str();
  c->add_option("--trajectory", cmd->trajectory,
                "with --frames keyframes: the trajectory fuse will be given (TUM format)");
  c->add_option("--backend", o.backend,
                "what runs an ONNX model: auto (ONNX Runtime when installed, about 3x faster; "
                "else OpenCV's dnn), onnxruntime or opencv (docs/cli.md)")
      ->capture_default_str();
  c->add_option("--threads", cmd->threads,
                "threads of the network (OpenCV), 0 = the cores; the outputs are the same for any "
                "count")
      ->capture_default_str();
  c->add_option("--out", cmd->out,
                "output segmentation folder (an earlier segmentation there is replaced; any other "
                "folder is refused)")
      ->required();
  c->callback([cmd] { run_detect(*cmd); });
}

}  // namespace

OBJMAP_COMMAND(25, "detect", setup_detect);

}  // namespace objmap::app

// `objmap detect` through the binary: a whole folder (fr1_desk_9, 9 frames) that `objmap validate`
// accepts, byte-identical reruns, and every bad input as exit 2 with one line and no output left.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <set>

#include "objmap/segmentation/read.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

using test::run_objmap;
using test::fs::path;

const char* const kCliModels = "../models/yolo-fastest-1.1_coco";

std::size_t line_count(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

// Every file of a folder, name -> bytes.
std::vector<std::pair<std::string, std::string>> files_of(const path& dir) {
  std::vector<std::pair<std::string, std::string>> files;
  for (const auto& entry : test::fs::directory_iterator(dir))
    files.emplace_back(entry.path().filename().string(), test::read_text(entry.path()));
  std::sort(files.begin(), files.end());
  return files;
}

TEST(DetectCli, KeyframesOnlyAndThreads) {
  // --frames keyframes: only the frames fuse will take with this trajectory (motion keeps 3 of
  // fr1_desk_9's 9); the same files as the whole run for those frames, for any thread count.
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, kCliModels);
  test::TempDir tmp;
  const std::string model = (models / "yolo-fastest-1.1-xl.weights").string();
  const std::string gt = (data / "groundtruth.txt").string();
  const auto all = run_objmap({"detect", "--dataset", data.string(), "--model", model, "--out",
                               (tmp / "all").string(), "--threads", "1"});
  ASSERT_EQ(all.exit_code, 0) << all.err;
  const auto kf =
      run_objmap({"detect", "--dataset", data.string(), "--model", model, "--frames", "keyframes",
                  "--trajectory", gt, "--out", (tmp / "kf").string(), "--threads", "2"});
  ASSERT_EQ(kf.exit_code, 0) << kf.err;
  const auto every = files_of(tmp / "all"), keyframes = files_of(tmp / "kf");
  EXPECT_EQ(keyframes.size(), 3u);
  for (const auto& file : keyframes)
    EXPECT_NE(std::find(every.begin(), every.end(), file), every.end()) << file.first;

  // Bad combinations: one line, exit 2, nothing written.
  for (const auto& [extra, flag] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--frames", "keyframes"}, "--trajectory: missing"},
           {{"--frames", "some"}, "--frames: 'some'; expected all or keyframes"},
           {{"--trajectory", gt}, "--trajectory: is used with --frames keyframes only"},
           {{"--threads", "-1"}, "--threads: must be in [0, 64]"}}) {
    std::vector<std::string> args{"detect", "--dataset", data.string(),         "--model",
                                  model,    "--out",     (tmp / "bad").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_objmap(args);
    EXPECT_EQ(r.exit_code, 2) << flag;
    EXPECT_NE(r.err.find(flag), std::string::npos) << r.err;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_FALSE(test::fs::exists(tmp / "bad")) << flag;
  }
}

TEST(DetectCli, WholeFolderValidatesAndRerunsIdentically) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, kCliModels);
  test::TempDir tmp;
  const std::vector<std::string> args = {"detect",
                                         "--dataset",
                                         data.string(),
                                         "--model",
                                         (models / "yolo-fastest-1.1-xl.weights").string(),
                                         "--classes",
                                         "paper"};
  auto first = args;
  first.insert(first.end(), {"--out", (tmp / "seg").string()});
  const auto r = run_objmap(first);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("frames      9, 9 with detections"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("input 320 x 320"), std::string::npos) << r.out;

  const Segmentation seg = read_segmentation(tmp / "seg", {"auto", 640, 480});
  EXPECT_EQ(seg.format, "json");
  ASSERT_EQ(seg.frames.size(), 9u);
  // Every frame has the monitor and the keyboard (as the shared detections), nothing outside the
  // paper's eight classes.
  for (const auto& frame : seg.frames) {
    int monitors = 0, keyboards = 0;
    for (const auto& i : frame.instances) {
      monitors += i.class_name == "tv monitor";
      keyboards += i.class_name == "keyboard";
      EXPECT_NE(i.class_name, "cell phone");
      EXPECT_GT(i.score, 0.25);
    }
    EXPECT_EQ(monitors, 1) << frame.source;
    EXPECT_GE(keyboards, 1) << frame.source;
  }

  const auto v =
      run_objmap({"validate", "--dataset", data.string(), "--trajectory",
                  (data / "groundtruth.txt").string(), "--segmentation", (tmp / "seg").string()});
  ASSERT_EQ(v.exit_code, 0) << v.err;
  EXPECT_NE(v.out.find("format json, 9 frames"), std::string::npos) << v.out;

  auto second = args;
  second.insert(second.end(), {"--out", (tmp / "seg2").string()});
  ASSERT_EQ(run_objmap(second).exit_code, 0);
  EXPECT_EQ(files_of(tmp / "seg"), files_of(tmp / "seg2"));
}

// The whole pipeline from a bare TUM folder and a trajectory: detect -> track -> fuse. On
// fr1_desk_9 the map has the monitor and the keyboard (measured: exactly these 2 objects).
TEST(DetectCli, DetectTrackFuseEndToEnd) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, kCliModels);
  test::TempDir tmp;
  const auto d = run_objmap({"detect", "--dataset", data.string(), "--model",
                             (models / "yolo-fastest-1.1-xl.weights").string(), "--classes",
                             "paper", "--out", (tmp / "seg").string()});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const auto t = run_objmap({"track", "--dataset", data.string(), "--segmentation",
                             (tmp / "seg").string(), "--out", (tmp / "tracked").string()});
  ASSERT_EQ(t.exit_code, 0) << t.err;
  const auto f = run_objmap({"fuse", "--dataset", data.string(), "--trajectory",
                             (data / "groundtruth.txt").string(), "--segmentation",
                             (tmp / "tracked").string(), "--out", (tmp / "run").string()});
  ASSERT_EQ(f.exit_code, 0) << f.err;
  const auto objects = nlohmann::json::parse(test::read_text(tmp / "run" / "objects.json"));
  std::multiset<std::string> classes;
  for (const auto& o : objects["objects"]) classes.insert(o["class"].get<std::string>());
  EXPECT_EQ(classes.count("tv monitor"), 1u) << f.out;
  EXPECT_EQ(classes.count("keyboard"), 1u) << f.out;
  EXPECT_LE(classes.size(), 3u) << f.out;
}

// Runs `objmap detect` on fr1_desk_9 with `extra` arguments and expects exit 2, exactly one line
// on stderr, starting with `start` and containing `needle`, and no output folder.
void expect_exit2(const std::vector<std::string>& extra, const std::string& start,
                  const std::string& needle) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  test::TempDir tmp;
  std::vector<std::string> args = {"detect", "--dataset", data.string(), "--out",
                                   (tmp / "seg").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = run_objmap(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.rfind(start, 0), 0u) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
  EXPECT_FALSE(test::fs::exists(tmp / "seg"));
  for (const auto& entry : test::fs::directory_iterator(tmp.path()))
    ADD_FAILURE() << "left behind: " << entry.path();
}

TEST(DetectCli, MissingModelIsExit2) {
  test::TempDir tmp;
  expect_exit2({"--model", (tmp / "yolo.weights").string()},
               "objmap: error: " + (tmp / "yolo.weights").string() + ": no such file; expected",
               "Darknet YOLO model");
}

TEST(DetectCli, UnreadableWeightsIsExit2) {
  OBJMAP_DATA_OR_SKIP(models, kCliModels);
  test::TempDir tmp;
  test::fs::copy_file(models / "yolo-fastest-1.1.cfg", tmp / "yolo.cfg");
  std::string garbage(4096, '\0');
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<char>(i * 37 % 251);
  test::write_text(tmp / "yolo.weights", garbage);
  expect_exit2({"--model", (tmp / "yolo.weights").string()},
               "objmap: error: " + (tmp / "yolo.weights").string() + ": OpenCV cannot load it",
               "expected a Darknet YOLO model");
}

TEST(DetectCli, WrongKindIsExit2) {
  test::TempDir tmp;
  test::write_text(tmp / "model.txt", "not a model\n");
  expect_exit2({"--model", (tmp / "model.txt").string()},
               "objmap: error: " + (tmp / "model.txt").string() +
                   ": unsupported model kind '.txt'; expected",
               "frozen_inference_graph.pb");
}

// No Mask R-CNN weights exist here: a garbage .pb with a .pbtxt must still fail cleanly.
TEST(DetectCli, UnreadableTensorflowGraphIsExit2) {
  test::TempDir tmp;
  test::write_text(tmp / "frozen_inference_graph.pb", std::string(1000, '\x07'));
  test::write_text(tmp / "mask_rcnn.pbtxt",
                   "node { name: \"image_tensor\" op: \"Placeholder\" }\n");
  expect_exit2({"--model", (tmp / "frozen_inference_graph.pb").string(), "--config",
                (tmp / "mask_rcnn.pbtxt").string()},
               "objmap: error: " + (tmp / "frozen_inference_graph.pb").string() + ": ",
               "Mask R-CNN");
}

// A loadable TensorFlow graph that is not Mask R-CNN (one Relu): no "detection_out_final".
TEST(DetectCli, TensorflowGraphOfAnotherKindIsExit2) {
  test::TempDir tmp;
  test::write_text(tmp / "frozen_inference_graph.pb", std::string("\x22\x00", 2));  // versions {}
  test::write_text(tmp / "relu.pbtxt",
                   "node { name: \"image_tensor\" op: \"Placeholder\" attr { key: \"dtype\" value "
                   "{ type: DT_FLOAT } } }\nnode { name: \"relu\" op: \"Relu\" input: "
                   "\"image_tensor\" }\n");
  expect_exit2({"--model", (tmp / "frozen_inference_graph.pb").string(), "--config",
                (tmp / "relu.pbtxt").string()},
               "objmap: error: " + (tmp / "relu.pbtxt").string() +
                   ": the graph has no layer 'detection_out_final'; expected a Mask R-CNN text "
                   "graph made by OpenCV's tf_text_graph_mask_rcnn.py",
               "");
}

TEST(DetectCli, NoDetectionAtAllIsExit2) {
  OBJMAP_DATA_OR_SKIP(models, kCliModels);
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  expect_exit2(
      {"--model", (models / "yolo-fastest-1.1-xl.weights").string(), "--score-threshold", "1.0"},
      "objmap: error: " + data.string() + ": no detections in any of the 9 frames",
      "score threshold 1");
  // A class never seen in these frames.
  expect_exit2(
      {"--model", (models / "yolo-fastest-1.1-xl.weights").string(), "--classes", "teddy_bear"},
      "objmap: error: " + data.string() +
          ": no detections in any of the 9 frames (classes teddy bear, score threshold "
          "0.25)",
      "expected at least one");
}

TEST(DetectCli, UnknownClassIsExit2) {
  OBJMAP_DATA_OR_SKIP(models, kCliModels);
  expect_exit2(
      {"--model", (models / "yolo-fastest-1.1.weights").string(), "--classes", "chair,chiar"},
      "objmap: error: --classes: 'chiar' is not a class of the model", "80 names");
}

TEST(DetectCli, BadBackendIsExit2) {
  OBJMAP_DATA_OR_SKIP(models, kCliModels);
  OBJMAP_DATA_OR_SKIP(v8, "../models/yolov8n-seg_coco/yolov8n-seg_640x640.onnx");
  const std::string darknet = (models / "yolo-fastest-1.1.weights").string();
  expect_exit2({"--model", darknet, "--backend", "cuda"},
               "objmap: error: --backend: 'cuda'; expected auto, onnxruntime or opencv", "");
  expect_exit2({"--model", darknet, "--backend", "onnxruntime"},
               "objmap: error: --backend: onnxruntime runs ONNX models only", darknet);
  expect_exit2({"--model", v8.string(), "--input-width", "640", "--input-height", "480",
                "--backend", "onnxruntime"},
               "objmap: error: ", "input height is fixed at 640");
  // ONNX Runtime absent (OBJMAP_ONNXRUNTIME names the only file tried): asked for, exit 2 saying
  // how to install it; auto falls back to OpenCV's dnn.
  setenv("OBJMAP_ONNXRUNTIME", "/nonexistent/libonnxruntime.so.1", 1);
  expect_exit2({"--model", v8.string(), "--backend", "onnxruntime"},
               "objmap: error: " + v8.string() + ": ONNX Runtime not found (",
               "scripts/install-deps.sh");
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  test::TempDir tmp;
  const auto r = run_objmap({"detect", "--dataset", data.string(), "--model", v8.string(), "--out",
                             (tmp / "seg").string()});
  unsetenv("OBJMAP_ONNXRUNTIME");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("run by opencv"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace objmap::segmentation

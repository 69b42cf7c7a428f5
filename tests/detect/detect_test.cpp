// The detector stage on its own: Yolo-Fastest on the real fr1_desk_9 frames against the shared
// detections (made with the same model and input size through cv::dnn), the class tables, and the
// errors of a bad model or bad options.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <fstream>

#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "objmap/segmentation/coco_classes.h"
#include "objmap/segmentation/detect.h"
#include "objmap/segmentation/read.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

using test::error_of;
using test::fs::path;

const char* const kModels = "../models/yolo-fastest-1.1_coco";

double iou(const Box& a, const Box& b) {
  const double x1 = std::max(a.x, b.x), y1 = std::max(a.y, b.y);
  const double x2 = std::min(a.x + a.w, b.x + b.w), y2 = std::min(a.y + a.h, b.y + b.h);
  const double inter = std::max(0.0, x2 - x1) * std::max(0.0, y2 - y1);
  return inter / (a.w * a.h + b.w * b.h - inter);
}

TEST(DetectClasses, TablesAgreeWithCoco) {
  ASSERT_EQ(coco90_names().size(), 90u);
  EXPECT_EQ(coco90_names()[0], "person");
  EXPECT_EQ(coco90_names()[71], "tv monitor");  // COCO category 72 "tv"
  EXPECT_EQ(coco90_names()[75], "keyboard");
  EXPECT_EQ(coco90_names()[89], "toothbrush");
  // Every COCO-80 class is one of the 90, in the same order.
  std::size_t at = 0;
  for (const auto& name : coco80_names()) {
    while (at < 90 && coco90_names()[at] != name) ++at;
    EXPECT_LT(at, 90u) << name;
  }
  ASSERT_EQ(paper_detect_classes().size(), 8u);
  for (const auto& name : paper_detect_classes()) EXPECT_GE(coco80_id(name), 0) << name;
}

TEST(DetectOptions, CheckNamesTheBadField) {
  DetectOptions o;
  EXPECT_NO_THROW(o.check());
  o.score_threshold = 1.5;
  EXPECT_EQ(error_of([&] { o.check(); }),
            "DetectOptions.score_threshold: is 1.500000; expected a score in [0, 1]");
  o = {};
  o.nms_threshold = 0;
  EXPECT_NE(error_of([&] { o.check(); }).find("DetectOptions.nms_threshold"), std::string::npos);
  o = {};
  o.input_width = 320;
  EXPECT_NE(error_of([&] { o.check(); }).find("only one is set"), std::string::npos);
}

// The first frame of fr1_desk_9: the monitor and the keyboard, with the boxes of the shared
// detections (Yolo-Fastest-1.1-xl at 320 x 320, scale 1/255, through cv::dnn).
TEST(Detect, FirstFrameMonitorAndKeyboardMatchTheSharedDetections) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, kModels);
  DetectOptions options;
  options.model = models / "yolo-fastest-1.1-xl.weights";
  options.classes = {};  // all: compare with everything the shared file has
  Detector detector(options);
  EXPECT_EQ(detector.info().kind, ModelKind::kDarknetYolo);
  EXPECT_EQ(detector.info().config, models / "yolo-fastest-1.1-xl.cfg");
  EXPECT_EQ(detector.info().input_width, 320);  // from the cfg
  EXPECT_EQ(detector.info().input_height, 320);
  EXPECT_EQ(detector.info().kept_class_ids.size(), 80u);

  const auto frames = list_rgb_frames(data);
  ASSERT_EQ(frames.size(), 9u);
  const cv::Mat image = io::read_rgb(frames[0].rgb_file, 640, 480);
  const auto found = detector.detect(image, frames[0].rgb_file.string());

  const Segmentation shared = read_segmentation(data / "detections_yolofastest");
  ASSERT_EQ(shared.format, "boxes-named");
  const FrameSegmentation& reference = shared.frames.at(0);
  ASSERT_NEAR(reference.timestamp, frames[0].timestamp, 1e-6);
  for (const std::string cls : {"tv monitor", "keyboard"}) {
    const auto ref = std::find_if(reference.instances.begin(), reference.instances.end(),
                                  [&](const Instance& i) { return i.class_name == cls; });
    ASSERT_NE(ref, reference.instances.end()) << cls;
    double best = 0;
    double score = 0;
    for (const auto& i : found)
      if (i.class_name == cls && iou(i.bbox, ref->bbox) > best) {
        best = iou(i.bbox, ref->bbox);
        score = i.score;
      }
    EXPECT_GT(best, 0.9) << cls;
    EXPECT_NEAR(score, ref->score, 0.01) << cls;
  }
  // Same count as the shared frame: tv monitor, keyboard, two cell phones.
  EXPECT_EQ(found.size(), reference.instances.size());
  // Deterministic: the same image gives the same instances.
  const auto again = detector.detect(image);
  ASSERT_EQ(again.size(), found.size());
  for (std::size_t k = 0; k < found.size(); ++k) {
    EXPECT_EQ(again[k].class_name, found[k].class_name);
    EXPECT_EQ(again[k].score, found[k].score);
    EXPECT_EQ(again[k].bbox.x, found[k].bbox.x);
    EXPECT_EQ(again[k].bbox.w, found[k].bbox.w);
  }
}

// Every class the model knows by default; the paper's eight as a preset: the cell phones of the
// first frame are then not kept.
TEST(Detect, DefaultKeepsEveryClassThePaperPresetItsEight) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, kModels);
  DetectOptions options;
  options.model = models / "yolo-fastest-1.1-xl.weights";
  EXPECT_EQ(Detector(options).info().kept_class_ids.size(), 80u);
  options.classes = paper_detect_classes();
  Detector detector(options);
  EXPECT_EQ(detector.info().kept_class_ids, (std::vector<int>{39, 41, 56, 62, 64, 66, 73, 77}));
  const auto frames = list_rgb_frames(data);
  const auto found = detector.detect(io::read_rgb(frames[0].rgb_file, 0, 0));
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].class_name, "tv monitor");
  EXPECT_EQ(found[1].class_name, "keyboard");
  EXPECT_FALSE(found[0].mask.has_value());  // YOLO gives boxes only
}

// The decoding of Mask R-CNN's two outputs, on made-up outputs (no Mask R-CNN weights exist here):
// threshold, class filter, box in pixels, the class's 15 x 15 mask resized into the box.
TEST(DetectDecode, MaskRcnnOutputsGiveBoxesAndMasks) {
  ModelInfo model;
  model.kind = ModelKind::kTensorflowMaskRcnn;
  model.class_names = coco90_names();
  model.kept_class_ids = {61, 71};  // chair, tv monitor
  DetectOptions options;
  options.score_threshold = 0.5;
  const int n = 3, classes = 90;
  const int box_shape[4] = {1, 1, n, 7};
  cv::Mat boxes(4, box_shape, CV_32F, cv::Scalar(0));
  const float rows[n][7] = {{0, 71, 0.9f, 0.1f, 0.2f, 0.5f, 0.6f},   // tv monitor: kept
                            {0, 0, 0.95f, 0.0f, 0.0f, 1.0f, 1.0f},   // person: not a kept class
                            {0, 61, 0.3f, 0.5f, 0.5f, 0.7f, 0.9f}};  // chair below threshold
  std::copy(&rows[0][0], &rows[0][0] + n * 7, boxes.ptr<float>());
  const int mask_shape[4] = {n, classes, 15, 15};
  cv::Mat masks(4, mask_shape, CV_32F, cv::Scalar(0));
  // The monitor's mask: the left 7 of 15 columns; the other classes' masks of that detection are
  // empty (the class of the detection picks its mask).
  float* monitor = masks.ptr<float>(0, 71);
  for (int v = 0; v < 15; ++v)
    for (int u = 0; u < 7; ++u) monitor[v * 15 + u] = 1.f;
  const auto found = decode_outputs(model, options, {boxes, masks}, 640, 480);
  ASSERT_EQ(found.size(), 1u);
  const Instance& tv = found[0];
  EXPECT_EQ(tv.class_name, "tv monitor");
  EXPECT_DOUBLE_EQ(tv.score, 0.9);
  EXPECT_DOUBLE_EQ(tv.bbox.x, 64);
  EXPECT_DOUBLE_EQ(tv.bbox.y, 96);
  EXPECT_DOUBLE_EQ(tv.bbox.w, 256);
  EXPECT_DOUBLE_EQ(tv.bbox.h, 192);
  ASSERT_TRUE(tv.mask.has_value());
  EXPECT_EQ(tv.mask->width, 640);
  EXPECT_EQ(tv.mask->height, 480);
  // About 7/15 of the box, all inside its left part.
  const double share = static_cast<double>(tv.mask->area()) / (256.0 * 192.0);
  EXPECT_NEAR(share, 7.0 / 15.0, 0.04);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u)
      if (tv.mask->at(u, v)) {
        ASSERT_GE(u, 64);
        ASSERT_LT(u, 64 + 128);
        ASSERT_GE(v, 96);
        ASSERT_LE(v, 96 + 192);
      }
  // A class count that is not the model's.
  model.class_names.resize(80);
  EXPECT_NE(error_of([&] {
              decode_outputs(model, options, {boxes, masks}, 640, 480);
            }).find("80 class names but the model outputs 90 classes"),
            std::string::npos);
}

// YOLO rows: centre/size fractions to pixels; NMS across classes (default) or per class.
TEST(DetectDecode, YoloRowsAndNonMaximumSuppression) {
  ModelInfo model;
  model.class_names = coco80_names();
  for (int i = 0; i < 80; ++i) model.kept_class_ids.push_back(i);
  cv::Mat out(3, 85, CV_32F, cv::Scalar(0));
  auto set_row = [&](int r, float cx, float cy, float w, float h, int cls, float score) {
    float* row = out.ptr<float>(r);
    row[0] = cx, row[1] = cy, row[2] = w, row[3] = h, row[4] = score, row[5 + cls] = score;
  };
  set_row(0, 0.5f, 0.5f, 0.25f, 0.5f, 62, 0.8f);   // tv monitor
  set_row(1, 0.51f, 0.5f, 0.25f, 0.5f, 63, 0.6f);  // laptop on the same box
  set_row(2, 0.9f, 0.9f, 0.4f, 0.4f, 56, 0.2f);    // chair below 0.25, over the border
  DetectOptions options;
  auto found = decode_outputs(model, options, {out}, 640, 480);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].class_name, "tv monitor");
  EXPECT_DOUBLE_EQ(found[0].bbox.x, 240);
  EXPECT_DOUBLE_EQ(found[0].bbox.y, 120);
  EXPECT_DOUBLE_EQ(found[0].bbox.w, 160);
  EXPECT_DOUBLE_EQ(found[0].bbox.h, 240);
  EXPECT_FALSE(found[0].mask.has_value());
  options.nms_across_classes = false;
  found = decode_outputs(model, options, {out}, 640, 480);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[1].class_name, "laptop");
  // The chair is kept at a lower threshold, its box clamped to the image.
  options.score_threshold = 0.1;
  found = decode_outputs(model, options, {out}, 640, 480);
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0].class_name, "chair");  // sorted by class id
  EXPECT_DOUBLE_EQ(found[0].bbox.x + found[0].bbox.w, 640);
  EXPECT_DOUBLE_EQ(found[0].bbox.y + found[0].bbox.h, 480);
}

TEST(Detect, ModelErrors) {
  test::TempDir tmp;
  DetectOptions o;
  o.model = tmp / "none.weights";
  EXPECT_EQ(error_of([&] { Detector d(o); }),
            (tmp / "none.weights").string() +
                ": no such file; expected a Darknet YOLO model: .weights with its .cfg, a "
                "TensorFlow Mask R-CNN frozen_inference_graph.pb with its .pbtxt text graph "
                "(--config), or an Ultralytics instance-segmentation export (YOLOv5-seg or "
                "YOLOv8-seg .onnx)");
  test::write_text(tmp / "model.tflite", "x");
  o.model = tmp / "model.tflite";
  EXPECT_NE(error_of([&] { Detector d(o); }).find(": unsupported model kind '.tflite'; expected"),
            std::string::npos);
  // A .pb needs its text graph.
  test::write_text(tmp / "frozen_inference_graph.pb", "x");
  o.model = tmp / "frozen_inference_graph.pb";
  EXPECT_NE(error_of([&] { Detector d(o); }).find("needs its text graph"), std::string::npos);
  o.config = tmp / "graph.cfg";
  test::write_text(tmp / "graph.cfg", "x");
  EXPECT_NE(error_of([&] { Detector d(o); }).find("must be a .pbtxt file"), std::string::npos);
  // Weights without their cfg beside them.
  test::write_text(tmp / "alone.weights", "x");
  o = {};
  o.model = tmp / "alone.weights";
  EXPECT_EQ(error_of([&] { Detector d(o); }),
            (tmp / "alone.cfg").string() +
                ": no such file; expected a Darknet YOLO model: .weights with its .cfg");
}

// A Darknet model of one 1x1 convolution from 3 channels to 1 (a bias and 3 weights, no detector):
// DIR/conv.cfg, and DIR/conv.weights holding `values`, then the bytes `tail`, after a version 0.2
// header.
void write_conv_model(const path& dir, const std::vector<float>& values,
                      const std::string& tail = "") {
  test::write_text(dir / "conv.cfg",
                   "[net]\nwidth=32\nheight=32\nchannels=3\n\n[convolutional]\nfilters=1\nsize=1\n"
                   "stride=1\npad=0\nactivation=linear\n");
  std::ofstream out(dir / "conv.weights", std::ios::binary);
  const std::int32_t version[3] = {0, 2, 0};
  const std::uint64_t seen = 0;
  out.write(reinterpret_cast<const char*>(version), sizeof version);
  out.write(reinterpret_cast<const char*>(&seen), sizeof seen);
  out.write(reinterpret_cast<const char*>(values.data()),
            static_cast<std::streamsize>(values.size() * sizeof(float)));
  out.write(tail.data(), static_cast<std::streamsize>(tail.size()));
}

// A Darknet network that is not a detector (one 1x1 convolution, valid weights): no YOLO layer.
TEST(Detect, DarknetNetworkWithoutYoloLayerIsTheWrongKind) {
  test::TempDir tmp;
  write_conv_model(tmp.path(), {0.f, 1.f, 1.f, 1.f});  // bias, then 3 weights
  DetectOptions o;
  o.model = tmp / "conv.weights";
  EXPECT_EQ(error_of([&] { Detector d(o); }),
            (tmp / "conv.cfg").string() +
                ": the network has no [yolo] or [region] output layer; expected a Darknet YOLO "
                "detector");
}

// OpenCV loads a .weights file that holds fewer or more weights than its cfg asks for without a
// word (and the detector then finds nothing): objmap compares the counts.
TEST(Detect, WeightsThatDoNotFitTheCfgAreNamed) {
  test::TempDir tmp;
  write_conv_model(tmp.path(), {0.f, 1.f, 1.f});  // bias and 2 of the 3 weights
  DetectOptions o;
  o.model = tmp / "conv.weights";
  EXPECT_EQ(error_of([&] { Detector d(o); }),
            (tmp / "conv.weights").string() +
                ": holds 3 weights, fewer than the 4 that conv.cfg asks for (truncated, or made "
                "for another cfg); expected the .weights trained with this .cfg");
  write_conv_model(tmp.path(), {}, "abcdef");  // not whole float32 values
  EXPECT_NE(error_of([&] { Detector d(o); }).find(": not a Darknet weights file"),
            std::string::npos)
      << error_of([&] { Detector d(o); });

  // The real model's xl weights with the smaller model's cfg.
  OBJMAP_DATA_OR_SKIP(models, kModels);
  o.model = models / "yolo-fastest-1.1-xl.weights";
  o.config = models / "yolo-fastest-1.1.cfg";
  EXPECT_EQ(error_of([&] { Detector d(o); }),
            o.model.string() +
                ": holds 923486 weights, more than the 346062 that yolo-fastest-1.1.cfg asks for "
                "(made for another cfg); expected the .weights trained with this .cfg");
}

// A class file that does not fit the model, and a class the model does not have.
TEST(Detect, ClassErrors) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, kModels);
  test::TempDir tmp;
  DetectOptions o;
  o.model = models / "yolo-fastest-1.1.weights";
  o.classes = {"chair", "tvmonitor", "chiar"};
  EXPECT_EQ(error_of([&] { Detector d(o); }),
            "DetectOptions.classes: 'chiar' is not a class of the model (the built-in COCO-80 "
            "names, 80 names); "
            "expected names such as 'chair', 'cup', 'tv monitor', 'keyboard'");
  test::write_text(tmp / "three.names", "chair\ntvmonitor\nkeyboard\n");
  o.classes = {"tv_monitor"};
  o.classes_file = tmp / "three.names";
  Detector detector(o);  // loads: the names are only checked against the output when run
  EXPECT_EQ(detector.info().class_names,
            (std::vector<std::string>{"chair", "tv monitor", "keyboard"}));
  EXPECT_EQ(detector.info().kept_class_ids, std::vector<int>{1});
  const auto frames = list_rgb_frames(data);
  EXPECT_EQ(error_of([&] { detector.detect(io::read_rgb(frames[0].rgb_file, 0, 0)); }),
            (tmp / "three.names").string() +
                ": 3 class names but the model outputs 80 classes; expected a classes file that "
                "fits");
}

}  // namespace
}  // namespace objmap::segmentation

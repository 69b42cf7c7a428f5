// objmap detect with Ultralytics instance-segmentation ONNX exports (segmentation/yolo_seg.h): the
// shared YOLOv5n-seg files on real frames, both layouts on tensors made here, and bad models.
#include "objmap/segmentation/yolo_seg.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "objmap/core/error.h"
#include "objmap/io/dataset.h"
#include "objmap/io/image.h"
#include "objmap/segmentation/detect_compare.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

using test::error_of;
using test::fs::path;

const char* const kSegModels = "../models/yolov5n-seg_coco";

std::size_t area(const Mask& m) {
  std::size_t n = 0;
  for (auto b : m.data) n += b != 0;
  return n;
}

const Instance* find(const std::vector<Instance>& found, const std::string& cls) {
  for (const auto& i : found)
    if (i.class_name == cls) return &i;
  return nullptr;
}

std::vector<Instance> detect_first_frame(const path& dataset, const path& model,
                                         double score_threshold = 0.25) {
  DetectOptions options;
  options.model = model;
  options.classes = {};
  options.score_threshold = score_threshold;
  Detector detector(options);
  EXPECT_EQ(detector.info().kind, ModelKind::kOnnxYoloSeg);
  const auto frames = list_rgb_frames(dataset);
  return detector.detect(io::read_rgb(frames[0].rgb_file, 640, 480), "frame 0");
}

TEST(YoloSeg, Fr1DeskMonitorAndMouseFromBothInputSizes) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, kSegModels);
  EXPECT_EQ(onnx_input_shape(models / "yolov5n-seg_480x640.onnx"),
            (std::vector<std::int64_t>{1, 3, 480, 640}));
  const auto plain = detect_first_frame(data, models / "yolov5n-seg_480x640.onnx");
  const auto boxed = detect_first_frame(data, models / "yolov5n-seg_640x640.onnx");  // letterbox
  for (const auto* found : {&plain, &boxed}) {
    const Instance* tv = find(*found, "tv monitor");
    ASSERT_NE(tv, nullptr);
    ASSERT_TRUE(tv->mask.has_value());
    const std::size_t pixels = area(*tv->mask);
    EXPECT_GE(pixels, 40000u);  // the monitor's outline and stand (the data README: 47,646)
    EXPECT_LE(pixels, 55000u);
    std::size_t outside = 0;
    for (int v = 0; v < 480; ++v)
      for (int u = 0; u < 640; ++u)
        if (tv->mask->at(u, v) && (u < tv->bbox.x - 1 || u > tv->bbox.x + tv->bbox.w + 1 ||
                                   v < tv->bbox.y - 1 || v > tv->bbox.y + tv->bbox.h + 1))
          ++outside;
    EXPECT_EQ(outside, 0u) << "the mask lies inside its box";
    EXPECT_NE(find(*found, "mouse"), nullptr);
  }
  EXPECT_GE(find(plain, "tv monitor")->score, 0.5);
  EXPECT_GE(mask_iou(*find(plain, "tv monitor")->mask, *find(boxed, "tv monitor")->mask), 0.9)
      << "the letterbox is undone";
}

TEST(YoloSeg, YcbVideoGelatinBoxAsBookMatchesTheLabelMask) {
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f");
  OBJMAP_DATA_OR_SKIP(models, kSegModels);
  const auto found = detect_first_frame(data, models / "yolov5n-seg_480x640.onnx", 0.1);
  const Instance* book = find(found, "book");
  ASSERT_NE(book, nullptr);
  const cv::Mat labels =
      cv::imread((data / "masks" / "0.000000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(labels.empty());
  Mask gelatin;
  gelatin.width = 640;
  gelatin.height = 480;
  gelatin.data.assign(640 * 480, 0);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) gelatin.data[v * 640 + u] = labels.at<std::uint8_t>(v, u) == 8;
  EXPECT_GE(mask_iou(*book->mask, gelatin), 0.9);  // measured 0.960
}

// The YOLOv8-seg export of ../shared/models (its own output layout: [1, 116, 8400], no
// objectness) on real frames: the monitor of fr1_desk_9 as YOLOv5n-seg finds it, and the kitchen
// table of 7-Scenes that YOLOv5n-seg misses (docs/cli.md "Which model finds what").
const char* const kV8Model = "../models/yolov8n-seg_coco/yolov8n-seg_640x640.onnx";

TEST(YoloSeg, YoloV8ExportFindsTheMonitorAsYoloV5Does) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(v8, kV8Model);
  OBJMAP_DATA_OR_SKIP(v5, kSegModels);
  const auto found = detect_first_frame(data, v8);
  const Instance* tv = find(found, "tv monitor");
  ASSERT_NE(tv, nullptr);
  ASSERT_TRUE(tv->mask.has_value());
  EXPECT_GE(tv->score, 0.5);
  const auto v5_found = detect_first_frame(data, v5 / "yolov5n-seg_480x640.onnx");
  ASSERT_NE(find(v5_found, "tv monitor"), nullptr);
  EXPECT_GE(mask_iou(*tv->mask, *find(v5_found, "tv monitor")->mask), 0.8)
      << "the two models agree on the monitor's outline";
}

TEST(YoloSeg, YoloV8ExportFindsTheKitchenTableThatYoloV5Misses) {
  OBJMAP_DATA_OR_SKIP(data, "7scenes_redkitchen_3dmatch_50f");
  OBJMAP_DATA_OR_SKIP(v8, kV8Model);
  OBJMAP_DATA_OR_SKIP(v5, kSegModels);
  const io::Dataset scenes = io::read_dataset(data);
  const cv::Mat image = io::read_rgb(scenes.frames[0].rgb_file, 640, 480);
  auto detect = [&](const path& model) {
    DetectOptions options;
    options.model = model;
    options.classes = {};
    return Detector(options).detect(image, "frame 0");
  };
  const auto with_v8 = detect(v8);
  const Instance* table = find(with_v8, "dining table");
  ASSERT_NE(table, nullptr);
  ASSERT_TRUE(table->mask.has_value());
  EXPECT_GE(area(*table->mask), 20000u) << "a table top, not a speck";
  EXPECT_EQ(find(detect(v5 / "yolov5n-seg_480x640.onnx"), "dining table"), nullptr);
}

// output0 rows for one object: a box (cx, cy, w, h in input pixels) of class `cls`, objectness 1,
// mask coefficients (1, 0, ..., 0); output1: prototype 0 is +8 on rows [y0, y1) of the prototype
// grid and -8 elsewhere, the others 0. v8 = the same without objectness, transposed.
struct Tensors {
  cv::Mat detections, protos;
};
Tensors make_tensors(bool v8, int classes, int input_w, int input_h, float cx, float cy, float w,
                     float h, int cls, int y0, int y1) {
  const int columns = (v8 ? 4 : 5) + classes + 32;
  const int rows = 3;  // the object, a weak duplicate of it, an empty row
  int dsize[3] = {1, v8 ? columns : rows, v8 ? rows : columns};
  Tensors t;
  t.detections = cv::Mat(3, dsize, CV_32F, cv::Scalar(0));
  auto set = [&](int row, int column, float value) {
    float* d = t.detections.ptr<float>();
    if (v8)
      d[column * rows + row] = value;
    else
      d[row * columns + column] = value;
  };
  const int first_class = v8 ? 4 : 5;
  for (int row : {0, 1}) {
    set(row, 0, cx + row), set(row, 1, cy), set(row, 2, w), set(row, 3, h);
    if (!v8) set(row, 4, 1.f);
    set(row, first_class + cls, row == 0 ? 0.9f : 0.6f);
    set(row, first_class + classes, 1.f);  // coefficient 0
  }
  const int ph = input_h / 4, pw = input_w / 4;
  int psize[4] = {1, 32, ph, pw};
  t.protos = cv::Mat(4, psize, CV_32F, cv::Scalar(0));
  float* p = t.protos.ptr<float>();
  for (int v = 0; v < ph; ++v)
    for (int u = 0; u < pw; ++u) p[v * pw + u] = (v >= y0 && v < y1) ? 8.f : -8.f;
  return t;
}

ModelInfo four_classes() {
  ModelInfo m;
  m.kind = ModelKind::kOnnxYoloSeg;
  m.model = "made-in-the-test.onnx";
  m.class_names = {"cup", "book", "mouse", "keyboard"};
  m.kept_class_ids = {0, 1, 2, 3};
  return m;
}

TEST(YoloSeg, BothLayoutsDecodeToTheSameInstances) {
  // A 640x480 frame in a 640x640 input: letterboxed 80 px down. The box spans input rows 180-300
  // (frame rows 100-220); prototype rows 50-60 (input rows 200-240, frame rows 120-160) are on.
  const Letterbox lb = make_letterbox(640, 480, 640, 640);
  EXPECT_EQ(lb.pad_x, 0);
  EXPECT_EQ(lb.pad_y, 80);
  EXPECT_DOUBLE_EQ(lb.scale, 1.0);
  DetectOptions options;
  options.classes = {};
  const ModelInfo model = four_classes();
  std::vector<Instance> decoded[2];
  for (bool v8 : {false, true}) {
    const Tensors t = make_tensors(v8, 4, 640, 640, 320, 240, 100, 120, 1, 50, 60);
    EXPECT_EQ(yolo_seg_layout(t.detections, t.protos, 4, "m"),
              v8 ? YoloSegLayout::kV8 : YoloSegLayout::kV5);
    decoded[v8] = decode_yolo_seg(model, options, t.detections, t.protos, lb);
  }
  for (const auto& found : decoded) {
    ASSERT_EQ(found.size(), 1u) << "the weaker duplicate is suppressed";
    EXPECT_EQ(found[0].class_name, "book");
    EXPECT_NEAR(found[0].score, 0.9, 1e-6);
    EXPECT_NEAR(found[0].bbox.x, 270, 1e-9);
    EXPECT_NEAR(found[0].bbox.y, 100, 1e-9);
    EXPECT_NEAR(found[0].bbox.w, 100, 1e-9);
    EXPECT_NEAR(found[0].bbox.h, 120, 1e-9);
    ASSERT_TRUE(found[0].mask.has_value());
    // Rows 120-159 of the frame, columns 270-369: 40 x 100 pixels (+-1 row of interpolation).
    EXPECT_NEAR(static_cast<double>(area(*found[0].mask)), 4000.0, 200.0);
    EXPECT_TRUE(found[0].mask->at(320, 140));
    EXPECT_FALSE(found[0].mask->at(320, 100)) << "outside the prototype's rows";
    EXPECT_FALSE(found[0].mask->at(250, 140)) << "outside the box";
  }
  EXPECT_EQ(decoded[0][0].mask->data, decoded[1][0].mask->data);

  // A class filter and a threshold above the score leave nothing.
  options.score_threshold = 0.95;
  const Tensors t = make_tensors(false, 4, 640, 640, 320, 240, 100, 120, 1, 50, 60);
  EXPECT_TRUE(decode_yolo_seg(model, options, t.detections, t.protos, lb).empty());
}

TEST(YoloSeg, OutputsOfAnotherShapeAreNamed) {
  const Tensors t = make_tensors(false, 4, 640, 640, 320, 240, 100, 120, 1, 50, 60);
  const std::string message = error_of([&] { yolo_seg_layout(t.detections, t.protos, 80, "m"); });
  EXPECT_NE(message.find("output0 [1, 3, 41]"), std::string::npos) << message;
  EXPECT_NE(message.find("for 80 classes"), std::string::npos) << message;
  EXPECT_NE(message.find("YOLOv5-seg [1, N, 117]"), std::string::npos) << message;
}

// A minimal ONNX model written here (protobuf by hand): one Identity node, input x [1, 3, 8, 8],
// output y. A network with one output: no mask prototypes.
std::string field(int number, const std::string& bytes) {
  std::string out;
  auto varint = [&](std::uint64_t v) {
    do {
      out.push_back(static_cast<char>((v & 0x7f) | (v > 0x7f ? 0x80 : 0)));
      v >>= 7;
    } while (v);
  };
  varint(static_cast<std::uint64_t>(number) << 3 | 2);
  varint(bytes.size());
  return out + bytes;
}
std::string varint_field(int number, std::uint64_t value) {
  std::string out(1, static_cast<char>(number << 3));
  do {
    out.push_back(static_cast<char>((value & 0x7f) | (value > 0x7f ? 0x80 : 0)));
    value >>= 7;
  } while (value);
  return out;
}
std::string identity_onnx() {
  std::string dims;
  for (int d : {1, 3, 8, 8}) dims += field(1, varint_field(1, d));
  const std::string type = field(1, varint_field(1, 1) + field(2, dims));  // float tensor
  const std::string node = field(1, "x") + field(2, "y") + field(4, "Identity");
  const std::string graph = field(1, node) + field(2, "g") +
                            field(11, field(1, "x") + field(2, type)) +
                            field(12, field(1, "y") + field(2, type));
  return varint_field(1, 7) + field(7, graph) + field(8, varint_field(2, 12));
}

TEST(YoloSeg, ModelsThatAreNotSegmentationExportsAreNamed) {
  test::TempDir dir;
  const path identity = dir / "identity.onnx";
  {
    std::ofstream out(identity, std::ios::binary);
    out << identity_onnx();
  }
  EXPECT_EQ(onnx_input_shape(identity), (std::vector<std::int64_t>{1, 3, 8, 8}));
  DetectOptions options;
  options.model = identity;
  std::string message = error_of([&] { Detector d(options); });
  EXPECT_NE(message.find("has 1 output(s); expected 2"), std::string::npos) << message;
  EXPECT_NE(message.find("without masks"), std::string::npos) << message;

  const path garbage = dir / "garbage.onnx";
  {
    std::ofstream out(garbage, std::ios::binary);
    out << "not a model at all";
  }
  options.model = garbage;
  message = error_of([&] { Detector d(options); });
  EXPECT_NE(message.find("garbage.onnx"), std::string::npos) << message;

  options.model = dir / "missing.onnx";
  message = error_of([&] { Detector d(options); });
  EXPECT_NE(message.find("no such file"), std::string::npos) << message;
}

}  // namespace
}  // namespace objmap::segmentation

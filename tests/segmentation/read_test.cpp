#include "objmap/segmentation/read.h"

#include <gtest/gtest.h>

#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "objmap/core/error.h"
#include "objmap/segmentation/rle.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

namespace fs = std::filesystem;
using test::error_of;
using test::TempDir;
using test::write_text;

#define EXPECT_ERROR_HAS(call, text) \
  EXPECT_NE(error_of([&] { call; }).find(text), std::string::npos) << error_of([&] { call; })

ReadOptions vga() {
  ReadOptions options;
  options.image_width = 640;
  options.image_height = 480;
  return options;
}

std::size_t count_instances(const Segmentation& segmentation) {
  std::size_t n = 0;
  for (const auto& frame : segmentation.frames) n += frame.instances.size();
  return n;
}

// ---- real data ---------------------------------------------------------------------------------

TEST(ReadReal, Fr1DeskBoxesNamed) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_desk_9/detections_yolofastest");
  EXPECT_EQ(detect_format(dir), "boxes-named");
  const Segmentation seg = read_segmentation(dir, vga());
  EXPECT_EQ(seg.format, "boxes-named");
  ASSERT_EQ(seg.frames.size(), 9u);
  EXPECT_EQ(count_instances(seg), 30u);
  const FrameSegmentation& first = seg.frames.front();
  EXPECT_DOUBLE_EQ(first.timestamp, 1305031453.359684);
  ASSERT_EQ(first.instances.size(), 4u);
  // "62 tvmonitor 0.805013 14 0 231 233"
  const Instance& tv = first.instances[0];
  EXPECT_EQ(tv.class_name, "tv monitor");
  EXPECT_DOUBLE_EQ(tv.score, 0.805013);
  EXPECT_EQ(tv.bbox.x, 14);
  EXPECT_EQ(tv.bbox.y, 0);
  EXPECT_EQ(tv.bbox.w, 217);
  EXPECT_EQ(tv.bbox.h, 233);
  EXPECT_FALSE(tv.track_id);
  EXPECT_FALSE(tv.mask);
  EXPECT_EQ(first.instances[2].class_name, "cell phone");
  EXPECT_DOUBLE_EQ(seg.frames.back().timestamp, 1305031453.627706);
  for (std::size_t i = 1; i < seg.frames.size(); ++i) {
    EXPECT_LT(seg.frames[i - 1].timestamp, seg.frames[i].timestamp);
  }
}

TEST(ReadReal, Fr1RpyBoxesNamedWithEmptyFrames) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_rpy_every4/detections_yolofastest");
  const Segmentation seg = read_segmentation(dir, vga());
  EXPECT_EQ(seg.format, "boxes-named");
  ASSERT_EQ(seg.frames.size(), 174u);
  EXPECT_EQ(count_instances(seg), 521u);
  std::size_t empty = 0;
  for (const auto& frame : seg.frames) empty += frame.instances.empty();
  EXPECT_EQ(empty, 11u);
  EXPECT_EQ(seg.frames[0].instances.at(0).class_name,
            "laptop");  // "63 laptop 0.502414 208 51 455 292"
  EXPECT_EQ(seg.frames[0].instances.at(0).bbox.w, 247);
}

TEST(ReadReal, Fr3LongOfficeBoxesCoco) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr3_long_office_household_annotations/detections_yolo");
  EXPECT_EQ(detect_format(dir), "boxes-coco");
  const Segmentation seg = read_segmentation(dir, vga());  // speed: bench_fusion
  ASSERT_EQ(seg.frames.size(), 2585u);
  EXPECT_EQ(count_instances(seg), 17225u);
  // First line of 1341847980.722988.txt: "73 173 138 46 70 0.578918", (x, y) the top-left corner.
  const Instance& book = seg.frames[0].instances.at(0);
  EXPECT_DOUBLE_EQ(seg.frames[0].timestamp, 1341847980.722988);
  EXPECT_EQ(seg.frames[0].instances.size(), 7u);
  EXPECT_EQ(book.class_name, "book");
  EXPECT_DOUBLE_EQ(book.score, 0.578918);
  EXPECT_EQ(book.bbox.x, 173);
  EXPECT_EQ(book.bbox.y, 138);
  EXPECT_EQ(book.bbox.w, 46);
  EXPECT_EQ(book.bbox.h, 70);
  // Every box in the image after clamping; the one 7 px past the right border
  // (1341847989.166672: "56 502 158 145 198") is clamped to x + w = 640.
  bool found = false;
  for (const auto& frame : seg.frames) {
    for (const auto& instance : frame.instances) {
      ASSERT_LE(instance.bbox.x + instance.bbox.w, 640.0);
      ASSERT_LE(instance.bbox.y + instance.bbox.h, 480.0);
      if (std::abs(frame.timestamp - 1341847989.166672) < 1e-6 && instance.bbox.x == 502) {
        EXPECT_EQ(instance.class_name, "chair");
        EXPECT_EQ(instance.bbox.w, 138);
        found = true;
      }
    }
  }
  EXPECT_TRUE(found);
}

TEST(ReadReal, Fr3CabinetBoxesXywh) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr3_cabinet_58kf/boxes_yolov2");
  EXPECT_EQ(detect_format(dir), "boxes-xywh");
  ReadOptions options = vga();
  options.default_class = "Cabinet";
  const Segmentation seg = read_segmentation(dir, options);
  ASSERT_EQ(seg.frames.size(), 58u);
  EXPECT_EQ(count_instances(seg), 51u);
  std::size_t empty = 0;
  for (const auto& frame : seg.frames) empty += frame.instances.empty();
  EXPECT_EQ(empty, 7u);
  // 1341841278.8427.txt: "175\t24\t385\t373\t0.42"
  EXPECT_DOUBLE_EQ(seg.frames[0].timestamp, 1341841278.8427);
  const Instance& cabinet = seg.frames[0].instances.at(0);
  EXPECT_EQ(cabinet.class_name, "cabinet");
  EXPECT_DOUBLE_EQ(cabinet.score, 0.42);
  EXPECT_EQ(cabinet.bbox.x, 175);
  EXPECT_EQ(cabinet.bbox.w, 385);
  EXPECT_EQ(cabinet.bbox.h, 373);
  EXPECT_EQ(read_segmentation(dir).frames[0].instances.at(0).class_name, "object");
}

TEST(ReadReal, YcbvPngWithClassesTxt) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f/masks");
  EXPECT_EQ(detect_format(dir), "png");
  const Segmentation seg = read_segmentation(dir, vga());
  EXPECT_EQ(seg.format, "png");
  ASSERT_EQ(seg.frames.size(), 10u);
  EXPECT_DOUBLE_EQ(seg.frames[0].timestamp, 0.0);
  EXPECT_DOUBLE_EQ(seg.frames[9].timestamp, 0.3);
  const std::vector<std::pair<std::string, int>> expected = {
      {"009 gelatin box", 8}, {"025 mug", 14}, {"061 foam brick", 21}};
  for (const auto& frame : seg.frames) {
    ASSERT_EQ(frame.instances.size(), 3u) << frame.source;
    for (std::size_t i = 0; i < 3; ++i) {
      const Instance& instance = frame.instances[i];
      EXPECT_EQ(instance.class_name, expected[i].first);
      EXPECT_EQ(instance.track_id, expected[i].second);
      EXPECT_EQ(instance.score, 1.0);
      ASSERT_TRUE(instance.mask);
      EXPECT_EQ(instance.mask->width, 640);
      EXPECT_EQ(instance.mask->height, 480);
      EXPECT_GT(instance.mask->area(), 500u);
      // bbox is the tight box of the mask: a pixel on its top row and on its left column
      const int x = static_cast<int>(instance.bbox.x), y = static_cast<int>(instance.bbox.y);
      const int w = static_cast<int>(instance.bbox.w), h = static_cast<int>(instance.bbox.h);
      ASSERT_GT(w, 0);
      ASSERT_LE(x + w, 640);
      ASSERT_LE(y + h, 480);
      bool top = false, left = false;
      for (int u = x; u < x + w; ++u) top = top || instance.mask->at(u, y);
      for (int v = y; v < y + h; ++v) left = left || instance.mask->at(x, v);
      EXPECT_TRUE(top && left);
    }
  }
  // First frame, checked independently (PNG decoded to PPM outside OpenCV, pixels counted in
  // Python): value 8: 18265 px, box [186, 132, 139, 191]; 14: 20100, [335, 106, 169, 189]; 21:
  // 22265, [379, 216, 161, 189].
  const std::vector<std::pair<std::size_t, std::vector<double>>> first = {
      {18265, {186, 132, 139, 191}}, {20100, {335, 106, 169, 189}}, {22265, {379, 216, 161, 189}}};
  for (std::size_t i = 0; i < 3; ++i) {
    const Instance& instance = seg.frames[0].instances[i];
    EXPECT_EQ(instance.mask->area(), first[i].first);
    EXPECT_EQ(
        (std::vector<double>{instance.bbox.x, instance.bbox.y, instance.bbox.w, instance.bbox.h}),
        first[i].second);
  }
  // The mask size is checked against the image size.
  ReadOptions small;
  small.image_width = 320;
  small.image_height = 240;
  EXPECT_ERROR_HAS(read_segmentation(dir, small),
                   "0.000000.png: mask is 640x480 (w x h); expected the image size 320x240");
}

// ---- malformed copies and synthetic folders ----------------------------------------------------

// FrameReader lists the frames and tells the format up front, and reads a frame only when asked:
// a malformed later frame is an error of that frame's read, not of the listing.
TEST(FrameReader, ReadsOneFrameWhenAsked) {
  TempDir tmp;
  write_text(tmp / "2.5.json",
             "{\"instances\":[{\"class\":\"cup\",\"score\":0.5,\"bbox\":[1,2,3,4]}]}\n");
  write_text(tmp / "1.0.json", "{\"instances\":[]}\n");
  write_text(tmp / "3.0.json", "{\"instances\":[{\"class\":");
  const FrameReader reader(tmp.path());
  EXPECT_EQ(reader.format(), "json");
  ASSERT_EQ(reader.size(), 3u);
  EXPECT_EQ(reader.frames()[0].timestamp, 1.0);
  EXPECT_EQ(reader.frames()[1].timestamp, 2.5);
  EXPECT_EQ(reader.frames()[2].path, tmp / "3.0.json");
  const FrameSegmentation second = reader.read(1);
  EXPECT_EQ(second.timestamp, 2.5);
  ASSERT_EQ(second.instances.size(), 1u);
  EXPECT_EQ(second.instances[0].class_name, "cup");
  EXPECT_EQ(second.instances[0].bbox.w, 3.0);
  EXPECT_TRUE(reader.read(0).instances.empty());
  EXPECT_ERROR_HAS(reader.read(2), (tmp / "3.0.json").string() + ":1: malformed JSON");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()),
                   (tmp / "3.0.json").string() + ":1: malformed JSON");
}

TEST(ReadBoxes, TextInNumberField) {
  TempDir tmp;
  write_text(tmp / "1.0.txt",
             "# class_id class_name score x1 y1 x2 y2\n62 tvmonitor 0.8 14 zero 231 233\n");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "1.0.txt").string() + ":2: y1 is 'zero'; expected a finite number");
}

TEST(ReadBoxes, ScoreOutsideUnitInterval) {
  TempDir tmp;
  write_text(tmp / "1.0.txt", "56 10 10 20 20 1.5\n");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "1.0.txt").string() + ":1: score 1.5; expected a number in [0, 1]");
}

TEST(ReadBoxes, UnknownClassId) {
  TempDir tmp;
  write_text(tmp / "1.0.txt", "80 10 10 20 20 0.5\n");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "1.0.txt").string() +
                ":1: coco80_id 80; expected a COCO-80 class id 0..79 (coco.names order)");
  write_text(tmp / "1.0.txt", "81 tvmonitor 0.8 14 0 231 233\n");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()), ":1: class_id 81; expected a COCO-80 class id");
}

TEST(ReadBoxes, NameNotMatchingId) {
  TempDir tmp;
  write_text(tmp / "1.0.txt", "62 cup 0.8 14 0 231 233\n");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()),
                   ":1: class_name 'cup' does not match class_id 62; expected 'tv monitor'");
}

TEST(ReadBoxes, BoxOutsideImageRejectedAndWithinToleranceClamped) {
  TempDir tmp;
  write_text(tmp / "1.0.txt", "10 10 100 100 0.5\n");
  write_text(tmp / "2.0.txt", "600 10 50 100 0.5\n");  // ends at x = 650: 10 px past 640
  write_text(tmp / "3.0.txt", "-1.5 10 50 100 0.5\n");
  ReadOptions options = vga();
  const Segmentation seg = read_segmentation(tmp.path(), options);
  EXPECT_EQ(seg.frames[1].instances[0].bbox.w, 40);  // clamped to the border
  EXPECT_EQ(seg.frames[2].instances[0].bbox.x, 0);
  EXPECT_EQ(seg.frames[2].instances[0].bbox.w, 48.5);
  write_text(tmp / "2.0.txt", "600 10 50.5 100 0.5\n");  // 10.5 px past the border
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path(), options); }),
            (tmp / "2.0.txt").string() +
                ":1: box [600, 10, 50.5, 100] (x y w h) ends at x = 650.5, past the image width "
                "640 by more than 10 px");
  write_text(tmp / "2.0.txt", "10 -20 50 100 0.5\n");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path(), options),
                   "2.0.txt:1: box [10, -20, 50, 100] (x y w h) starts above the image by more "
                   "than 10 px");
  options.box_tolerance_px = 0;
  write_text(tmp / "2.0.txt", "10 10 631 100 0.5\n");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path(), options), "past the image width 640");
}

TEST(ReadBoxes, WrongFieldCountNamesTheLayout) {
  TempDir tmp;
  write_text(tmp / "1.0.txt", "56 10 10 20 20 0.5\n56 10 10 20 20\n");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "1.0.txt").string() + ":2: 5 fields; expected 6: coco80_id x y w h score");
}

TEST(ReadBoxes, FormatOverridesDetection) {
  TempDir tmp;
  write_text(tmp / "1.0.txt", "56 10 10 20 20\n");
  EXPECT_EQ(detect_format(tmp.path()), "boxes-xywh");
  ReadOptions options;
  options.format = "boxes-coco";
  EXPECT_ERROR_HAS(read_segmentation(tmp.path(), options), ":1: 5 fields; expected 6");
}

TEST(ReadFolder, EmptyFolder) {
  TempDir tmp;
  EXPECT_ERROR_HAS(detect_format(tmp.path()), ": empty folder; expected <timestamp>.json");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()), ": empty folder; expected");
  ReadOptions options;
  options.format = "json";
  EXPECT_ERROR_HAS(read_segmentation(tmp.path(), options),
                   "no frame for format json: empty folder; expected <timestamp>.json files");
}

TEST(ReadFolder, NothingRecognisable) {
  TempDir tmp;
  write_text(tmp / "notes.md", "hello\n");
  write_text(tmp / "frame_01.txt", "1 2 3 4 0.5\n");
  EXPECT_EQ(error_of([&] { detect_format(tmp.path()); }),
            tmp.path().string() +
                ": nothing recognisable: found 2 other ('frame_01.txt', 'notes.md'); expected "
                "<timestamp>.json (canonical), <timestamp>.png label images (with "
                "<timestamp>.instances.json or classes.txt), <timestamp>/<class>/<track_id>.txt "
                "pixel lists (paper), or <timestamp>.txt box files (class_id class_name score x1 "
                "y1 x2 y2 | coco80_id x y w h score | x y w h score)");
}

TEST(ReadFolder, MissingFolderAndMixedKinds) {
  TempDir tmp;
  EXPECT_ERROR_HAS(detect_format(tmp / "nope"), "nope: no such folder");
  write_text(tmp / "1.0.txt", "1 2 3 4 0.5\n");
  write_text(tmp / "1.0.json", "{\"instances\":[]}");
  EXPECT_ERROR_HAS(detect_format(tmp.path()),
                   ": found 1 <timestamp>.json, 1 <timestamp>.txt; cannot tell which");
}

TEST(ReadFolder, UnknownBoxLayout) {
  TempDir tmp;
  write_text(tmp / "1.0.txt", "# header\n1 2\n");
  EXPECT_EQ(error_of([&] { detect_format(tmp.path()); }),
            (tmp / "1.0.txt").string() +
                ":2: 2 fields \"1 2\"; cannot tell the box layout, expected \"class_id class_name "
                "score x1 y1 x2 y2\", \"coco80_id x y w h score\" or \"x y w h score\"");
}

TEST(ReadOptionsCheck, RejectsBadFields) {
  ReadOptions options;
  options.format = "yaml";
  EXPECT_ERROR_HAS(options.check(), "ReadOptions.format: 'yaml'; expected auto, json, png");
  options = ReadOptions{};
  options.image_width = 640;
  EXPECT_ERROR_HAS(options.check(), "expected both > 0");
}

// ---- canonical JSON ----------------------------------------------------------------------------

TEST(ReadJson, MaskBboxAndDefaults) {
  TempDir tmp;
  // "S152M2": the 8x6 hand vector of rle_test.cpp, 1-pixels in columns 4..5, rows 2..7.
  write_text(tmp / "2.5.json",
             R"({"instances":[{"class":"TV_monitor","score":0.5,"track_id":3,
                 "mask":{"size":[8,6],"counts":"S152M2"}},
                {"class":"cup","bbox":[1,2,3,4]}]})");
  write_text(tmp / "1.5.json", R"({"instances":[]})");
  const Segmentation seg = read_segmentation(tmp.path());
  EXPECT_EQ(seg.format, "json");
  ASSERT_EQ(seg.frames.size(), 2u);
  EXPECT_EQ(seg.frames[0].timestamp, 1.5);
  const Instance& tv = seg.frames[1].instances.at(0);
  EXPECT_EQ(tv.class_name, "tv monitor");
  EXPECT_EQ(tv.track_id, 3);
  ASSERT_TRUE(tv.mask);
  EXPECT_EQ(tv.mask->area(), 7u);
  EXPECT_EQ(tv.bbox.x, 4);
  EXPECT_EQ(tv.bbox.y, 2);
  EXPECT_EQ(tv.bbox.w, 2);
  EXPECT_EQ(tv.bbox.h, 6);
  const Instance& cup = seg.frames[1].instances.at(1);
  EXPECT_EQ(cup.score, 1.0);
  EXPECT_FALSE(cup.track_id);
  EXPECT_FALSE(cup.mask);
  EXPECT_EQ(cup.bbox.h, 4);
}

TEST(ReadJson, MalformedJsonSaysWhere) {
  TempDir tmp;
  write_text(tmp / "1.0.json", "{\"instances\": [\n  {\"class\": \"cup\", \"score\": 0.9,}\n]}\n");
  const std::string message = error_of([&] { read_segmentation(tmp.path()); });
  EXPECT_EQ(
      message.rfind((tmp / "1.0.json").string() +
                        ":2: malformed JSON at column 33: syntax error while parsing object key - "
                        "unexpected '}'; expected string literal",
                    0),
      0u)
      << message;
}

TEST(ReadJson, BadRleString) {
  TempDir tmp;
  write_text(tmp / "1.0.json",
             R"({"instances":[{"class":"cup","mask":{"size":[3,3],"counts":"33!N"}}]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "1.0.json").string() +
                ": instances[0].mask.counts: character '!' at position 2; expected '0'..'o'");
}

TEST(ReadJson, RleCountsNotSummingToSize) {
  TempDir tmp;
  write_text(tmp / "1.0.json",
             R"({"instances":[{"class":"cup","mask":{"size":[3,4],"counts":"332N"}}]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "1.0.json").string() +
                ": instances[0].mask.counts: 4 runs summing to 9 pixels; expected h*w = 3*4 = 12");
}

TEST(ReadJson, MaskSizeDiffersFromImage) {
  TempDir tmp;
  write_text(tmp / "1.0.json",
             R"({"instances":[{"class":"cup","mask":{"size":[3,3],"counts":"332N"}}]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path(), vga()); }),
            (tmp / "1.0.json").string() +
                ": instances[0].mask.size: mask is 3x3 (w x h); expected the image size 640x480");
}

TEST(ReadJson, FieldErrors) {
  TempDir tmp;
  const auto file = (tmp / "1.0.json").string();
  write_text(tmp / "1.0.json",
             R"({"instances":[{"class":"cup","score":"high","bbox":[0,0,1,1]}]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            file + ": instances[0].score: string \"high\"; expected a number in [0, 1]");
  write_text(tmp / "1.0.json", R"({"instances":[{"class":"cup","score":-0.1,"bbox":[0,0,1,1]}]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            file + ": instances[0].score: score -0.1; expected a number in [0, 1]");
  write_text(tmp / "1.0.json", R"({"instances":[{"class":"cup"}]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            file + ": instances[0]: neither bbox nor mask; expected at least one of them");
  write_text(tmp / "1.0.json", R"({"instances":[{"score":0.5,"bbox":[0,0,1,1]}]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            file + ": instances[0].class: missing; expected a class name string");
  write_text(tmp / "1.0.json", R"({"instances":[{"class":"cup","bbox":[0,0,1]}]})");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()),
                   "instances[0].bbox: [0,0,1]; expected [x, y, w, h]");
  write_text(tmp / "1.0.json", R"({"instances":[{"class":"cup","bbox":[700,0,10,10]}]})");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path(), vga()),
                   "instances[0].bbox: box [700, 0, 10, 10] (x y w h) ends at x = 710");
  write_text(tmp / "1.0.json", R"({"objects":[]})");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            file + ": instances: missing; expected {\"instances\":[...]}");
}

// ---- PNG with sidecar --------------------------------------------------------------------------

TEST(ReadPng, SixteenBitWithSidecar) {
  TempDir tmp;
  cv::Mat labels(4, 5, CV_16UC1, cv::Scalar(0));
  labels.at<std::uint16_t>(1, 2) = 300;
  labels.at<std::uint16_t>(2, 2) = 300;
  labels.at<std::uint16_t>(3, 4) = 7;
  ASSERT_TRUE(cv::imwrite((tmp / "1.25.png").string(), labels));
  write_text(tmp / "1.25.instances.json",
             R"({"instances":[{"id":300,"class":"Teddy_Bear","score":0.75,"track_id":12},
                              {"id":7,"class":"cup"}]})");
  EXPECT_EQ(detect_format(tmp.path()), "png");
  const Segmentation seg = read_segmentation(tmp.path());
  ASSERT_EQ(seg.frames.size(), 1u);
  EXPECT_EQ(seg.frames[0].timestamp, 1.25);
  ASSERT_EQ(seg.frames[0].instances.size(), 2u);
  const Instance& cup = seg.frames[0].instances[0];  // ascending id: 7 first
  EXPECT_EQ(cup.class_name, "cup");
  EXPECT_FALSE(cup.track_id);
  EXPECT_EQ(cup.bbox.x, 4);
  EXPECT_EQ(cup.bbox.y, 3);
  const Instance& bear = seg.frames[0].instances[1];
  EXPECT_EQ(bear.class_name, "teddy bear");
  EXPECT_EQ(bear.track_id, 12);
  EXPECT_EQ(bear.score, 0.75);
  EXPECT_EQ(bear.mask->area(), 2u);
  EXPECT_EQ(bear.bbox.h, 2);

  write_text(tmp / "1.25.instances.json", R"({"instances":[{"id":300,"class":"cup"}]})");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()),
                   "1.25.instances.json: no entry for label value 7 of 1.25.png");
  write_text(
      tmp / "1.25.instances.json",
      R"({"instances":[{"id":7,"class":"cup"},{"id":300,"class":"cup"},{"id":5,"class":"cup"}]})");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()),
                   "1.25.instances.json: id 5 has no pixel in 1.25.png (values present: 7, 300)");
}

TEST(ReadPng, MalformedYcbvCopy) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f/masks");
  TempDir tmp;
  test::copy_tree(dir, tmp.path());
  // classes.txt without the mug (value 14)
  write_text(tmp / "classes.txt", "# value class\n8 009_gelatin_box\n21 061_foam_brick\n");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "0.000000.png").string() + ": label value 14 is not in " +
                (tmp / "classes.txt").string() +
                "; expected every value of the image to have a class");
  write_text(tmp / "classes.txt", "8 009_gelatin_box\nfourteen 025_mug\n");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "classes.txt").string() + ":2: label value is 'fourteen'; expected an integer");
  // a colour image in place of a label image
  fs::remove(tmp / "classes.txt");
  // not an image, a damaged one: io's strict reader names the file
  write_text(tmp / "0.100000.png", "not an image");
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "0.100000.png").string() + ": not a PNG image");
  std::string png = test::read_text(tmp / "0.000000.png");
  png[png.size() - 13] ^= 1;  // the last IDAT chunk's CRC
  write_text(tmp / "0.100000.png", png);
  EXPECT_EQ(error_of([&] { read_segmentation(tmp.path()); }),
            (tmp / "0.100000.png").string() +
                ": cannot decode the image (libpng: IDAT: CRC error); expected a PNG image");
  ASSERT_TRUE(
      cv::imwrite((tmp / "0.100000.png").string(), cv::Mat(4, 4, CV_8UC3, cv::Scalar(1, 2, 3))));
  EXPECT_ERROR_HAS(read_segmentation(tmp.path()),
                   "0.100000.png: 3 channel(s) of 8-bit; expected a single-channel 8- or 16-bit");
}

// ---- the paper's txt layout --------------------------------------------------------------------

TEST(ReadPaper, PixelListsToMasks) {
  TempDir tmp;
  write_text(tmp / "10.5" / "teddy_bear" / "7.txt", "3 4\n4 4\n4 5\n");
  write_text(tmp / "10.5" / "cup" / "12.txt", "0 0\n");
  write_text(tmp / "10.5" / "cup" / "2.txt", "9 9\n");
  fs::create_directories(tmp / "9.0");  // a frame without instances
  EXPECT_EQ(detect_format(tmp.path()), "txt-paper");
  ReadOptions options;
  options.image_width = 10;
  options.image_height = 10;
  const Segmentation seg = read_segmentation(tmp.path(), options);
  ASSERT_EQ(seg.frames.size(), 2u);
  EXPECT_TRUE(seg.frames[0].instances.empty());
  const auto& instances = seg.frames[1].instances;
  ASSERT_EQ(instances.size(), 3u);  // classes by name, tracks by number
  EXPECT_EQ(instances[0].class_name, "cup");
  EXPECT_EQ(instances[0].track_id, 2);
  EXPECT_EQ(instances[1].track_id, 12);
  EXPECT_EQ(instances[2].class_name, "teddy bear");
  EXPECT_EQ(instances[2].track_id, 7);
  EXPECT_EQ(instances[2].mask->area(), 3u);
  EXPECT_EQ(instances[2].bbox.x, 3);
  EXPECT_EQ(instances[2].bbox.y, 4);
  EXPECT_EQ(instances[2].bbox.w, 2);
  EXPECT_EQ(instances[2].bbox.h, 2);
  EXPECT_EQ(instances[2].mask->width, 10);

  write_text(tmp / "10.5" / "cup" / "2.txt", "9 10\n");
  EXPECT_EQ(
      error_of([&] { read_segmentation(tmp.path(), options); }),
      (tmp / "10.5" / "cup" / "2.txt").string() +
          ":1: pixel (9, 10) outside the 10x10 image; expected 0 <= u < width, 0 <= v < height");
  write_text(tmp / "10.5" / "cup" / "2.txt", "9 x\n");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path(), options),
                   "2.txt:1: v is 'x'; expected an integer");
  write_text(tmp / "10.5" / "cup" / "2.txt", "9 1\n");
  write_text(tmp / "10.5" / "cup" / "two.txt", "9 1\n");
  EXPECT_ERROR_HAS(read_segmentation(tmp.path(), options),
                   "two.txt: not a track file; expected <track_id>.txt");
}

TEST(ReadJson, ANumberBeyondADoubleIsNamedByItsField) {
  // "score": 1e999 overflows a double: nlohmann's out_of_range error (406) was exit 1 naming no
  // file, then named the file alone; the other readers name the field.
  test::TempDir dir;
  test::write_text(dir / "1.000000.json",
                   R"({"instances":[{"class":"cup","score":0.5,"bbox":[1,2,3,4]},
                                    {"class":"cup","score":1e999,"bbox":[1,2,3,4]}]})");
  try {
    read_segmentation(dir.path());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "1.000000.json").string() + ": instances[1].score");
    EXPECT_NE(e.reason().find("number overflow parsing '1e999'"), std::string::npos) << e.what();
    EXPECT_NE(e.reason().find("expected a finite number in [0, 1]"), std::string::npos) << e.what();
  }
  test::write_text(dir / "1.000000.json",
                   R"({"instances":[{"class":"cup","score":0.5,"bbox":[1,2,-1e999,4]}]})");
  try {
    read_segmentation(dir.path());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "1.000000.json").string() + ": instances[0].bbox[2]");
  }
}

}  // namespace
}  // namespace objmap::segmentation

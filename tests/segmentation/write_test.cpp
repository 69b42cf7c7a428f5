#include "objmap/segmentation/write.h"

#include <gtest/gtest.h>

#include <random>

#include "objmap/core/error.h"
#include "objmap/segmentation/read.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

namespace fs = std::filesystem;

TEST(Write, FrameFileName) {
  EXPECT_EQ(frame_file_name(1305031453.359684), "1305031453.359684.json");
  EXPECT_EQ(frame_file_name(1341841278.8427), "1341841278.842700.json");
  EXPECT_EQ(frame_file_name(0.0), "0.000000.json");
}

TEST(Write, FrameJsonIsDocumentedLayout) {
  FrameSegmentation frame;
  Instance cup;
  cup.class_name = "cup";
  cup.score = 0.5;
  cup.track_id = 7;
  cup.bbox = {1, 2, 3, 4};
  frame.instances.push_back(cup);
  Instance tv;
  tv.class_name = "tv monitor";
  tv.bbox = {0, 0, 1, 1};
  tv.mask = Mask{2, 1, {0, 1}};
  frame.instances.push_back(tv);
  EXPECT_EQ(frame_json(frame),
            "{\"instances\":[{\"class\":\"cup\",\"score\":0.5,\"track_id\":7,\"bbox\":[1.0,2.0,3.0,"
            "4.0]},{\"class\":\"tv monitor\",\"score\":1.0,\"bbox\":[0.0,0.0,1.0,1.0],\"mask\":{"
            "\"size\":[1,2],\"counts\":\"11\"}}]}\n");
}

TEST(Write, RoundTripThroughCanonicalFormat) {
  Segmentation original;
  std::mt19937 random(7);
  for (int f = 0; f < 4; ++f) {
    FrameSegmentation frame;
    frame.timestamp = 1305031453.359684 + 0.033 * f;
    for (int i = 0; i < f; ++i) {
      Instance instance;
      instance.class_name = i % 2 ? "teddy bear" : "tv monitor";
      instance.score = 0.123456789 * (i + 1);
      if (i != 1) instance.track_id = 10 * f + i;
      if (i != 2) {
        Mask mask{64, 48, {}};
        for (int p = 0; p < 64 * 48; ++p) mask.data.push_back((random() % 7) < 2 ? 1 : 0);
        instance.mask = mask;
        instance.bbox = {0, 0, 64, 48};
      } else {
        instance.bbox = {1.5, 2.25, 30.125, 20};
      }
      frame.instances.push_back(instance);
    }
    original.frames.push_back(frame);
  }
  test::TempDir tmp;
  write_segmentation(tmp / "seg", original);
  EXPECT_TRUE(fs::exists(tmp / "seg" / "1305031453.359684.json"));
  ReadOptions options;
  options.image_width = 64;
  options.image_height = 48;
  const Segmentation read = read_segmentation(tmp / "seg", options);
  EXPECT_EQ(read.format, "json");
  ASSERT_EQ(read.frames.size(), original.frames.size());
  for (std::size_t f = 0; f < read.frames.size(); ++f) {
    EXPECT_NEAR(read.frames[f].timestamp, original.frames[f].timestamp, 5e-7);
    ASSERT_EQ(read.frames[f].instances.size(), original.frames[f].instances.size());
    for (std::size_t i = 0; i < read.frames[f].instances.size(); ++i) {
      const Instance& a = original.frames[f].instances[i];
      const Instance& b = read.frames[f].instances[i];
      EXPECT_EQ(a.class_name, b.class_name);
      EXPECT_EQ(a.score, b.score);  // shortest round-trip doubles: exact
      EXPECT_EQ(a.track_id, b.track_id);
      EXPECT_EQ(a.bbox.x, b.bbox.x);
      EXPECT_EQ(a.bbox.y, b.bbox.y);
      EXPECT_EQ(a.bbox.w, b.bbox.w);
      EXPECT_EQ(a.bbox.h, b.bbox.h);
      ASSERT_EQ(a.mask.has_value(), b.mask.has_value());
      if (a.mask) {
        EXPECT_EQ(a.mask->data, b.mask->data);
      }
    }
  }
  // Writing what was read gives the same bytes (deterministic).
  write_segmentation(tmp / "again", read);
  for (const auto& entry : fs::directory_iterator(tmp / "seg")) {
    EXPECT_EQ(test::read_text(entry.path()),
              test::read_text(tmp / "again" / entry.path().filename()));
  }
  // No temporary file left behind.
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(tmp / "seg")) {
    EXPECT_EQ(entry.path().extension(), ".json") << entry.path();
    ++files;
  }
  EXPECT_EQ(files, 4u);
}

TEST(Write, RealYcbvMasksSurviveTheCanonicalFormat) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f/masks");
  const Segmentation png = read_segmentation(dir);
  test::TempDir tmp;
  write_segmentation(tmp.path(), png);
  EXPECT_TRUE(fs::exists(tmp / "0.033333.json"));
  const Segmentation json = read_segmentation(tmp.path());
  EXPECT_EQ(json.format, "json");
  ASSERT_EQ(json.frames.size(), 10u);
  for (std::size_t f = 0; f < 10; ++f) {
    EXPECT_NEAR(json.frames[f].timestamp, png.frames[f].timestamp, 5e-7);
    ASSERT_EQ(json.frames[f].instances.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
      const Instance& a = png.frames[f].instances[i];
      const Instance& b = json.frames[f].instances[i];
      EXPECT_EQ(a.class_name, b.class_name);
      EXPECT_EQ(a.track_id, b.track_id);
      EXPECT_EQ(a.mask->data, b.mask->data);
      EXPECT_EQ(a.bbox.x, b.bbox.x);
      EXPECT_EQ(a.bbox.h, b.bbox.h);
    }
  }
}

TEST(Write, RejectsTwoFramesWithOneFileName) {
  Segmentation seg;
  seg.frames.resize(2);
  seg.frames[0].timestamp = 1.0;
  seg.frames[1].timestamp = 1.0000001;
  test::TempDir tmp;
  try {
    write_segmentation(tmp / "seg", seg);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1.000000.json: two frames have this file name"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace objmap::segmentation

// objmap validate on every real folder of ../shared/data and on a synthetic scene.
#include <gtest/gtest.h>

#include "support/test_support.h"

namespace objmap::test {
namespace {

bool has(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

TEST(Validate, Fr1Desk9) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  const auto r = run_objmap({"validate", "--dataset", data.string(), "--trajectory",
                             (data / "groundtruth.txt").string(), "--segmentation",
                             (data / "detections_yolofastest").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "9 rgb, 9 depth, 9 associated pairs")) << r.out;
  EXPECT_TRUE(has(r.out, "camera        fr1")) << r.out;
  EXPECT_TRUE(has(r.out, "9 of 9 frames have a pose")) << r.out;
  EXPECT_TRUE(has(r.out, "format boxes-named, 9 frames")) << r.out;
  EXPECT_TRUE(has(r.out, "tv monitor")) << r.out;
}

TEST(Validate, Fr1RpyEvery4WithTheVisualOdometryCoveringOnlyTheStart) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_rpy_every4");
  const auto r = run_objmap({"validate", "--dataset", data.string(), "--trajectory",
                             (data / "vo_estimate_first100.txt").string(), "--quick"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "174 associated pairs")) << r.out;
  EXPECT_TRUE(has(r.out, "1 of 174 pairs decoded")) << r.out;
  // The first 100 frames of the full sequence are about the first 25 of every 4th frame.
  EXPECT_TRUE(has(r.out, "25 of 174 frames have a pose")) << r.out;
}

TEST(Validate, Fr3CabinetJpegAndBoxesWithoutClass) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr3_cabinet_58kf");
  const auto r = run_objmap({"validate", "--dataset", data.string(), "--trajectory",
                             (data / "groundtruth.txt").string(), "--segmentation",
                             (data / "boxes_yolov2").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "58 associated pairs")) << r.out;
  EXPECT_TRUE(has(r.out, "camera        fr3")) << r.out;
  EXPECT_TRUE(has(r.out, "58 of 58 frames have a pose")) << r.out;
  EXPECT_TRUE(has(r.out, "format boxes-xywh")) << r.out;
}

TEST(Validate, YcbVideoMasksAndItsOwnCamera) {
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f");
  const auto r = run_objmap({"validate", "--dataset", data.string(), "--trajectory",
                             (data / "groundtruth.txt").string(), "--segmentation",
                             (data / "masks").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "10 associated pairs")) << r.out;
  EXPECT_TRUE(has(r.out, "fx 1066.778")) << r.out;
  EXPECT_TRUE(has(r.out, "depth factor 10000")) << r.out;
  EXPECT_TRUE(has(r.out, "format png, 10 frames")) << r.out;
  EXPECT_TRUE(has(r.out, "30 (30 with a mask, 30 with a track id)")) << r.out;
}

TEST(Validate, Fr3LongOfficeDetectionsWithoutImages) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr3_long_office_household_annotations");
  const auto r = run_objmap({"validate", "--dataset", data.string(), "--trajectory",
                             (data / "groundtruth.txt").string(), "--segmentation",
                             (data / "detections_yolo").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "2585 rgb")) << r.out;
  EXPECT_TRUE(has(r.out, "format boxes-coco, 2585 frames")) << r.out;
}

TEST(Validate, SyntheticScene) {
  TempDir dir;
  const auto s = run_objmap({"synth", "--out", (dir / "s").string(), "--frames", "6"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto r = run_objmap({"validate", "--dataset", (dir / "s").string(), "--trajectory",
                             (dir / "s" / "groundtruth.txt").string(), "--segmentation",
                             (dir / "s" / "segmentation").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "6 associated pairs")) << r.out;
  EXPECT_TRUE(has(r.out, "6 of 6 frames have a pose")) << r.out;
  EXPECT_TRUE(has(r.out, "format json, 6 frames, 6 of them")) << r.out;
}

TEST(Validate, TrajectoryOfAnotherSequenceIsRejected) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(other, "tum/fr3_cabinet_58kf/groundtruth.txt");
  const auto r = run_objmap(
      {"validate", "--dataset", data.string(), "--trajectory", other.string(), "--quick"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r.err, "overlaps no frame")) << r.err;
  EXPECT_TRUE(has(r.err, "groundtruth.txt")) << r.err;
}

// Settings YAML that OpenCV reads but whose top level is no mapping (fuzz_camera_yaml's finding:
// an assertion of OpenCV's FileStorage, once "internal error", exit 1): exit 2, one line naming
// the file.
TEST(Validate, AMalformedCameraFileIsExit2InOneLineNamingIt) {
  TempDir dir;
  const auto s = run_objmap({"synth", "--out", (dir / "s").string(), "--frames", "2"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const fs::path yaml = dir / "bad.yaml";
  write_text(yaml, "%YAML:1.\n- 1\n");
  const auto r =
      run_objmap({"validate", "--dataset", (dir / "s").string(), "--camera", yaml.string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, "objmap: error: " + yaml.string() +
                       ": the top level is a sequence, not a mapping; expected ORB-SLAM2 "
                       "settings (Camera.fx: ...)\n");
}

}  // namespace
}  // namespace objmap::test

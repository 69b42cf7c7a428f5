// objmap synth --preset walkthrough -> objmap fuse: a room walked round twice (636 frames, three
// tables, twelve chairs, six of them packed round a dining table), the detector's noise plus a new
// track ID for every object seen again after 30 frames away, and one mask over two touching
// instances of one class in 30% of the frames where they touch (the preset's default). Every true
// object must be found exactly once, with the default keyframes and with every frame
// (docs/fusion.md, "Walk-throughs").
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "fuse_helpers.h"

namespace objmap::test {
namespace {

class FuseWalkthrough : public ::testing::TestWithParam<int> {};

// The walk-through of `seed`, 636 frames at half size (test cache).
fs::path walkthrough_scene(const std::string& seed, RunResult* why) {
  return cached_output("walk636-seed" + seed + "-scene",
                       {"synth", "--out", "{OUT}", "--preset", "walkthrough", "--frames", "636",
                        "--scale", "0.5", "--seed", seed},
                       why);
}

TEST_P(FuseWalkthrough, EveryObjectOnceWithTheDefaultKeyframesAndWithEveryFrame) {
  const std::string seed = std::to_string(GetParam());
  RunResult why;
  const fs::path scene = walkthrough_scene(seed, &why);
  ASSERT_TRUE(fs::exists(scene)) << why.err;
  const auto gt = read_gt_objects(scene / "objects_gt.json");
  std::map<std::string, int> gt_classes;
  for (const auto& g : gt) ++gt_classes[g.cls];
  ASSERT_EQ(gt_classes["chair"], 12);
  for (const std::string keyframes : {"auto", "all"}) {
    SCOPED_TRACE("--keyframes " + keyframes);
    const fs::path run = cached_output(
        "walk636-seed" + seed + "-fuse-" + keyframes,
        {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
         "--segmentation", (scene / "segmentation").string(), "--keyframes", keyframes,
         "--dense-map", "false", "--out", "{OUT}"},
        &why);
    ASSERT_TRUE(fs::exists(run)) << why.err;
    const auto fused = read_fused_objects(run / "objects.json");
    std::map<std::string, int> fused_classes;
    for (const auto& f : fused) ++fused_classes[f.cls];
    EXPECT_EQ(fused_classes, gt_classes);
    // Each true object has its own map object of its class (greedy one-to-one within 0.3 m).
    EXPECT_EQ(match_objects(gt, fused, 0.3, /*same_class=*/true).size(), gt.size());
    // No chair's box is wider than a chair.
    const auto widths = horizontal_widths(run / "objects.json");
    for (const auto& f : fused) {
      if (f.cls == "chair") {
        EXPECT_LE(widths.at(f.id), 0.8) << "chair " << f.id;
      }
    }
  }
}

// One frame in 18 (sparse exports for 3D detection): objects seen in fewer than three such frames
// are not confirmed, but no true object is two map objects: each class has at most its true count,
// and no two map objects of one class lie within 0.3 m of one true object.
TEST_P(FuseWalkthrough, OneFrameInEighteenSplitsNoObject) {
  const std::string seed = std::to_string(GetParam());
  RunResult why;
  const fs::path scene = walkthrough_scene(seed, &why);
  ASSERT_TRUE(fs::exists(scene)) << why.err;
  const fs::path run = cached_output(
      "walk636-seed" + seed + "-fuse-stride18",
      {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
       "--segmentation", (scene / "segmentation").string(), "--keyframes", "stride", "--stride",
       "18", "--dense-map", "false", "--out", "{OUT}"},
      &why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  const auto gt = read_gt_objects(scene / "objects_gt.json");
  const auto fused = read_fused_objects(run / "objects.json");
  std::map<std::string, int> gt_classes, fused_classes;
  for (const auto& g : gt) ++gt_classes[g.cls];
  for (const auto& f : fused) ++fused_classes[f.cls];
  for (const auto& [cls, n] : fused_classes) EXPECT_LE(n, gt_classes[cls]) << cls;
  EXPECT_GE(fused_classes["chair"], 9);  // most chairs are still found
  for (const auto& g : gt) {
    int near = 0;
    for (const auto& f : fused) near += f.cls == g.cls && (f.centroid - g.centroid).norm() < 0.3;
    EXPECT_LE(near, 1) << g.cls << " " << g.id;
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, FuseWalkthrough, ::testing::Values(1, 2, 3));

}  // namespace
}  // namespace objmap::test

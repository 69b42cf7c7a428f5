// objmap synth --preset apartment --keep-every 18 -> objmap fuse: a flat's large furniture (a bed,
// a couch, a refrigerator, a toilet) walked through and exported as scans for 3D detection are,
// one frame in 18, with no track id carried from one written frame to the next (issue #39 §5).
// Each view of the 2 m couch sees its nearer half: without the join of continuous parts the couch
// is two map couches on every seed; with it, every class has at most its true count and every
// piece of furniture is one map object whose box centre lies in its true box (docs/fusion.md,
// "Parts of one instance").
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "fuse_helpers.h"

namespace objmap::test {
namespace {

class FuseApartment : public ::testing::TestWithParam<int> {};

TEST_P(FuseApartment, OneFrameInEighteenGivesTheCouchAndEveryPieceOfFurnitureOnce) {
  const std::string seed = std::to_string(GetParam());
  RunResult why;
  const fs::path scene =
      cached_output("apartment954-keep18-seed" + seed,
                    {"synth", "--out", "{OUT}", "--preset", "apartment", "--frames", "954",
                     "--scale", "0.5", "--keep-every", "18", "--seed", seed},
                    &why);
  ASSERT_TRUE(fs::exists(scene)) << why.err;
  const auto gt = read_gt_objects(scene / "objects_gt.json");
  std::map<std::string, int> gt_classes;
  for (const auto& g : gt) ++gt_classes[g.cls];
  ASSERT_EQ(gt_classes["couch"], 1);
  const auto fuse = [&](const std::string& join) {
    const fs::path run = cached_output(
        "apartment954-keep18-seed" + seed + "-fuse-join-" + join,
        {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
         "--segmentation", (scene / "segmentation").string(), "--keyframes", "all",
         "--join-continuous", join, "--out", "{OUT}"},
        &why);
    EXPECT_TRUE(fs::exists(run)) << why.err;
    return fs::exists(run) ? read_fused_objects(run / "objects.json") : std::vector<FusedObject>{};
  };
  std::map<std::string, int> without;
  for (const auto& f : fuse("false")) ++without[f.cls];
  EXPECT_EQ(without["couch"], 2) << "the split this test is about no longer happens";

  const auto fused = fuse("true");
  std::map<std::string, int> classes;
  for (const auto& f : fused) ++classes[f.cls];
  for (const auto& [cls, n] : classes) EXPECT_LE(n, gt_classes[cls]) << cls;
  for (const auto& g : gt) {
    int inside = 0;
    for (const auto& f : fused) inside += f.cls == g.cls && g.contains(f.position, 0.1);
    if (g.cls == "couch" || g.cls == "bed" || g.cls == "refrigerator" || g.cls == "toilet") {
      EXPECT_EQ(inside, 1) << g.cls << " " << g.id;
    } else {
      EXPECT_LE(inside, 1) << g.cls << " " << g.id;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, FuseApartment, ::testing::Values(1, 2, 3));

}  // namespace
}  // namespace objmap::test

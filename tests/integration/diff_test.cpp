// objmap diff end to end: synthetic pairs with known changes (objmap synth --second-visit-of,
// fused with detector noise, scored by objmap eval diff) and real same-place pairs from
// ../shared/data (skipped with a message when it is absent).
#include <gtest/gtest.h>

#include <cstdio>

#include <nlohmann/json.hpp>

#include "support/diff_pair.h"
#include "support/schema_check.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

// Three seeds (issue #42: change F1 >= 0.9, registration within 2 cm and 1 degree on each).
class DiffSyntheticSeeds : public ::testing::TestWithParam<const char*> {};

TEST_P(DiffSyntheticSeeds, ChangesFoundAndRegisteredOnASecondVisit) {
  const SynthPair p = diff_synth_pair(GetParam());
  ASSERT_TRUE(fs::exists(p.run_a) && fs::exists(p.run_b)) << p.why.err;
  TempDir tmp;
  const RunResult d = run_objmap({"diff", "--before", p.run_a.string(), "--after", p.run_b.string(),
                                  "--out", (tmp / "diff").string()});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const json diff = json::parse(read_text(tmp / "diff" / "diff.json"));
  EXPECT_TRUE(validate_json(diff, load_schema("diff.schema.json")).empty());
  EXPECT_TRUE(validate_json(json::parse(read_text(p.second / "changes_gt.json")),
                            load_schema("changes_gt.schema.json"))
                  .empty());
  const RunResult e =
      run_objmap({"eval", "diff", "--diff", (tmp / "diff" / "diff.json").string(), "--gt",
                  (p.second / "changes_gt.json").string(), "--json", (tmp / "eval.json").string()});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const json ev = json::parse(read_text(tmp / "eval.json"));
  EXPECT_TRUE(validate_json(ev, load_schema("eval_diff.schema.json")).empty());
  EXPECT_LT(ev["registration"]["rotation_error_deg"].get<double>(), 1.0) << e.out;
  EXPECT_LT(ev["registration"]["error_at_objects_m"].get<double>(), 0.02) << e.out;
  EXPECT_GE(ev["all"]["f1"].get<double>(), 0.9) << e.out << d.out;
}

INSTANTIATE_TEST_SUITE_P(Seeds, DiffSyntheticSeeds, ::testing::Values("11", "12", "13"),
                         [](const auto& info) { return std::string("seed") + info.param; });

TEST(DiffSynthetic, TheKnownTransformGivesTheSameChanges) {
  const SynthPair p = diff_synth_pair("11");
  ASSERT_TRUE(fs::exists(p.run_a) && fs::exists(p.run_b)) << p.why.err;
  TempDir tmp;
  const RunResult d =
      run_objmap({"diff", "--before", p.run_a.string(), "--after", p.run_b.string(), "--align",
                  (p.second / "changes_gt.json").string(), "--out", (tmp / "diff").string()});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const json diff = json::parse(read_text(tmp / "diff" / "diff.json"));
  EXPECT_EQ(diff["registration"]["source"], "given");
  const RunResult e = run_objmap({"eval", "diff", "--diff", (tmp / "diff" / "diff.json").string(),
                                  "--gt", (p.second / "changes_gt.json").string()});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(e.out.find("rotation error 0.000 deg"), std::string::npos) << e.out;
}

// ---- real pairs

bool diff_real_data(const std::string& relative) {
  if (has_data(relative)) return true;
  if (data_required()) ADD_FAILURE() << "real data " << relative << " required but absent";
  return false;
}

fs::path diff_fuse_tum(const std::string& name, RunResult* why) {
  const fs::path data = data_dir() / "tum" / name;
  return cached_output(
      "diff-real-" + name,
      {"fuse", "--dataset", data.string(), "--trajectory", (data / "groundtruth.txt").string(),
       "--segmentation", (data / "detections_yolofastest").string(), "--out", "{OUT}"},
      why);
}

// No object reported removed or added whose place both visits saw with its surface unchanged:
// every removed / added object's place must have been seen empty by the other visit.
void expect_no_unsupported_changes(const json& diff) {
  for (const json& o : diff["objects"]) {
    const std::string s = o["status"];
    if (s == "removed") {
      EXPECT_LT(o["evidence"]["after_visit"]["surface_share"].get<double>(), 0.5) << o.dump();
    }
    if (s == "added") {
      EXPECT_LT(o["evidence"]["before_visit"]["surface_share"].get<double>(), 0.5) << o.dump();
    }
  }
}

TEST(DiffReal, TwoRecordingsOfOneOfficeReportNoChangeWhereBothSawIt) {
  if (!diff_real_data("tum/fr1_desk_9") || !diff_real_data("tum/fr1_rpy_every4"))
    GTEST_SKIP() << "real data absent: " << data_dir();
  RunResult why;
  const fs::path desk = diff_fuse_tum("fr1_desk_9", &why);
  ASSERT_TRUE(fs::exists(desk)) << why.err;
  const fs::path rpy = diff_fuse_tum("fr1_rpy_every4", &why);
  ASSERT_TRUE(fs::exists(rpy)) << why.err;
  TempDir tmp;
  // Both recordings are in the benchmark's ground-truth frame: registered, the identity within a
  // degree of yaw and 5 cm (fr1_desk_9's own up estimate is 4 degrees off: the tilt is not asked).
  const RunResult g = run_objmap({"diff", "--before", rpy.string(), "--after", desk.string(),
                                  "--out", (tmp / "registered").string()});
  ASSERT_EQ(g.exit_code, 0) << g.err;
  const json reg = json::parse(read_text(tmp / "registered" / "diff.json"));
  EXPECT_NEAR(reg["registration"]["yaw_deg"].get<double>(), 0.0, 1.0) << g.out;
  for (int k : {3, 7, 11})
    EXPECT_NEAR(reg["registration"]["before_from_after"][k].get<double>(), 0.0, 0.05) << g.out;
  expect_no_unsupported_changes(reg);
  EXPECT_EQ(reg["counts"]["removed"].get<int>() + reg["counts"]["added"].get<int>(), 0) << g.out;
  // The other order (the short visit first): the inverse transform, as close to the identity.
  const RunResult back = run_objmap({"diff", "--before", desk.string(), "--after", rpy.string(),
                                     "--out", (tmp / "reverse").string()});
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const json rev = json::parse(read_text(tmp / "reverse" / "diff.json"));
  EXPECT_NEAR(rev["registration"]["yaw_deg"].get<double>(),
              -reg["registration"]["yaw_deg"].get<double>(), 0.2)
      << back.out;
  for (int k : {3, 7, 11})
    EXPECT_NEAR(rev["registration"]["before_from_after"][k].get<double>(), 0.0, 0.05) << back.out;
  EXPECT_EQ(rev["counts"]["removed"].get<int>() + rev["counts"]["added"].get<int>(), 0) << back.out;
  // With the known identity, the same.
  write_text(tmp / "identity.json",
             R"({"before_from_after": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]})");
  const RunResult d =
      run_objmap({"diff", "--before", rpy.string(), "--after", desk.string(), "--align",
                  (tmp / "identity.json").string(), "--out", (tmp / "diff").string()});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const json diff = json::parse(read_text(tmp / "diff" / "diff.json"));
  EXPECT_TRUE(validate_json(diff, load_schema("diff.schema.json")).empty());
  expect_no_unsupported_changes(diff);
  EXPECT_EQ(diff["counts"]["removed"].get<int>() + diff["counts"]["added"].get<int>(), 0) << d.out;
  EXPECT_GT(diff["registration"]["fitness"].get<double>(), 0.5) << d.out;
}

TEST(DiffReal, ARecordingAgainstItselfRegistersAtTheIdentityUnchanged) {
  if (!diff_real_data("tum/fr1_rpy_every4")) GTEST_SKIP() << "real data absent: " << data_dir();
  RunResult why;
  const fs::path rpy = diff_fuse_tum("fr1_rpy_every4", &why);
  ASSERT_TRUE(fs::exists(rpy)) << why.err;
  TempDir tmp;
  const RunResult d = run_objmap({"diff", "--before", rpy.string(), "--after", rpy.string(),
                                  "--out", (tmp / "diff").string()});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const json diff = json::parse(read_text(tmp / "diff" / "diff.json"));
  EXPECT_NEAR(diff["registration"]["yaw_deg"].get<double>(), 0.0, 0.01);
  // Both shares: every point of either map lies on the other.
  EXPECT_GT(diff["registration"]["fitness_both"].get<double>(), 0.99);
  EXPECT_EQ(diff["counts"]["unchanged"].get<int>(), static_cast<int>(diff["objects"].size()));
}

TEST(DiffReal, TwoHalvesOfASevenScenesClipRegisterAndAgree) {
  if (!diff_real_data("7scenes_redkitchen_3dmatch_50f")) GTEST_SKIP() << "real data absent";
  const fs::path model = data_dir() / "../models/yolov5n-seg_coco/yolov5n-seg_480x640.onnx";
  if (!fs::exists(model)) GTEST_SKIP() << "model absent: " << model;
  // Frames 8-32 and 33-57, each a 7-Scenes folder of its own (links), detected and fused apart.
  TempDir tmp;
  const fs::path clip = data_dir() / "7scenes_redkitchen_3dmatch_50f";
  fs::path runs[2];
  for (int h = 0; h < 2; ++h) {
    const fs::path half = tmp / ("half" + std::to_string(h));
    fs::create_directories(half);
    fs::copy_file(clip / "camera-intrinsics.txt", half / "camera-intrinsics.txt");
    for (int i = 8 + 25 * h; i < 33 + 25 * h; ++i) {
      char stem[32];
      std::snprintf(stem, sizeof stem, "frame-%06d", i);
      for (const char* ext : {".color.png", ".depth.png", ".pose.txt"})
        fs::create_symlink(clip / (std::string(stem) + ext), half / (std::string(stem) + ext));
    }
    const RunResult det = run_objmap({"detect", "--dataset", half.string(), "--model",
                                      model.string(), "--out", (half / "seg").string()});
    ASSERT_EQ(det.exit_code, 0) << det.err;
    runs[h] = tmp / ("run" + std::to_string(h));
    const RunResult fuse = run_objmap({"fuse", "--dataset", half.string(), "--segmentation",
                                       (half / "seg").string(), "--out", runs[h].string()});
    ASSERT_EQ(fuse.exit_code, 0) << fuse.err;
  }
  const RunResult d = run_objmap({"diff", "--before", runs[0].string(), "--after", runs[1].string(),
                                  "--out", (tmp / "diff").string()});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const json diff = json::parse(read_text(tmp / "diff" / "diff.json"));
  // One recording, one world frame: the identity.
  EXPECT_NEAR(diff["registration"]["yaw_deg"].get<double>(), 0.0, 1.0) << d.out;
  for (int k : {3, 7, 11})
    EXPECT_NEAR(diff["registration"]["before_from_after"][k].get<double>(), 0.0, 0.03) << d.out;
  expect_no_unsupported_changes(diff);
  EXPECT_EQ(diff["counts"]["removed"].get<int>() + diff["counts"]["added"].get<int>(), 0) << d.out;
}

TEST(DiffReal, TwoDifferentPlacesAreExit2Named) {
  if (!diff_real_data("tum/fr1_desk_9") || !diff_real_data("ycbv_0000_10f"))
    GTEST_SKIP() << "real data absent: " << data_dir();
  RunResult why;
  const fs::path desk = diff_fuse_tum("fr1_desk_9", &why);
  ASSERT_TRUE(fs::exists(desk)) << why.err;
  const fs::path ycb_data = data_dir() / "ycbv_0000_10f";
  const fs::path ycb = cached_output("diff-real-ycbv",
                                     {"fuse", "--dataset", ycb_data.string(), "--trajectory",
                                      (ycb_data / "groundtruth.txt").string(), "--segmentation",
                                      (ycb_data / "masks").string(), "--out", "{OUT}"},
                                     &why);
  ASSERT_TRUE(fs::exists(ycb)) << why.err;
  TempDir tmp;
  const RunResult d = run_objmap({"diff", "--before", desk.string(), "--after", ycb.string(),
                                  "--out", (tmp / "diff").string()});
  EXPECT_EQ(d.exit_code, 2) << d.out;
  EXPECT_NE(d.err.find("no credible registration"), std::string::npos) << d.err;
  EXPECT_NE(d.err.find(desk.string()), std::string::npos) << d.err;
  EXPECT_FALSE(fs::exists(tmp / "diff" / "diff.json"));
}

}  // namespace
}  // namespace objmap::test

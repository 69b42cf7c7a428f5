// objmap diff and objmap eval diff at the command line: exit 2 with one line naming the file and
// field or the reason; a run against itself is all unchanged, at the identity, byte-identical
// twice. On the seed-3 synthetic run shared with tests/cli query (tests/support cached_output).
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

fs::path diff_cli_run(RunResult* why) {
  const fs::path scene =
      cached_output("seed3-orbit60-scene",
                    {"synth", "--out", "{OUT}", "--seed", "3", "--orbit-speed", "60"}, why);
  if (!fs::exists(scene)) return {};
  return cached_output(
      "seed3-orbit60-fuse",
      {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
       "--segmentation", (scene / "segmentation").string(), "--out", "{OUT}"},
      why);
}

int diff_cli_lines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

TEST(DiffCli, ARunAgainstItselfIsUnchangedAtTheIdentityAndDeterministic) {
  RunResult why;
  const fs::path run = diff_cli_run(&why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  TempDir tmp;
  const RunResult r = run_objmap(
      {"diff", "--before", run.string(), "--after", run.string(), "--out", (tmp / "d1").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json d = json::parse(read_text(tmp / "d1" / "diff.json"));
  EXPECT_NEAR(d["registration"]["yaw_deg"].get<double>(), 0.0, 0.01);
  for (int k : {3, 7, 11})
    EXPECT_NEAR(d["registration"]["translation_m"][k / 4].get<double>(), 0, 1e-3);
  for (const json& o : d["objects"]) EXPECT_EQ(o["status"], "unchanged") << o.dump();
  EXPECT_GT(d["objects"].size(), 5u);
  const RunResult again = run_objmap(
      {"diff", "--before", run.string(), "--after", run.string(), "--out", (tmp / "d2").string()});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  std::string first = read_text(tmp / "d1" / "diff.json"),
              second = read_text(tmp / "d2" / "diff.json");
  // The paths of the outputs are not in it; the runs are the same: byte-identical.
  EXPECT_EQ(first, second);
}

TEST(DiffCli, ADamagedObjectsJsonIsOneLineNamingFileAndField) {
  RunResult why;
  const fs::path run = diff_cli_run(&why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  TempDir tmp;
  const fs::path damaged = tmp / "damaged";
  fs::create_directories(damaged);
  for (const auto& e : fs::directory_iterator(run))
    if (e.is_regular_file()) fs::copy_file(e.path(), damaged / e.path().filename());
  json objects = json::parse(read_text(run / "objects.json"));
  objects["objects"][1].erase("class");
  write_text(damaged / "objects.json", objects.dump(1));
  const RunResult r = run_objmap({"diff", "--before", damaged.string(), "--after", run.string(),
                                  "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(diff_cli_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find((damaged / "objects.json").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("objects[1]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("class"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "out" / "diff.json"));
}

TEST(DiffCli, MissingRunBadAlignAndOutOverAnInputAreExit2) {
  RunResult why;
  const fs::path run = diff_cli_run(&why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  TempDir tmp;
  RunResult r = run_objmap({"diff", "--before", (tmp / "nowhere").string(), "--after", run.string(),
                            "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(diff_cli_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;

  write_text(tmp / "align.json", R"({"before_from_after": [1, 0, 0]})");
  r = run_objmap({"diff", "--before", run.string(), "--after", run.string(), "--align",
                  (tmp / "align.json").string(), "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(diff_cli_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("align.json: before_from_after"), std::string::npos) << r.err;

  r = run_objmap(
      {"diff", "--before", run.string(), "--after", run.string(), "--out", run.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(diff_cli_lines(r.err), 1) << r.err;

  // A run without its dense map: the registration and the free-space evidence need it.
  fs::copy(run, tmp / "no_dense", fs::copy_options::recursive);
  fs::remove(tmp / "no_dense" / "map_dense.ply");
  r = run_objmap({"diff", "--before", run.string(), "--after", (tmp / "no_dense").string(), "--out",
                  (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(diff_cli_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("map_dense.ply: missing"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "out" / "diff.json"));

  r = run_objmap({"diff", "--before", run.string(), "--after", run.string(), "--out",
                  (tmp / "out").string(), "--min-fitness", "2"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--min-fitness"), std::string::npos) << r.err;
}

TEST(DiffCli, EvalDiffNamesAMalformedTruthFile) {
  TempDir tmp;
  write_text(
      tmp / "diff.json",
      R"({"registration":{"before_from_after":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]},"objects":[]})");
  write_text(tmp / "changes_gt.json", R"({"before_from_after":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],
    "objects":[{"status":"moved","before_position":[0,0],"after_position":[1,1,1]}]})");
  const RunResult r = run_objmap({"eval", "diff", "--diff", (tmp / "diff.json").string(), "--gt",
                                  (tmp / "changes_gt.json").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(diff_cli_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("changes_gt.json: objects[0].before_position"), std::string::npos) << r.err;
}

TEST(DiffCli, EvalDiffCountsAMoveFoundAsRemovedPlusAddedAsWrong) {
  TempDir tmp;
  // Truth: one object moved from (0,0,0) to (1,0,0); the after world is the before world + 2 m in
  // x.
  write_text(tmp / "changes_gt.json", R"({"before_from_after":[1,0,0,-2,0,1,0,0,0,0,1,0,0,0,0,1],
    "objects":[{"status":"moved","before_position":[0,0,0],"after_position":[3,0,0]},
               {"status":"removed","before_position":[5,5,0],"after_position":null}]})");
  const auto diff = [](const std::string& objects) {
    return R"({"registration":{"before_from_after":[1,0,0,-2,0,1,0,0,0,0,1,0,0,0,0,1]},"objects":)" +
           objects + "}";
  };
  // Found as moved (and the removal found): all right.
  write_text(
      tmp / "right.json",
      diff(R"([{"status":"moved","before":{"position":[0.05,0,0]},"after":{"position":[3,0.1,0]}},
                      {"status":"removed","before":{"position":[5,5,0.1]},"after":null}])"));
  RunResult r =
      run_objmap({"eval", "diff", "--diff", (tmp / "right.json").string(), "--gt",
                  (tmp / "changes_gt.json").string(), "--json", (tmp / "e1.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json e = json::parse(read_text(tmp / "e1.json"));
  EXPECT_DOUBLE_EQ(e["all"]["f1"].get<double>(), 1.0);
  EXPECT_NEAR(e["registration"]["rotation_error_deg"].get<double>(), 0.0, 1e-9);
  // Found as removed + added: two false positives and a miss (the true removal still right).
  write_text(tmp / "split.json",
             diff(R"([{"status":"removed","before":{"position":[0,0,0]},"after":null},
                      {"status":"added","before":null,"after":{"position":[3,0,0]}},
                      {"status":"removed","before":{"position":[5,5,0]},"after":null}])"));
  r = run_objmap({"eval", "diff", "--diff", (tmp / "split.json").string(), "--gt",
                  (tmp / "changes_gt.json").string(), "--json", (tmp / "e2.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  e = json::parse(read_text(tmp / "e2.json"));
  EXPECT_EQ(e["moved"]["correct"].get<int>(), 0);
  EXPECT_EQ(e["added"]["found"].get<int>(), 1);
  EXPECT_EQ(e["added"]["correct"].get<int>(), 0);
  EXPECT_EQ(e["removed"]["found"].get<int>(), 2);
  EXPECT_EQ(e["removed"]["correct"].get<int>(), 1);
  EXPECT_EQ(e["all"]["correct"].get<int>(), 1);
  EXPECT_EQ(e["all"]["found"].get<int>(), 3);
  EXPECT_EQ(e["all"]["truth"].get<int>(), 2);
}

}  // namespace
}  // namespace objmap::test

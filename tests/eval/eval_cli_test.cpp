// objmap eval ate / rpe through the built binary: exit codes, printed numbers, JSON,
// --save-aligned.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <sstream>

#include "objmap/io/trajectory.h"
#include "support/test_support.h"

namespace objmap::eval {
namespace {

using objmap::test::read_text;
using objmap::test::run_objmap;
using objmap::test::TempDir;
using objmap::test::write_text;

bool has(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

TEST(EvalCli, AteOnFr1XyzPrintsAndWritesTheReferenceNumbers) {
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  TempDir tmp;
  const auto r =
      run_objmap({"eval", "ate", "--gt", (dir / "freiburg1_xyz-groundtruth.txt").string(), "--est",
                  (dir / "freiburg1_xyz-rgbdslam.txt").string(), "--json",
                  (tmp / "ate.json").string(), "--save-aligned", (tmp / "aligned.txt").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "786")) << r.out;
  EXPECT_TRUE(has(r.out, "0.013473")) << r.out;
  const auto json = nlohmann::json::parse(read_text(tmp / "ate.json"));
  EXPECT_EQ(json.at("pairs").get<int>(), 786);
  EXPECT_NEAR(json.at("rmse").get<double>(), 0.013473, 1e-6);
  for (const char* key : {"mean", "median", "std", "min", "max"}) EXPECT_TRUE(json.contains(key));
  EXPECT_EQ(json.at("gt_from_est").at("type"), "se3");
  const Trajectory aligned = io::read_trajectory(tmp / "aligned.txt");
  EXPECT_EQ(aligned.size(), 788u);  // every pose of the estimate
}

TEST(EvalCli, RpeOnFr1XyzPrintsAndWritesTheReferenceNumbers) {
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  TempDir tmp;
  const auto r =
      run_objmap({"eval", "rpe", "--gt", (dir / "freiburg1_xyz-groundtruth.txt").string(), "--est",
                  (dir / "freiburg1_xyz-rgbdslam.txt").string(), "--delta", "1", "--delta-unit",
                  "f", "--json", (tmp / "rpe.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "783")) << r.out;
  EXPECT_TRUE(has(r.out, "0.005763")) << r.out;
  const auto json = nlohmann::json::parse(read_text(tmp / "rpe.json"));
  EXPECT_EQ(json.at("pairs").get<int>(), 783);
  EXPECT_NEAR(json.at("translational").at("rmse").get<double>(), 0.005763, 1e-6);
  EXPECT_EQ(json.at("rotational").at("unit"), "deg");
  EXPECT_EQ(json.at("delta_unit"), "f");
}

TEST(EvalCli, ARepeatedGroundTruthStampGivesTheTumToolsNumbers) {
  // As freiburg2_desk's groundtruth.txt (line 10863 repeats 1311868229.5760): fr1_xyz's ground
  // truth with one stamp written twice, first with a pose 1 m off. TUM's tools keep the later line
  // (a dictionary); so does objmap, with one warning line: the reference numbers are unchanged.
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  TempDir tmp;
  std::istringstream in(read_text(dir / "freiburg1_xyz-groundtruth.txt"));
  std::string line, gt;
  int data_lines = 0;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#' && ++data_lines == 400) {
      std::istringstream fields(line);
      std::string stamp;
      fields >> stamp;
      gt += stamp + " 9 9 9 0 0 0 1\n";  // the earlier, wrong pose
    }
    gt += line + "\n";
  }
  write_text(tmp / "gt.txt", gt);
  const std::string est = (dir / "freiburg1_xyz-rgbdslam.txt").string();
  const auto ate = run_objmap({"eval", "ate", "--gt", (tmp / "gt.txt").string(), "--est", est});
  ASSERT_EQ(ate.exit_code, 0) << ate.err;
  EXPECT_TRUE(has(ate.out, "786")) << ate.out;
  EXPECT_TRUE(has(ate.out, "0.013473")) << ate.out;
  EXPECT_EQ(std::count(ate.err.begin(), ate.err.end(), '\n'), 1) << ate.err;
  EXPECT_TRUE(has(ate.err, "objmap: warning: " + (tmp / "gt.txt").string() + ":")) << ate.err;
  EXPECT_TRUE(has(ate.err, "this later pose is used, as the TUM benchmark's tools do")) << ate.err;
  const auto rpe = run_objmap({"eval", "rpe", "--gt", (tmp / "gt.txt").string(), "--est", est,
                               "--delta", "1", "--delta-unit", "f"});
  ASSERT_EQ(rpe.exit_code, 0) << rpe.err;
  EXPECT_TRUE(has(rpe.out, "783")) << rpe.out;
  EXPECT_TRUE(has(rpe.out, "0.005763")) << rpe.out;
}

TEST(EvalCli, APoseFarBeyondMetresIsNamedByItsLine) {
  // A pose at 1e300 m gave ATE inf / nan (exit 0): now exit 2 naming the file and line.
  TempDir tmp;
  std::string gt = "# timestamp tx ty tz qx qy qz qw\n";
  for (int k = 0; k < 5; ++k)
    gt += std::to_string(100 + k) + (k == 3 ? " 1e300" : " 0.5") + " 0 0 0 0 0 1\n";
  write_text(tmp / "gt.txt", gt);
  write_text(tmp / "est.txt",
             "100 0 0 0 0 0 0 1\n101 0 0 0 0 0 0 1\n102 0 0 0 0 0 0 1\n"
             "103 0 0 0 0 0 0 1\n104 0 0 0 0 0 0 1\n");
  for (const char* what : {"ate", "rpe"}) {
    const auto r = run_objmap({"eval", what, "--gt", (tmp / "gt.txt").string(), "--est",
                               (tmp / "est.txt").string(), "--json", (tmp / "r.json").string()});
    EXPECT_EQ(r.exit_code, 2) << what << r.out;
    EXPECT_TRUE(
        has(r.err, (tmp / "gt.txt").string() + ":5: the pose at 103 has a coordinate of 1e+300 m"))
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(objmap::test::fs::exists(tmp / "r.json"));
  }
}

// A small pair of files: gt on a line, the estimate shifted by (1, 2, 3) m.
void write_small_pair(const TempDir& tmp) {
  std::string gt = "# timestamp tx ty tz qx qy qz qw\n", est = gt;
  for (int k = 0; k < 6; ++k) {
    const double x = 0.1 * k, y = (k % 2) * 0.05, z = 0.02 * k * k;
    const std::string stamp = std::to_string(100 + k);
    gt += stamp + " " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) +
          " 0 0 0 1\n";
    est += stamp + " " + std::to_string(x + 1) + " " + std::to_string(y + 2) + " " +
           std::to_string(z + 3) + " 0 0 0 1\n";
  }
  write_text(tmp / "gt.txt", gt);
  write_text(tmp / "est.txt", est);
}

TEST(EvalCli, SaveAlignedWritesTheEstimateInTheGroundTruthWorld) {
  TempDir tmp;
  write_small_pair(tmp);
  const auto r =
      run_objmap({"eval", "ate", "--gt", (tmp / "gt.txt").string(), "--est",
                  (tmp / "est.txt").string(), "--save-aligned", (tmp / "aligned.txt").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Trajectory gt = io::read_trajectory(tmp / "gt.txt");
  const Trajectory aligned = io::read_trajectory(tmp / "aligned.txt");
  ASSERT_EQ(aligned.size(), gt.size());
  for (std::size_t i = 0; i < gt.size(); ++i) {
    EXPECT_EQ(aligned.poses[i].timestamp, gt.poses[i].timestamp);
    EXPECT_NEAR(
        (aligned.poses[i].world_from_cam.translation() - gt.poses[i].world_from_cam.translation())
            .norm(),
        0.0, 1e-9);
  }
}

TEST(EvalCli, MissingFileIsExitTwoWithOneLine) {
  TempDir tmp;
  write_small_pair(tmp);
  const std::string missing = (tmp / "nope.txt").string();
  for (const char* sub : {"ate", "rpe"}) {
    const auto r = run_objmap({"eval", sub, "--gt", (tmp / "gt.txt").string(), "--est", missing});
    EXPECT_EQ(r.exit_code, 2) << sub;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("objmap: error: " + missing, 0), 0u) << r.err;
  }
}

TEST(EvalCli, NoCommonStampsAndBadDeltaAreExitTwo) {
  TempDir tmp;
  write_small_pair(tmp);
  write_text(tmp / "late.txt", "5000 0 0 0 0 0 0 1\n5001 1 0 0 0 0 0 1\n");
  const auto ate = run_objmap(
      {"eval", "ate", "--gt", (tmp / "gt.txt").string(), "--est", (tmp / "late.txt").string()});
  EXPECT_EQ(ate.exit_code, 2);
  EXPECT_TRUE(has(ate.err, "no pose pairs within max_diff 0.02 s")) << ate.err;

  const auto unit = run_objmap({"eval", "rpe", "--gt", (tmp / "gt.txt").string(), "--est",
                                (tmp / "est.txt").string(), "--delta-unit", "parsec"});
  EXPECT_EQ(unit.exit_code, 2);
  EXPECT_TRUE(has(unit.err, "unknown unit 'parsec'")) << unit.err;

  const auto delta = run_objmap({"eval", "rpe", "--gt", (tmp / "gt.txt").string(), "--est",
                                 (tmp / "est.txt").string(), "--delta", "0"});
  EXPECT_EQ(delta.exit_code, 2);
  EXPECT_TRUE(has(delta.err, "error: --delta: ")) << delta.err;
}

TEST(EvalCli, EvalWithoutSubcommandIsAUsageError) {
  const auto r = run_objmap({"eval"});
  EXPECT_EQ(r.exit_code, 2);
}

}  // namespace
}  // namespace objmap::eval

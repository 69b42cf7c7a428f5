#include "objmap/eval/rpe.h"

#include <gtest/gtest.h>

#include <cmath>

#include "eval_test_util.h"
#include "objmap/core/error.h"
#include "objmap/io/trajectory.h"
#include "support/test_support.h"

namespace objmap::eval {
namespace {

using test::kPi;
using test::make_pose;
using test::make_trajectory;
using test::rot_z;

constexpr int kPoses = 10;

// Ground truth: a straight line along x, 0.1 m and 0.1 s per step, the camera turning 5° per step.
Trajectory line_gt() {
  std::vector<double> stamps;
  std::vector<Pose> poses;
  for (int k = 0; k < kPoses; ++k) {
    stamps.push_back(0.1 * k);
    poses.push_back(make_pose(rot_z(5.0 * kPi / 180.0 * k), Vec3(0.1 * k, 0.0, 0.0)));
  }
  return make_trajectory(stamps, poses, "gt.txt");
}

// The estimate follows the ground truth exactly but for one wrong step, 4 -> 5: its motion there is
// step_error · (gt_4⁻¹ gt_5); afterwards it moves as the ground truth does (rigidly carried along).
// With evaluate_rpe.py's E = (est_i⁻¹ est_j)(gt_i⁻¹ gt_j)⁻¹, the pair (4, 5) has E = step_error and
// every other one-frame pair has E = identity.
Trajectory line_est(const Trajectory& gt, const Pose& step_error) {
  Trajectory est = gt;
  est.source = "est.txt";
  const Pose carried =
      gt.poses[4].world_from_cam * step_error * gt.poses[4].world_from_cam.inverse();
  for (int k = 5; k < kPoses; ++k)
    est.poses[k].world_from_cam = carried * gt.poses[k].world_from_cam;
  return est;
}

Pose step_error() { return make_pose(rot_z(2.0 * kPi / 180.0), Vec3(0.01, 0.0, 0.0)); }

TEST(Rpe, OneWrongStepGivesTheHandDerivedStatistics) {
  const Trajectory gt = line_gt();
  const Trajectory est = line_est(gt, step_error());
  RpeOptions options;
  options.delta = 1;
  options.delta_unit = DeltaUnit::kFrames;
  const RpeResult r = evaluate_rpe(gt, est, options);
  // i = 0..7 with j = i + 1; (8, 9) is dropped because j is the last pose (as the script does).
  ASSERT_EQ(r.pairs.size(), 8u);
  for (std::size_t n = 0; n < r.pairs.size(); ++n) {
    EXPECT_EQ(r.pairs[n].est_index_i, n);
    EXPECT_EQ(r.pairs[n].est_index_j, n + 1);
    EXPECT_EQ(r.pairs[n].gt_index_i, n);
  }
  EXPECT_NEAR(r.pairs[4].translational_m, 0.01, 1e-12);
  EXPECT_NEAR(r.pairs[4].rotational_rad, 2.0 * kPi / 180.0, 1e-9);
  // translational: one 0.01 and seven 0 over 8 pairs
  EXPECT_NEAR(r.translational_m.rmse, 0.01 / std::sqrt(8.0), 1e-12);
  EXPECT_NEAR(r.translational_m.mean, 0.01 / 8.0, 1e-12);
  EXPECT_NEAR(r.translational_m.median, 0.0, 1e-12);
  EXPECT_NEAR(r.translational_m.stddev, std::sqrt(1e-4 / 8.0 - 0.01 / 8.0 * 0.01 / 8.0), 1e-12);
  EXPECT_NEAR(r.translational_m.max, 0.01, 1e-12);
  EXPECT_NEAR(r.translational_m.min, 0.0, 1e-12);
  // rotational (degrees): one 2° and seven 0 (arccos near 1 resolves only ~1e-6°)
  EXPECT_NEAR(r.rotational_deg.rmse, 2.0 / std::sqrt(8.0), 1e-5);
  EXPECT_NEAR(r.rotational_deg.mean, 0.25, 1e-5);
  EXPECT_NEAR(r.rotational_deg.max, 2.0, 1e-9);
  EXPECT_EQ(r.translational_m.count, 8u);
  EXPECT_NEAR(r.max_diff_s, 0.2, 1e-12);  // 2 × median ground-truth interval
}

TEST(Rpe, PairsForEachDeltaUnit) {
  const Trajectory gt = line_gt();
  const Trajectory est = gt;
  const auto pairs_for = [&](double delta, DeltaUnit unit) {
    RpeOptions options;
    options.delta = delta;
    options.delta_unit = unit;
    const RpeResult r = evaluate_rpe(gt, est, options);
    std::vector<std::pair<std::size_t, std::size_t>> out;
    for (const RpePair& p : r.pairs) {
      EXPECT_NEAR(p.translational_m, 0.0, 1e-12);
      out.emplace_back(p.est_index_i, p.est_index_j);
    }
    return out;
  };
  using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;
  // j = i + 2 for 0.2 s, 0.2 m and 10° of rotation; j = 9 (last) is never kept.
  Pairs plus_two;
  for (std::size_t i = 0; i + 2 < kPoses - 1; ++i) plus_two.emplace_back(i, i + 2);
  EXPECT_EQ(pairs_for(0.2, DeltaUnit::kSeconds), plus_two);
  EXPECT_EQ(pairs_for(0.2, DeltaUnit::kMetres), plus_two);
  EXPECT_EQ(pairs_for(10.0 * kPi / 180.0, DeltaUnit::kRadians), plus_two);
  EXPECT_EQ(pairs_for(10.0, DeltaUnit::kDegrees), plus_two);
  EXPECT_EQ(pairs_for(2, DeltaUnit::kFrames), plus_two);
  // A delta past the end: every j is the last pose -> no pairs -> InputError.
  EXPECT_THROW(pairs_for(100, DeltaUnit::kFrames), InputError);
}

TEST(Rpe, GroundTruthMatchesFartherThanMaxDiffAreDropped) {
  const Trajectory gt = line_gt();
  Trajectory est = gt;
  est.source = "est.txt";
  for (StampedPose& p : est.poses) p.timestamp += 0.03;  // every estimate stamp 30 ms late
  RpeOptions options;
  options.delta = 1;
  options.delta_unit = DeltaUnit::kFrames;
  EXPECT_EQ(evaluate_rpe(gt, est, options).pairs.size(), 8u);  // default max_diff 0.2 s

  options.max_diff_s = 0.02;
  try {
    evaluate_rpe(gt, est, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "est.txt");
    EXPECT_EQ(e.reason().rfind("no pose pairs within max_diff 0.02 s", 0), 0u) << e.what();
  }
  options.offset_s = -0.03;  // the offset brings them back
  EXPECT_EQ(evaluate_rpe(gt, est, options).pairs.size(), 8u);
}

TEST(Rpe, BadOptionsAreInputErrors) {
  RpeOptions options;
  options.delta = 0.0;
  EXPECT_THROW(options.check(), InputError);
  options.delta = -1.0;
  try {
    evaluate_rpe(line_gt(), line_gt(), options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "RpeOptions.delta");
    EXPECT_NE(e.reason().find("expected a finite number > 0"), std::string::npos) << e.what();
  }
  options.delta = 1.0;
  options.max_diff_s = 0.0;
  EXPECT_THROW(options.check(), InputError);
  try {
    parse_delta_unit("parsec");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--delta-unit");
    EXPECT_EQ(e.reason().rfind("unknown unit 'parsec'", 0), 0u) << e.what();
  }
  for (const char* unit : {"s", "m", "rad", "deg", "f"})
    EXPECT_EQ(to_string(parse_delta_unit(unit)), unit);
}

TEST(Rpe, FindClosestIndexIsTheScriptsBinarySearch) {
  const std::vector<double> l = {0.0, 1.0, 2.0, 3.0};
  EXPECT_EQ(find_closest_index(l, 1.5), 2u);  // tie: the first visited (middle = 2) wins
  EXPECT_EQ(find_closest_index(l, 0.4), 0u);
  EXPECT_EQ(find_closest_index(l, 2.6), 3u);
  EXPECT_EQ(find_closest_index(l, -5.0), 0u);
  EXPECT_EQ(find_closest_index(l, 9.0), 3u);
  EXPECT_EQ(find_closest_index(l, 1.0), 1u);
}

TEST(Rpe, Fr1XyzRgbdslamMatchesEvaluateRpePy) {
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  const Trajectory gt = io::read_trajectory(dir / "freiburg1_xyz-groundtruth.txt");
  const Trajectory est = io::read_trajectory(dir / "freiburg1_xyz-rgbdslam.txt");
  RpeOptions options;
  options.delta = 1;
  options.delta_unit = DeltaUnit::kFrames;
  const RpeResult r = evaluate_rpe(gt, est, options);
  EXPECT_EQ(r.pairs.size(), 783u);
  EXPECT_NEAR(r.translational_m.rmse, 0.005763, 1e-6);
  EXPECT_EQ(r.rotational_deg.count, 783u);
  EXPECT_GT(r.rotational_deg.rmse, 0.0);
}

}  // namespace
}  // namespace objmap::eval

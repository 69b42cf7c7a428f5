#include "objmap/eval/ate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "eval_test_util.h"
#include "objmap/core/error.h"
#include "objmap/io/trajectory.h"
#include "support/test_support.h"

namespace objmap::eval {
namespace {

using test::make_pose;
using test::make_trajectory;
using test::rot_z;

// The 8 corners (±1, ±2, ±3) of a box around `center` (distinct extents: the alignment is unique).
// noise(corner) = sx·sy·(1 + sz)·e along x: it sums to zero and is uncorrelated with the corners
// (Σ nᵢ gᵢᵀ = 0), so the best alignment of (corners + noise) onto the corners is the identity and
// the errors are |nᵢ|: four corners with 2e, four with 0.
struct BoxCase {
  std::vector<double> stamps;
  std::vector<Vec3> gt_points, noisy_points;
};

BoxCase box_case(double e) {
  BoxCase c;
  const Vec3 center(1.0, -2.0, 0.5);
  int k = 0;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      for (int sz : {-1, 1}) {
        const Vec3 g = center + Vec3(sx * 1.0, sy * 2.0, sz * 3.0);
        c.stamps.push_back(10.0 + k++);
        c.gt_points.push_back(g);
        c.noisy_points.push_back(g + Vec3(sx * sy * (1 + sz) * e, 0.0, 0.0));
      }
  return c;
}

// est_from_gt: the estimate lives in another world frame.
Pose est_from_gt_world() {
  return make_pose(Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, -0.5).normalized()).toRotationMatrix(),
                   Vec3(3.0, -1.0, 2.0));
}

TEST(Ate, KnownRigidOffsetAndNoiseGiveTheHandDerivedStatistics) {
  const double e = 0.01;
  const BoxCase c = box_case(e);
  std::vector<Pose> gt_poses, est_poses;
  for (std::size_t i = 0; i < c.gt_points.size(); ++i) {
    const Pose cam = make_pose(rot_z(0.1 * i), c.gt_points[i]);
    gt_poses.push_back(cam);
    est_poses.push_back(est_from_gt_world() * make_pose(rot_z(0.1 * i), c.noisy_points[i]));
  }
  const Trajectory gt = make_trajectory(c.stamps, gt_poses, "gt.txt");
  const Trajectory est = make_trajectory(c.stamps, est_poses, "est.txt");

  const AteResult r = evaluate_ate(gt, est, {});
  ASSERT_EQ(r.stats.count, 8u);
  // errors: 2e ×4, 0 ×4
  EXPECT_NEAR(r.stats.rmse, e * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(r.stats.mean, e, 1e-12);
  EXPECT_NEAR(r.stats.median, e, 1e-12);
  EXPECT_NEAR(r.stats.stddev, e, 1e-12);
  EXPECT_NEAR(r.stats.min, 0.0, 1e-12);
  EXPECT_NEAR(r.stats.max, 2.0 * e, 1e-12);
  // The alignment is the inverse of the frame change, scale 1.
  const Pose expected = est_from_gt_world().inverse();
  EXPECT_TRUE(r.gt_from_est.rotation.isApprox(expected.linear(), 1e-12));
  EXPECT_TRUE(r.gt_from_est.translation.isApprox(expected.translation(), 1e-12));
  EXPECT_EQ(r.gt_from_est.scale, 1.0);
  // The aligned estimate is back in the ground truth's world, orientations included.
  ASSERT_EQ(r.aligned.size(), est.size());
  for (std::size_t i = 0; i < est.size(); ++i) {
    EXPECT_TRUE(r.aligned.poses[i].world_from_cam.linear().isApprox(gt_poses[i].linear(), 1e-12));
    EXPECT_NEAR((r.aligned.poses[i].world_from_cam.translation() - c.noisy_points[i]).norm(), 0.0,
                1e-12);
  }
}

TEST(Ate, OffsetAssociatesShiftedStamps) {
  const BoxCase c = box_case(0.0);
  std::vector<Pose> poses;
  std::vector<double> shifted;
  for (std::size_t i = 0; i < c.gt_points.size(); ++i) {
    poses.push_back(make_pose(Eigen::Matrix3d::Identity(), c.gt_points[i]));
    shifted.push_back(c.stamps[i] + 1000.005);
  }
  const Trajectory gt = make_trajectory(c.stamps, poses, "gt.txt");
  const Trajectory est = make_trajectory(shifted, poses, "est.txt");
  EXPECT_THROW(evaluate_ate(gt, est, {}), InputError);
  AteOptions options;
  options.offset_s = -1000.0;
  const AteResult r = evaluate_ate(gt, est, options);
  EXPECT_EQ(r.stats.count, 8u);
  EXPECT_NEAR(r.stats.max, 0.0, 1e-12);
}

TEST(Ate, ScaleOptionRecoversAKnownScale) {
  const BoxCase c = box_case(0.0);
  const double s = 0.37;  // the estimate is 0.37 times too small (monocular)
  const Pose est_from_gt = est_from_gt_world();
  std::vector<Pose> gt_poses, est_poses;
  for (std::size_t i = 0; i < c.gt_points.size(); ++i) {
    gt_poses.push_back(make_pose(Eigen::Matrix3d::Identity(), c.gt_points[i]));
    est_poses.push_back(make_pose(est_from_gt.linear(), s * (est_from_gt * c.gt_points[i])));
  }
  const Trajectory gt = make_trajectory(c.stamps, gt_poses);
  const Trajectory est = make_trajectory(c.stamps, est_poses);

  AteOptions options;
  options.with_scale = true;
  const AteResult sim3 = evaluate_ate(gt, est, options);
  EXPECT_NEAR(sim3.gt_from_est.scale, 1.0 / s, 1e-12);
  EXPECT_NEAR(sim3.stats.rmse, 0.0, 1e-12);
  EXPECT_TRUE(sim3.gt_from_est.rotation.isApprox(est_from_gt.linear().transpose(), 1e-12));

  const AteResult rigid = evaluate_ate(gt, est, {});
  EXPECT_EQ(rigid.gt_from_est.scale, 1.0);
  EXPECT_GT(rigid.stats.rmse, 1.0);  // a rigid alignment cannot undo the scale
}

TEST(Ate, AlignPointsIsAProperRotationForAReflectedCloud) {
  // Points mirrored in z: the best proper rotation, not the reflection (the det fix of `align`).
  const std::vector<Vec3> source = {{1, 0, 0}, {0, 2, 0}, {0, 0, 3}, {1, 1, 1}};
  std::vector<Vec3> target;
  for (const Vec3& p : source) target.push_back(Vec3(p.x(), p.y(), -p.z()));
  const Similarity a = align_points(source, target, false);
  EXPECT_NEAR(a.rotation.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((a.rotation * a.rotation.transpose()).isIdentity(1e-12));
}

TEST(Ate, NoCommonStampsIsAnInputError) {
  const Trajectory gt =
      make_trajectory({1.0, 2.0, 3.0}, std::vector<Pose>(3, Pose::Identity()), "gt.txt");
  const Trajectory est =
      make_trajectory({7.0, 8.0, 9.0}, std::vector<Pose>(3, Pose::Identity()), "est.txt");
  try {
    evaluate_ate(gt, est, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "est.txt");
    EXPECT_EQ(e.reason().rfind("no pose pairs within max_diff 0.02 s", 0), 0u) << e.what();
  }
}

TEST(Ate, OnePairIsNotEnough) {
  const Trajectory gt = make_trajectory({1.0, 2.0}, std::vector<Pose>(2, Pose::Identity()), "g");
  const Trajectory est = make_trajectory({2.001, 8.0}, std::vector<Pose>(2, Pose::Identity()), "e");
  try {
    evaluate_ate(gt, est, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.reason().rfind("only 1 pose pair within max_diff", 0), 0u) << e.what();
  }
}

TEST(Ate, BadOptionsAreRejected) {
  AteOptions options;
  options.max_diff_s = -0.1;
  EXPECT_THROW(options.check(), InputError);
}

TEST(Ate, Fr1XyzRgbdslamMatchesEvaluateAtePy) {
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  const Trajectory gt = io::read_trajectory(dir / "freiburg1_xyz-groundtruth.txt");
  const Trajectory est = io::read_trajectory(dir / "freiburg1_xyz-rgbdslam.txt");
  const AteResult r = evaluate_ate(gt, est, {});
  EXPECT_EQ(r.stats.count, 786u);
  EXPECT_NEAR(r.stats.rmse, 0.013473, 1e-6);
  EXPECT_LE(r.stats.min, r.stats.median);
  EXPECT_LE(r.stats.median, r.stats.max);

  AteOptions options;
  options.with_scale = true;
  const AteResult sim3 = evaluate_ate(gt, est, options);
  EXPECT_LE(sim3.stats.rmse, r.stats.rmse);  // one more degree of freedom
  EXPECT_NEAR(sim3.gt_from_est.scale, 1.0, 0.05);
}

}  // namespace
}  // namespace objmap::eval

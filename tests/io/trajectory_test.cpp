#include "objmap/io/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::read_text;
using test::TempDir;
using test::write_text;

// The InputError message of reading `text` as a trajectory ("" when it reads fine).
std::string read_error(const std::string& text, std::string* where = nullptr) {
  TempDir dir;
  write_text(dir / "t.txt", text);
  try {
    read_trajectory(dir / "t.txt");
  } catch (const InputError& e) {
    if (where) *where = e.where().substr(e.where().rfind(':'));
    return e.reason();
  }
  return "";
}

const char* kGood =
    "# header\n"
    "1.0 0 0 0 0 0 0 1\n"
    "\n"
    "2.0 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n";

TEST(ReadTrajectory, RealFilesRowCounts) {
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  const Trajectory gt = read_trajectory(dir / "freiburg1_xyz-groundtruth.txt");
  EXPECT_EQ(gt.size(), 3000u);
  EXPECT_EQ(gt.poses.front().timestamp, 1305031098.6659);
  EXPECT_EQ(gt.poses.front().world_from_cam.translation(), Vec3(1.3563, 0.6305, 1.6380));
  EXPECT_EQ(gt.source, (dir / "freiburg1_xyz-groundtruth.txt").string());
  // RGBD-SLAM's file starts with a "# TF Coordinate Frame ID" comment.
  const Trajectory est = read_trajectory(dir / "freiburg1_xyz-rgbdslam.txt");
  EXPECT_EQ(est.size(), 788u);
  EXPECT_EQ(est.poses.front().timestamp, 1305031102.160407);
  const Trajectory orb = read_trajectory(dir / "freiburg1_xyz-ORB_kf_mono.txt");
  EXPECT_EQ(orb.size(), 32u);
  EXPECT_TRUE(orb.poses.front().world_from_cam.isApprox(Pose::Identity(), 0.0));
}

TEST(ReadTrajectory, LongOfficeGroundTruthNormalised) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr3_long_office_household_annotations");
  const Trajectory gt = read_trajectory(dir / "groundtruth.txt");
  EXPECT_EQ(gt.size(), 8710u);
  for (const StampedPose& p : gt.poses) {
    const Eigen::Matrix3d r = p.world_from_cam.linear();
    ASSERT_LT((r * r.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  }
  // First row: 1341847980.7900 -0.6832 2.6909 1.7373 0.0003 0.8617 -0.5072 -0.0145
  const Eigen::Quaterniond q =
      Eigen::Quaterniond(0.0145, -0.0003, -0.8617, 0.5072).normalized();  // same rotation
  EXPECT_TRUE(gt.poses[0].world_from_cam.linear().isApprox(q.toRotationMatrix(), 1e-14));
  EXPECT_EQ(gt.poses[0].timestamp, 1341847980.79);
}

TEST(ReadTrajectory, ReadsSmallFileAndRotation) {
  TempDir dir;
  write_text(dir / "t.txt", kGood);
  const Trajectory t = read_trajectory(dir / "t.txt");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.poses[1].timestamp, 2.0);
  EXPECT_EQ(t.poses[1].world_from_cam.translation(), Vec3(1, 2, 3));
  // 90 degrees about z: x axis of the camera goes to y of the world.
  EXPECT_TRUE((t.poses[1].world_from_cam.linear() * Vec3::UnitX()).isApprox(Vec3::UnitY(), 1e-15));
}

TEST(ReadTrajectory, WrongFieldCounts) {
  std::string where;
  EXPECT_EQ(read_error("1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n", &where),
            "7 fields; expected 8: timestamp tx ty tz qx qy qz qw");
  EXPECT_EQ(where, ":2");
  EXPECT_EQ(read_error("# c\n1.0 0 0 0 0 0 0 1 9\n", &where),
            "9 fields; expected 8: timestamp tx ty tz qx qy qz qw");
  EXPECT_EQ(where, ":2");
}

TEST(ReadTrajectory, TextNanInfInNumberFields) {
  std::string where;
  EXPECT_EQ(read_error("1.0 0 zero 0 0 0 0 1\n", &where), "ty is 'zero'; expected a finite number");
  EXPECT_EQ(where, ":1");
  EXPECT_EQ(read_error("1.0 0 0 0 0 0 0 1\n2.0 nan 0 0 0 0 0 1\n", &where),
            "tx is 'nan'; expected a finite number");
  EXPECT_EQ(where, ":2");
  EXPECT_EQ(read_error("inf 0 0 0 0 0 0 1\n"), "timestamp is 'inf'; expected a finite number");
  EXPECT_EQ(read_error("1 0 0 0 0 0 0 -Infinity\n"), "qw is '-Infinity'; expected a finite number");
}

TEST(ReadTrajectory, QuaternionNorm) {
  std::string where;
  EXPECT_EQ(read_error("1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1.01\n", &where),
            "quaternion (qx qy qz qw) has norm 1.01; expected a unit quaternion (norm within "
            "0.001 of 1)");
  EXPECT_EQ(where, ":2");
  EXPECT_NE(read_error("1.0 0 0 0 0 0 0 0\n").find("has norm 0;"), std::string::npos);
  // Within 1e-3: normalised.
  TempDir dir;
  write_text(dir / "t.txt", "1.0 0 0 0 0 0 0.7071 0.7072\n");
  const Eigen::Matrix3d r = read_trajectory(dir / "t.txt").poses[0].world_from_cam.linear();
  EXPECT_LT((r * r.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-15);
}

TEST(ReadTrajectory, TimestampsOutOfOrderOrDuplicated) {
  std::string where;
  EXPECT_EQ(read_error("2.0 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n", &where),
            "timestamp 1.5 is before 2 of line 1; expected strictly increasing timestamps");
  EXPECT_EQ(where, ":2");
}

TEST(ReadTrajectory, ARepeatedTimestampIsTheLaterPoseAsInTheTumTools) {
  // freiburg2_desk's groundtruth.txt repeats 1311868229.5760 (line 10863): TUM's evaluate_ate.py
  // reads the file into a dictionary, so the later line replaces the earlier one.
  test::TempDir dir;
  test::write_text(
      dir / "t.txt",
      "1.0 0 0 0 0 0 0 1\n2.0 5 0 0 0 0 0 1\n# c\n2.0 1 2 3 0 0 0 1\n3.0 0 0 0 0 0 0 1\n");
  const Trajectory t = read_trajectory(dir / "t.txt");
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t.poses[1].timestamp, 2.0);
  EXPECT_EQ(t.poses[1].world_from_cam.translation(), Vec3(1, 2, 3));
  ASSERT_EQ(t.warnings.size(), 1u);
  EXPECT_EQ(t.warnings[0], (dir / "t.txt").string() +
                               ":4: timestamp 2.0 repeats line 2; this later pose is used, as the "
                               "TUM benchmark's tools do");
}

TEST(ReadTrajectory, EmptyOrMissingFile) {
  EXPECT_EQ(read_error("# only a comment\n\n"),
            "no pose in the file; expected lines 'timestamp tx ty tz qx qy qz qw'");
  TempDir dir;
  EXPECT_THROW(read_trajectory(dir / "missing.txt"), InputError);
}

TEST(ReadTrajectory, MalformedCopyOfRealFile) {
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  std::string text = read_text(dir / "freiburg1_xyz-rgbdslam.txt");
  // Drop the last field of line 101 (the TF comment is line 1).
  std::istringstream in(text);
  std::string line, out;
  for (int n = 1; std::getline(in, line); ++n) {
    if (n == 101) line = line.substr(0, line.rfind(' '));
    out += line + "\n";
  }
  TempDir tmp;
  write_text(tmp / "est.txt", out);
  try {
    read_trajectory(tmp / "est.txt");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(
        std::string(e.what()),
        (tmp / "est.txt").string() + ":101: 7 fields; expected 8: timestamp tx ty tz qx qy qz qw");
  }
}

bool bit_equal(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// Reads `file`, writes it, reads it back: the number of poses whose rotation matrix changed and the
// largest change of a rotation element. Timestamps and translations must come back bit for bit.
std::pair<std::size_t, double> round_trip(const fs::path& file, const fs::path& out) {
  const Trajectory in = read_trajectory(file);
  write_trajectory(out, in);
  const Trajectory back = read_trajectory(out);
  EXPECT_EQ(back.size(), in.size());
  std::size_t changed = 0;
  double max_change = 0;
  for (std::size_t i = 0; i < in.size() && i < back.size(); ++i) {
    EXPECT_TRUE(bit_equal(back.poses[i].timestamp, in.poses[i].timestamp)) << i;
    const auto& a = in.poses[i].world_from_cam.matrix();
    const auto& b = back.poses[i].world_from_cam.matrix();
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(bit_equal(a(k, 3), b(k, 3))) << i;
    const double change = (a.topLeftCorner<3, 3>() - b.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff();
    changed += change != 0.0;
    max_change = std::max(max_change, change);
  }
  return {changed, max_change};
}

TEST(WriteTrajectory, RoundTripIsBitExact) {
  OBJMAP_DATA_OR_SKIP(dir, "trajectories/fr1_xyz");
  TempDir tmp;
  // RGBD-SLAM's estimate and the groundtruth: every pose comes back bit for bit, rotation included.
  EXPECT_EQ(round_trip(dir / "freiburg1_xyz-rgbdslam.txt", tmp / "a.txt").first, 0u);
  EXPECT_EQ(round_trip(dir / "freiburg1_xyz-groundtruth.txt", tmp / "b.txt").first, 0u);
  // So writing what was read gives the same bytes again, header included.
  const Trajectory est = read_trajectory(dir / "freiburg1_xyz-rgbdslam.txt");
  write_trajectory(tmp / "out" / "t.txt", est, "written by a test\nsecond line");
  const std::string text = read_text(tmp / "out" / "t.txt");
  EXPECT_EQ(text.rfind("# written by a test\n# second line\n# timestamp tx ty tz qx qy qz qw\n", 0),
            0u);
  write_trajectory(tmp / "again.txt", read_trajectory(tmp / "out" / "t.txt"),
                   "written by a test\nsecond line");
  EXPECT_EQ(read_text(tmp / "again.txt"), text);
}

TEST(WriteTrajectory, RoundTripRotationsWithinTwoUlps) {
  // A few rotations have no double quaternion that reproduces them exactly within the search:
  // they come back within 2 ulps (4.4e-16); timestamps and translations are still bit-exact.
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_rpy_every4");
  TempDir tmp;
  const auto [changed, max_change] = round_trip(dir / "groundtruth.txt", tmp / "gt.txt");
  EXPECT_LT(changed, 2742u / 20);  // measured: 90 of 2742
  EXPECT_LE(max_change, 4.5e-16);
}

TEST(WriteTrajectory, ShortestRoundTripNumbers) {
  Trajectory t;
  t.poses.push_back({1305031453.359684, Pose::Identity()});
  t.poses.back().world_from_cam.translation() = Vec3(0.1, -2.5, 1.0 / 3.0);
  EXPECT_EQ(format_trajectory(t),
            "# timestamp tx ty tz qx qy qz qw\n"
            "1305031453.359684 0.1 -2.5 0.3333333333333333 0 0 0 1\n");
}

// ---- lookup ----

Trajectory two_poses() {
  Trajectory t;
  Pose a = Pose::Identity();
  a.translation() = Vec3(0, 0, 0);
  Pose b = Pose::Identity();
  b.translation() = Vec3(2, 4, -6);
  b.linear() = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).toRotationMatrix();
  t.poses = {{10.0, a}, {10.02, b}};
  return t;
}

TEST(LookupPose, NearestWithinMaxDiff) {
  const Trajectory t = two_poses();
  PoseLookupOptions o;  // 0.02 s, nearest
  EXPECT_TRUE(lookup_pose(t, 10.004, o)->isApprox(t.poses[0].world_from_cam, 0.0));
  EXPECT_TRUE(lookup_pose(t, 10.016, o)->isApprox(t.poses[1].world_from_cam, 0.0));
  EXPECT_TRUE(lookup_pose(t, 10.035, o)->isApprox(t.poses[1].world_from_cam, 0.0));
  EXPECT_FALSE(lookup_pose(t, 10.05, o).has_value());
  EXPECT_FALSE(lookup_pose(t, 9.97, o).has_value());
  EXPECT_FALSE(lookup_pose(Trajectory{}, 1.0, o).has_value());
}

TEST(LookupPose, SlerpExactAtStampsAndHalfway) {
  const Trajectory t = two_poses();
  const PoseLookupOptions o{0.02, true};
  // Exact at the stamps: the stored poses, bit for bit.
  EXPECT_EQ(lookup_pose(t, 10.0, o)->matrix(), t.poses[0].world_from_cam.matrix());
  EXPECT_EQ(lookup_pose(t, 10.02, o)->matrix(), t.poses[1].world_from_cam.matrix());
  // Halfway: half the translation, 45 degrees about z.
  const double mid = 10.0 + (10.02 - 10.0) / 2;
  const Pose p = *lookup_pose(t, mid, o);
  EXPECT_TRUE(p.translation().isApprox(Vec3(1, 2, -3), 1e-12));
  const Eigen::AngleAxisd aa(p.linear());
  EXPECT_NEAR(aa.angle(), M_PI / 4, 1e-12);
  EXPECT_TRUE(aa.axis().isApprox(Vec3::UnitZ(), 1e-12));
  // A quarter of the way: 22.5 degrees.
  const Pose q = *lookup_pose(t, 10.005, o);
  EXPECT_NEAR(Eigen::AngleAxisd(q.linear()).angle(), M_PI / 8, 1e-9);
  EXPECT_TRUE(q.translation().isApprox(Vec3(0.5, 1, -1.5), 1e-9));
}

TEST(LookupPose, InterpolatesOnlyWhenBothNeighboursAreWithinMaxDiff) {
  const Trajectory t = two_poses();
  const PoseLookupOptions o{0.012, true};
  // 10.005: previous 0.005 away, next 0.015 away (> 0.012): nearest, no interpolation.
  EXPECT_TRUE(lookup_pose(t, 10.005, o)->isApprox(t.poses[0].world_from_cam, 0.0));
  // 10.01: both 0.01 away: interpolated.
  EXPECT_TRUE(lookup_pose(t, 10.01, o)->translation().isApprox(Vec3(1, 2, -3), 1e-9));
  // Past the end: no extrapolation.
  EXPECT_TRUE(lookup_pose(t, 10.03, o)->isApprox(t.poses[1].world_from_cam, 0.0));
}

TEST(LookupPose, OptionsOutOfRange) {
  const Trajectory t = two_poses();
  for (double bad : {-0.01, std::nan(""), HUGE_VAL}) {
    PoseLookupOptions o;
    o.max_diff_s = bad;
    try {
      lookup_pose(t, 10.0, o);
      FAIL() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "PoseLookupOptions.max_diff_s");
    }
  }
  PoseLookupOptions zero;
  zero.max_diff_s = 0;  // exact stamps only
  EXPECT_TRUE(lookup_pose(t, 10.02, zero).has_value());
  EXPECT_FALSE(lookup_pose(t, 10.0200001, zero).has_value());
}

}  // namespace
}  // namespace objmap::io

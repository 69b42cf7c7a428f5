// Pose correction on small constructed problems whose answer is known.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "objmap/core/error.h"
#include "objmap/pose/align.h"
#include "objmap/pose/correct.h"

namespace objmap::pose {
namespace {

Pose make_pose(double yaw, double pitch, const Vec3& t) {
  Pose p = Pose::Identity();
  p.linear() = (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()))
                   .toRotationMatrix();
  p.translation() = t;
  return p;
}

// A camera orbiting 8 landmarks on a table, looking at the table centre.
struct Scene {
  std::vector<Pose> truth;
  std::vector<Vec3> landmarks;
};

Scene orbit_scene(int keyframes) {
  Scene s;
  for (int j = 0; j < 8; ++j)
    s.landmarks.push_back(Vec3(0.4 * std::cos(0.8 * j), 0.3 * std::sin(1.1 * j), 0.05 * (j % 3)));
  for (int k = 0; k < keyframes; ++k) {
    const double a = 0.03 * k;  // radians along the orbit
    const Vec3 position(1.5 * std::cos(a), 1.5 * std::sin(a), 0.5);
    // Camera z toward the table centre.
    const Vec3 z = (-position).normalized();
    const Vec3 x = z.cross(Vec3::UnitZ()).normalized();
    const Vec3 y = z.cross(x);
    Pose p = Pose::Identity();
    p.linear().col(0) = x;
    p.linear().col(1) = y;
    p.linear().col(2) = z;
    p.translation() = position;
    s.truth.push_back(p);
  }
  return s;
}

// Observations of every landmark from every keyframe, measured with the true poses, plus noise.
Problem observe(const Scene& s, const std::vector<Pose>& input, double noise_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  Problem p;
  for (std::size_t k = 0; k < input.size(); ++k)
    p.keyframes.push_back({static_cast<double>(k), input[k]});
  for (std::size_t j = 0; j < s.landmarks.size(); ++j)
    p.landmarks.push_back({static_cast<int>(j), s.landmarks[j]});
  for (std::size_t k = 0; k < input.size(); ++k)
    for (std::size_t j = 0; j < s.landmarks.size(); ++j) {
      Observation o;
      o.keyframe = k;
      o.landmark = j;
      o.centroid_in_cam =
          s.truth[k].inverse() * s.landmarks[j] + Vec3(noise(rng), noise(rng), noise(rng));
      p.observations.push_back(o);
    }
  return p;
}

// Drift: a yaw about the first position and a translation growing with the keyframe index.
std::vector<Pose> drifted(const std::vector<Pose>& truth, double yaw_per_kf, double m_per_kf) {
  std::vector<Pose> out;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    Pose d = Pose::Identity();
    d.linear() = Eigen::AngleAxisd(yaw_per_kf * k, Vec3::UnitZ()).toRotationMatrix();
    d.translation() = truth[0].translation() - d.linear() * truth[0].translation() +
                      Vec3(m_per_kf * k, 0.5 * m_per_kf * k, 0.0);
    out.push_back(d * truth[k]);
  }
  return out;
}

// Acceptance thresholds off (residual drop, held-out observations): the tests of other guardrails.
CorrectionOptions without_thresholds() {
  CorrectionOptions options;
  options.min_improvement = 0.0;
  options.min_held_out_improvement = -1.0;
  return options;
}

double position_rms(const std::vector<Pose>& a, const std::vector<Pose>& b) {
  double sum = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
    sum += (a[k].translation() - b[k].translation()).squaredNorm();
  return std::sqrt(sum / a.size());
}

TEST(AlignRigid, RecoversAKnownTransformExactly) {
  const Pose truth = make_pose(0.7, -0.3, Vec3(0.5, -1.2, 2.0));
  const std::vector<Vec3> source = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0.3, 0.1, 1.5}, {-1, 1, 1}};
  std::vector<Vec3> target;
  for (const Vec3& p : source) target.push_back(truth * p);
  const Pose found = align_rigid(source, target);
  EXPECT_LT((found.matrix() - truth.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  // Three non-collinear points are enough.
  const Pose three =
      align_rigid({source.begin(), source.begin() + 3}, {target.begin(), target.begin() + 3});
  EXPECT_LT((three.matrix() - truth.matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

// align_rigid is Umeyama's method with weights: without weights it gives Eigen::umeyama's answer,
// and with whole weights that of Eigen::umeyama on each pair repeated as often as its weight.
TEST(AlignRigid, IsEigenUmeyamaWithWeights) {
  const Pose truth = make_pose(-1.1, 0.4, Vec3(2.0, 0.3, -0.7));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Vec3> source, target;
  for (int i = 0; i < 12; ++i) {
    source.emplace_back(0.3 * i - 1.0, std::sin(1.3 * i), 0.1 * i * i - 2.0);
    target.push_back(truth * source.back() + Vec3(noise(rng), noise(rng), noise(rng)));
  }
  const auto umeyama = [](const std::vector<Vec3>& s, const std::vector<Vec3>& t) {
    Eigen::Matrix3Xd sm(3, s.size()), tm(3, t.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
      sm.col(static_cast<Eigen::Index>(i)) = s[i];
      tm.col(static_cast<Eigen::Index>(i)) = t[i];
    }
    return Eigen::Matrix4d(Eigen::umeyama(sm, tm, /*with_scaling=*/false));
  };
  EXPECT_LT((align_rigid(source, target).matrix() - umeyama(source, target)).cwiseAbs().maxCoeff(),
            1e-12);
  std::vector<double> weights;
  std::vector<Vec3> source_repeated, target_repeated;
  for (std::size_t i = 0; i < source.size(); ++i) {
    weights.push_back(static_cast<double>(1 + i % 3));
    for (std::size_t r = 0; r < 1 + i % 3; ++r) {
      source_repeated.push_back(source[i]);
      target_repeated.push_back(target[i]);
    }
  }
  EXPECT_LT(
      (align_rigid(source, target, weights).matrix() - umeyama(source_repeated, target_repeated))
          .cwiseAbs()
          .maxCoeff(),
      1e-12);
}

TEST(AlignRigid, BadInputSaysWhatIsWrong) {
  try {
    align_rigid({Vec3::Zero(), Vec3::Ones()}, {Vec3::Zero()});
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "align_rigid: 2 source and 1 target points; expected the same count");
  }
  EXPECT_THROW(align_rigid({}, {}), InputError);
}

TEST(Spread, CollinearPointsHaveNone) {
  EXPECT_NEAR(spread_m({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {-3, -3, -3}}), 0.0, 1e-6);
  EXPECT_NEAR(spread_m({{0, 0, 0}, {1, 0, 0}}), 0.0, 0.0);
  EXPECT_NEAR(spread_m({{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}}), 1.0, 1e-12);
}

TEST(CorrectPoses, GraphRecoversAKnownDrift) {
  const Scene s = orbit_scene(30);
  const std::vector<Pose> input = drifted(s.truth, 0.002, 0.001);  // 3.3 deg and 3 cm at the end
  const Problem problem = observe(s, input, 0.002, 1);
  const CorrectionResult r = correct_poses(problem, {});
  ASSERT_TRUE(r.accepted) << r.reason;
  const double before = position_rms(input, s.truth);
  const double after = position_rms(r.world_from_cam, s.truth);
  EXPECT_GT(before, 0.015);
  EXPECT_LT(after, 0.4 * before) << before << " -> " << after;
  EXPECT_LT(r.residual_after_m, r.residual_before_m);
  EXPECT_EQ(r.keyframes[0].reason, "fixed (gauge)");
  EXPECT_EQ(r.keyframes[0].translation_m, 0.0);
}

// View links (relative poses measured by aligning two views of one object): with one landmark
// only, its centroid cannot fix the rotation drift; links between consecutive keyframes and back to
// the first ones (the camera's loop) can.
TEST(CorrectPoses, ViewLinksRecoverADriftOneLandmarkCannot) {
  const Scene s = orbit_scene(30);
  const std::vector<Pose> input = drifted(s.truth, 0.004, 0.002);  // 6.6 deg and 6.5 cm at the end
  Problem problem = observe(s, input, 0.002, 2);
  problem.observations.erase(
      std::remove_if(problem.observations.begin(), problem.observations.end(),
                     [](const Observation& o) { return o.landmark != 0; }),
      problem.observations.end());
  const CorrectionResult alone = correct_poses(problem, {});
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (std::size_t b = 1; b < input.size(); ++b)
    for (std::size_t a : {b - 1, std::size_t{0}}) {
      if (a == 0 && b > 1 && a == b - 1) continue;
      if (a == 0 && b == 1 && problem.links.size() == 1) continue;  // (0, 1) once
      ViewLink l{a, b, 0, s.truth[a].inverse() * s.truth[b]};
      l.a_from_b.translation() += 0.002 * Vec3(noise(rng), noise(rng), noise(rng));
      problem.links.push_back(l);
    }
  CorrectionOptions options = without_thresholds();
  options.max_rotation_deg = 10.0;
  const CorrectionResult linked = correct_poses(problem, options);
  ASSERT_TRUE(linked.accepted) << linked.reason;
  const double before = position_rms(input, s.truth);
  const double after = position_rms(linked.world_from_cam, s.truth);
  EXPECT_LT(after, 0.25 * before) << before << " -> " << after;
  EXPECT_LT(after, position_rms(alone.proposed, s.truth));
  EXPECT_LT(linked.link_rms_after_sigmas, 0.5 * linked.link_rms_before_sigmas);
  EXPECT_LT(linked.held_out_link_after_sigmas, 0.75 * linked.held_out_link_before_sigmas);
}

TEST(CorrectPoses, ViewLinksThatDisagreeWithTheDriftAreRefused) {
  // Links that measure noise, not the drift: the held-out links do not get closer.
  const Scene s = orbit_scene(20);
  Problem problem = observe(s, s.truth, 0.002, 4);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (std::size_t b = 1; b < s.truth.size(); ++b) {
    ViewLink l{b - 1, b, 0, s.truth[b - 1].inverse() * s.truth[b]};
    l.a_from_b.translation() += Vec3(noise(rng), noise(rng), noise(rng));
    problem.links.push_back(l);
  }
  CorrectionOptions options = without_thresholds();
  const CorrectionResult r = correct_poses(problem, options);
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.reason.rfind("refused: too little gain on held-out view links", 0), 0u) << r.reason;
}

TEST(CorrectPoses, ACorrectionBelowAMillimetreIsRefused) {
  const Scene s = orbit_scene(20);
  const std::vector<Pose> input = drifted(s.truth, 0.00001, 0.00002);  // 0.4 mm at the end
  const Problem problem = observe(s, input, 0.00005, 7);
  CorrectionOptions options = without_thresholds();
  const CorrectionResult r = correct_poses(problem, options);
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.reason.rfind("refused: nothing to correct", 0), 0u) << r.reason;
  options.min_translation_m = 0.0;
  options.min_rotation_deg = 0.0;
  EXPECT_TRUE(correct_poses(problem, options).accepted);
}

TEST(CorrectPoses, BoundsGrowWithThePathTravelled) {
  const Scene s = orbit_scene(30);
  const std::vector<Pose> input = drifted(s.truth, 0.002, 0.004);  // 12 cm at the end
  const Problem problem = observe(s, input, 0.002, 6);
  CorrectionOptions options;
  options.max_translation_m = 0.03;
  const CorrectionResult fixed = correct_poses(problem, options);
  EXPECT_FALSE(fixed.accepted);
  EXPECT_EQ(fixed.reason.rfind("refused: a keyframe would move", 0), 0u) << fixed.reason;
  options.max_translation_fraction = 0.2;  // the orbit is 1.3 m long: 0.03 + 0.26 m at the end
  const CorrectionResult grown = correct_poses(problem, options);
  EXPECT_TRUE(grown.accepted) << grown.reason;
}

TEST(CorrectPoses, PaperRecoversAPerturbedKeyframeExactly) {
  const Scene s = orbit_scene(5);
  std::vector<Pose> input = s.truth;
  input[3] = make_pose(0.02, 0.01, Vec3(0.03, -0.02, 0.01)) * input[3];
  const Problem problem = observe(s, input, 0.0, 1);
  CorrectionOptions options;
  options.method = "paper";
  options.paper_prior = false;  // eq 20 alone
  options.held_out_check = false;
  const CorrectionResult r = correct_poses(problem, options);
  ASSERT_TRUE(r.accepted) << r.reason;
  EXPECT_LT((r.world_from_cam[3].matrix() - s.truth[3].matrix()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(r.keyframes[3].reason, "corrected (eq 20, 8 objects)");
  EXPECT_FALSE(r.keyframes[0].corrected);  // already exact: no decrease, refused
}

TEST(CorrectPoses, PaperRefusesTooFewOrCollinearObjects) {
  Scene s = orbit_scene(4);
  std::vector<Pose> input = s.truth;
  input[1] = make_pose(0.02, 0.0, Vec3(0.03, 0.0, 0.0)) * input[1];
  Problem few = observe(s, input, 0.0, 1);
  // Keyframe 1 keeps only two observations.
  std::vector<Observation> kept;
  for (const auto& o : few.observations)
    if (o.keyframe != 1 || o.landmark < 2) kept.push_back(o);
  few.observations = kept;
  CorrectionOptions options;
  options.method = "paper";
  const CorrectionResult r = correct_poses(few, options);
  EXPECT_EQ(r.keyframes[1].reason, "refused: 2 matched objects, needs 3");
  EXPECT_FALSE(r.keyframes[1].corrected);

  // Collinear landmarks: a rotation about their line is not observable.
  for (std::size_t j = 0; j < s.landmarks.size(); ++j) s.landmarks[j] = Vec3(0.1 * j, 0.1 * j, 0.0);
  const CorrectionResult c = correct_poses(observe(s, input, 0.0, 1), options);
  EXPECT_FALSE(c.accepted);
  EXPECT_EQ(c.keyframes[1].reason.rfind("refused: objects nearly collinear", 0), 0u)
      << c.keyframes[1].reason;
  EXPECT_EQ(c.reason, "refused: no keyframe has enough evidence for a correction");
  EXPECT_EQ(c.world_from_cam[1].matrix(), input[1].matrix());  // the input, untouched
}

TEST(CorrectPoses, NoDriftIsRefusedNotFitted) {
  const Scene s = orbit_scene(30);
  for (const std::string method : {"graph", "paper"}) {
    CorrectionOptions options;
    options.method = method;
    const Problem problem = observe(s, s.truth, 0.01, 7);
    const CorrectionResult r = correct_poses(problem, options);
    EXPECT_FALSE(r.accepted) << method << ": " << r.reason;
    EXPECT_EQ(position_rms(r.world_from_cam, s.truth), 0.0) << method;
  }
}

TEST(CorrectPoses, BoundsRefuseALargeCorrection) {
  const Scene s = orbit_scene(30);
  const std::vector<Pose> input = drifted(s.truth, 0.002, 0.001);
  CorrectionOptions options;
  options.max_translation_m = 0.005;
  const CorrectionResult r = correct_poses(observe(s, input, 0.002, 1), options);
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.reason.rfind("refused: a keyframe would move", 0), 0u) << r.reason;
}

TEST(CorrectPoses, BadInputThrowsWithTheReason) {
  Problem p;
  p.keyframes.push_back({0.0, Pose::Identity()});
  p.landmarks.push_back({1, Vec3::Zero()});
  p.observations.push_back({3, 0, Vec3::Ones(), Vec3::Zero(), 1.0});
  try {
    correct_poses(p, {});
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "observation 0: keyframe 3 does not exist; expected < 1");
  }
  p.observations.clear();
  p.keyframes.push_back({1.0, Pose::Identity()});
  p.links.push_back({1, 1, 0, Pose::Identity()});
  try {
    correct_poses(p, {});
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "link 0: keyframes 1 and 1: expected two different keyframes < 2");
  }
  CorrectionOptions bad;
  bad.method = "icp";
  try {
    bad.check();
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "CorrectionOptions.method: 'icp' is not a method; expected graph or paper");
  }
}

TEST(ApplyCorrections, InterpolatesBetweenKeyframesAndHoldsOutside) {
  Trajectory input;
  for (int i = 0; i <= 4; ++i)
    input.poses.push_back({0.5 * i, make_pose(0.1 * i, 0, Vec3(i, 0, 0))});
  const std::vector<StampedPose> before = {input.poses[1], input.poses[3]};
  Pose shift = Pose::Identity();
  shift.translation() = Vec3(0, 0.2, 0);
  const std::vector<Pose> after = {before[0].world_from_cam, shift * before[1].world_from_cam};
  const Trajectory out = apply_corrections(input, before, after);
  ASSERT_EQ(out.size(), input.size());
  const auto dy = [&](int i) {
    return out.poses[i].world_from_cam.translation().y() -
           input.poses[i].world_from_cam.translation().y();
  };
  EXPECT_NEAR(dy(0), 0.0, 1e-12);  // before the first keyframe: its correction (none)
  EXPECT_NEAR(dy(1), 0.0, 1e-12);
  EXPECT_NEAR(dy(2), 0.1, 1e-12);  // halfway
  EXPECT_NEAR(dy(3), 0.2, 1e-12);
  EXPECT_NEAR(dy(4), 0.2, 1e-12);  // after the last: held
  EXPECT_EQ(out.poses[2].timestamp, 1.0);
}

}  // namespace
}  // namespace objmap::pose

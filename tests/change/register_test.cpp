// Registration of two visits: a known yaw + translation recovered; pairs that do not register say
// why.
#include <gtest/gtest.h>

#include "change/change_test_util.h"
#include "objmap/change/register.h"
#include "objmap/core/error.h"

namespace objmap::change {
namespace {

using testing::make_test_visit;
using testing::moved_visit;
using testing::test_objects;
using testing::yaw_shift;

double rotation_error_deg(const Pose& a, const Pose& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

TEST(Register, RecoversAKnownYawAndTranslation) {
  const Visit before = make_test_visit(test_objects());
  const Pose after_from_before = yaw_shift(37.0, Vec3(1.2, -0.7, 0.1));
  const Visit after = moved_visit(before, after_from_before);
  const Registration r = register_visits(before, after, {});
  ASSERT_TRUE(r.credible) << r.why;
  const Pose truth = after_from_before.inverse();
  EXPECT_LT((r.before_from_after.translation() - truth.translation()).norm(), 0.001);
  EXPECT_LT(rotation_error_deg(r.before_from_after, truth), 0.05);
  EXPECT_NEAR(r.yaw_deg, -37.0, 0.05);
  EXPECT_EQ(r.common_objects, 8);
  EXPECT_GT(r.fitness, 0.95);
  EXPECT_GT(r.sigma_translation_m, 0.0);
  EXPECT_LT(r.sigma_translation_m, 0.01);
  EXPECT_LT(r.sigma_yaw_deg, 0.5);
}

TEST(Register, RecoversAHalfTurnWithTiltedUp) {
  // Both maps' up is not +z in their world: the gravity frames carry it.
  const Visit flat = make_test_visit(test_objects());
  Pose tilt = Pose::Identity();
  tilt.linear() = Eigen::AngleAxisd(0.3, Vec3::UnitX()).matrix();
  Visit before = moved_visit(flat, tilt);
  before.gravity_from_world = tilt.linear().transpose();
  before.up_in_world = tilt.linear() * Vec3::UnitZ();
  const Pose after_from_flat = yaw_shift(180.0, Vec3(-0.4, 2.0, 0.0));
  const Visit after = moved_visit(flat, after_from_flat);
  const Registration r = register_visits(before, after, {});
  ASSERT_TRUE(r.credible) << r.why;
  const Pose truth = tilt * after_from_flat.inverse();
  EXPECT_LT((r.before_from_after.translation() - truth.translation()).norm(), 0.001);
  EXPECT_LT(rotation_error_deg(r.before_from_after, truth), 0.05);
}

TEST(Register, OneCommonObjectNeedsTheDenseMapsToAgree) {
  const std::vector<testing::TestObject> all = test_objects();
  const std::vector<testing::TestObject> one(all.begin(), all.begin() + 1);
  const Visit before = make_test_visit(one);
  // The same room: a yaw sweep about the one object finds it, the dense maps agree.
  const Pose after_from_before = yaw_shift(20.0, Vec3(0.3, 0.1, 0.0));
  const Registration same = register_visits(before, moved_visit(before, after_from_before), {});
  ASSERT_TRUE(same.credible) << same.why;
  EXPECT_LT(rotation_error_deg(same.before_from_after, after_from_before.inverse()), 0.05);
  // Another place with that object: not credible, too few common objects.
  Visit other = make_test_visit(one);
  other.dense.clear();
  for (double x = -2.0; x <= 2.0; x += 0.02)
    for (double z = 0.0; z <= 2.5; z += 0.02) other.dense.push_back(Vec3f(x, -0.6f, z));
  for (const Vec3f& p : other.objects[0].points) other.dense.push_back(p);
  const Registration r = register_visits(before, other, {});
  EXPECT_FALSE(r.credible) << r.fitness;
  EXPECT_NE(r.why.find("too few common objects"), std::string::npos) << r.why;
}

TEST(Register, AnotherPlaceHasALowFitness) {
  // The same kinds of objects, laid out alike, but in another place: no floor, no table, a wall
  // right in front of them.
  const Visit before = make_test_visit(test_objects());
  Visit other = make_test_visit(test_objects());
  other.dense.clear();
  for (double x = -2.0; x <= 2.0; x += 0.02)
    for (double z = 0.0; z <= 2.5; z += 0.02) other.dense.push_back(Vec3f(x, -0.6f, z));
  for (const VisitObject& o : other.objects)
    for (const Vec3f& p : o.points) other.dense.push_back(p);
  const Registration r = register_visits(before, other, {});
  EXPECT_FALSE(r.credible);
  EXPECT_NE(r.why.find("ICP fitness"), std::string::npos) << r.why;
}

TEST(Register, GivenTransformIsKeptAndScored) {
  const Visit before = make_test_visit(test_objects());
  const Pose after_from_before = yaw_shift(-75.0, Vec3(0.5, 0.5, 0.0));
  const Visit after = moved_visit(before, after_from_before);
  const Registration r = score_registration(before, after, after_from_before.inverse(), {});
  EXPECT_TRUE(r.credible);
  EXPECT_EQ(r.source, "given");
  EXPECT_TRUE(r.before_from_after.isApprox(after_from_before.inverse()));
  EXPECT_GT(r.fitness, 0.95);
  EXPECT_EQ(r.common_objects, 8);
}

TEST(Register, OptionsNameTheBadField) {
  RegistrationOptions o;
  o.min_fitness = 1.5;
  try {
    o.check();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "RegistrationOptions.min_fitness");
  }
}

}  // namespace
}  // namespace objmap::change

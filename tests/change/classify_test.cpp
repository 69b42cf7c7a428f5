// Object statuses between two registered visits, on scenes whose answer is known.
#include <gtest/gtest.h>

#include <algorithm>

#include "change/change_test_util.h"
#include "objmap/change/classify.h"

namespace objmap::change {
namespace {

using testing::make_test_visit;
using testing::moved_visit;
using testing::test_objects;
using testing::TestObject;
using testing::yaw_shift;

const ObjectChange* with_before_id(const ChangeResult& r, int id) {
  for (const ObjectChange& c : r.objects)
    if (c.before_id && *c.before_id == id) return &c;
  return nullptr;
}

const ObjectChange* with_after_id(const ChangeResult& r, int id) {
  for (const ObjectChange& c : r.objects)
    if (c.after_id && *c.after_id == id) return &c;
  return nullptr;
}

// The after visit: cup 4 moved 0.6 m along +x, the bottle (6) gone, a book (9) added, all in
// another world frame.
struct ChangedPair {
  Visit before, after;
  Pose before_from_after;
};

ChangedPair changed_pair() {
  std::vector<TestObject> objects = test_objects();
  ChangedPair p;
  p.before = make_test_visit(objects);
  objects[3].centre += Vec3(0.6, 0.0, 0.0);                                // cup 4 moved
  objects.erase(objects.begin() + 5);                                      // bottle 6 removed
  objects.push_back({9, "book", {-0.45, 0.05, 0.77}, {0.1, 0.07, 0.02}});  // book 9 added
  const Pose after_from_before = yaw_shift(50.0, Vec3(1.0, 2.0, 0.0));
  p.after = moved_visit(make_test_visit(objects), after_from_before);
  p.before_from_after = after_from_before.inverse();
  return p;
}

TEST(Classify, MovedRemovedAddedAndTheRestUnchanged) {
  const ChangedPair p = changed_pair();
  const ChangeResult r = classify_changes(p.before, p.after, p.before_from_after, {});
  const ObjectChange* cup = with_before_id(r, 4);
  ASSERT_NE(cup, nullptr);
  EXPECT_EQ(cup->status, Status::kMoved) << cup->why;
  ASSERT_TRUE(cup->after_id);
  EXPECT_EQ(*cup->after_id, 4);
  EXPECT_LT((cup->displacement - Vec3(0.6, 0, 0)).norm(), 1e-9);
  const ObjectChange* bottle = with_before_id(r, 6);
  ASSERT_NE(bottle, nullptr);
  EXPECT_EQ(bottle->status, Status::kRemoved) << bottle->why;
  ASSERT_TRUE(bottle->evidence_after);
  EXPECT_GT(bottle->evidence_after->seen_through, bottle->evidence_after->surface);
  const ObjectChange* book = with_after_id(r, 9);
  ASSERT_NE(book, nullptr);
  EXPECT_EQ(book->status, Status::kAdded) << book->why;
  for (int id : {1, 2, 3, 5, 7, 8}) {
    const ObjectChange* c = with_before_id(r, id);
    ASSERT_NE(c, nullptr) << id;
    EXPECT_EQ(c->status, Status::kUnchanged) << id << ": " << c->why;
  }
  EXPECT_EQ(r.objects.size(), 9u);
}

TEST(Classify, OutOfViewIsNotSeenAgainNeverRemoved) {
  ChangedPair p = changed_pair();
  // The after visit looks only at the walls' far corner: the bottle's place is out of its view.
  Pose away = Pose::Identity();
  away.linear() = Eigen::AngleAxisd(M_PI, Vec3::UnitY()).matrix();  // about its image y axis
  for (Pose& c : p.after.world_from_cam) c = c * away;              // each camera turned round
  const ChangeResult r = classify_changes(p.before, p.after, p.before_from_after, {});
  const ObjectChange* bottle = with_before_id(r, 6);
  ASSERT_NE(bottle, nullptr);
  EXPECT_EQ(bottle->status, Status::kNotSeenAgain) << bottle->why;
}

TEST(Classify, UndetectedButPresentStaysUnchanged) {
  // The after map lost the detection of the keyboard, its surface is still in the dense map.
  ChangedPair p = changed_pair();
  p.after.objects.erase(std::remove_if(p.after.objects.begin(), p.after.objects.end(),
                                       [](const VisitObject& o) { return o.id == 2; }),
                        p.after.objects.end());
  const ChangeResult r = classify_changes(p.before, p.after, p.before_from_after, {});
  const ObjectChange* keyboard = with_before_id(r, 2);
  ASSERT_NE(keyboard, nullptr);
  EXPECT_EQ(keyboard->status, Status::kUnchanged) << keyboard->why;
  EXPECT_FALSE(keyboard->after_id);
}

TEST(Classify, ChangedClassAtTheSamePlace) {
  ChangedPair p = changed_pair();
  for (VisitObject& o : p.after.objects)
    if (o.id == 5) o.class_name = "bowl";
  const ChangeResult r = classify_changes(p.before, p.after, p.before_from_after, {});
  const ObjectChange* c = with_before_id(r, 5);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->status, Status::kChangedClass) << c->why;
}

TEST(Classify, SelfMovingClassesAreLeftOut) {
  ChangedPair p = changed_pair();
  p.before.objects.push_back(
      testing::make_visit_object({20, "person", {0, -1.0, 0.9}, {0.2, 0.2, 0.9}}));
  p.after.objects.push_back(testing::make_visit_object({21, "dog", {0, 0, 0.3}, {0.3, 0.1, 0.3}}));
  const ChangeResult r = classify_changes(p.before, p.after, p.before_from_after, {});
  EXPECT_EQ(with_before_id(r, 20), nullptr);
  EXPECT_EQ(with_after_id(r, 21), nullptr);
  ASSERT_EQ(r.left_out.size(), 2u);
  EXPECT_EQ(r.left_out[0].first, "dog");
  EXPECT_EQ(r.left_out[1].first, "person");
}

TEST(Classify, EvidenceOfAnEmptyPlaceAndOfAFullOne) {
  const Visit v = make_test_visit(test_objects());
  // A box 10 cm over the table where nothing stands: seen through to the table behind.
  const std::vector<Vec3f> empty =
      testing::box_surface(Vec3(-0.25, -0.3, 0.8), Vec3(-0.15, -0.2, 0.9), 0.01);
  std::vector<Vec3> points;
  for (const Vec3f& q : empty) points.push_back(q.cast<double>());
  const PlaceEvidence e = place_evidence(v, points, {});
  EXPECT_GT(e.sightlines, 100);
  EXPECT_EQ(e.surface, 0);
  // The keyboard's own points: its surface is there.
  points.clear();
  for (const Vec3f& q : v.objects[1].points) points.push_back(q.cast<double>());
  const PlaceEvidence f = place_evidence(v, points, {});
  EXPECT_GT(f.surface_share(), 0.9);
}

}  // namespace
}  // namespace objmap::change

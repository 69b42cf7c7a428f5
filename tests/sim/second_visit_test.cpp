// A second visit of a synthetic scene: the changes asked for, recorded exactly, with another world
// frame whose up is still +z.
#include <gtest/gtest.h>

#include <map>

#include "objmap/sim/presets.h"
#include "objmap/sim/second_visit.h"

namespace objmap::sim {
namespace {

TEST(SecondVisit, MovesRemovesAddsAndRecordsEachChange) {
  Scene scene = make_scene("tabletop", 11);
  const Scene first = scene;
  SecondVisitOptions o;
  o.enabled = true;
  o.move = 2;
  o.remove = 1;
  o.add = 1;
  const SecondVisit v = make_second_visit(scene, o, 111);
  std::map<std::string, int> count;
  for (const ObjectChangeGt& c : v.changes) ++count[c.status];
  EXPECT_EQ(count["moved"], 2);
  EXPECT_EQ(count["removed"], 1);
  EXPECT_EQ(count["added"], 1);
  EXPECT_EQ(count["unchanged"], static_cast<int>(first.objects.size()) - 3);
  EXPECT_EQ(scene.objects.size(), first.objects.size());  // one gone, one new
  // Up stays +z; the record's after positions are the scene's box centres.
  EXPECT_LT((v.after_from_before.linear() * Vec3::UnitZ() - Vec3::UnitZ()).norm(), 1e-12);
  for (const ObjectChangeGt& c : v.changes) {
    if (c.status == "unchanged") {
      const Vec3 moved = v.after_from_before * c.before_position;
      EXPECT_LT((moved - c.after_position).norm(), 1e-6) << c.class_name;
    }
    if (c.status == "moved") {
      const Vec3 back = v.after_from_before.inverse() * c.after_position;
      EXPECT_GE((back - c.before_position).head<2>().norm(), o.min_move_m - 1e-9);
    }
    if (c.after_id) {
      const SceneObject* now = scene.find(c.after_id);
      ASSERT_NE(now, nullptr);
      EXPECT_LT((v.after_from_before * now->obb.center - c.after_position).norm(), 1e-9);
    }
  }
}

TEST(SecondVisit, SameSeedSameVisit) {
  SecondVisitOptions o;
  o.enabled = true;
  Scene a = make_scene("office", 3), b = make_scene("office", 3);
  const SecondVisit va = make_second_visit(a, o, 7), vb = make_second_visit(b, o, 7);
  EXPECT_TRUE(va.after_from_before.isApprox(vb.after_from_before, 0.0));
  EXPECT_EQ(changes_gt_json(va, o), changes_gt_json(vb, o));
}

}  // namespace
}  // namespace objmap::sim

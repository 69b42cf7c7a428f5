#include <gtest/gtest.h>

#include <map>

#include <algorithm>
#include <cmath>
#include <set>

#include "objmap/core/error.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/scene.h"

namespace objmap::sim {
namespace {

SceneObject single(Shape shape, const Vec3& half, const Pose& world_from_object) {
  SceneObject o;
  o.id = 1;
  o.class_name = "thing";
  o.world_from_object = world_from_object;
  Part p;
  p.shape = shape;
  p.half_extent = half;
  o.parts.push_back(p);
  o.finalize(64);
  return o;
}

Pose pose(double x, double y, double z, double yaw_rad) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_rad, Vec3::UnitZ()).matrix();
  p.translation() = Vec3(x, y, z);
  return p;
}

TEST(Scene, RayHitsEachPrimitiveAtTheAnalyticDistance) {
  // Ray from (0, -2, 0.5) along +y (direction not unit: t scales with it).
  Ray ray;
  ray.origin = Vec3(0, -2, 0.5);
  ray.direction = Vec3(0, 2, 0);
  const SceneObject box = single(Shape::kBox, Vec3(0.2, 0.3, 0.5), pose(0, 0, 0.5, 0));
  SurfaceHit hit;
  ASSERT_TRUE(intersect_object(box, ray, 1e-9, &hit));
  EXPECT_NEAR(hit.t, (2.0 - 0.3) / 2.0, 1e-12);
  EXPECT_NEAR(hit.normal_in_part.y(), -1.0, 1e-12);

  const SceneObject cyl = single(Shape::kCylinder, Vec3(0.1, 0.1, 0.2), pose(0, 0, 0.5, 0.7));
  hit = SurfaceHit();
  ASSERT_TRUE(intersect_object(cyl, ray, 1e-9, &hit));
  EXPECT_NEAR(hit.t, (2.0 - 0.1) / 2.0, 1e-12);

  const SceneObject ell = single(Shape::kEllipsoid, Vec3(0.1, 0.25, 0.3), pose(0, 0, 0.5, 0));
  hit = SurfaceHit();
  ASSERT_TRUE(intersect_object(ell, ray, 1e-9, &hit));
  EXPECT_NEAR(hit.t, (2.0 - 0.25) / 2.0, 1e-12);

  // From above onto the cylinder cap.
  Ray down;
  down.origin = Vec3(0.05, 0, 2.0);
  down.direction = Vec3(0, 0, -1);
  hit = SurfaceHit();
  ASSERT_TRUE(intersect_object(cyl, down, 1e-9, &hit));
  EXPECT_NEAR(hit.t, 2.0 - 0.7, 1e-12);

  // A ray passing beside misses.
  Ray beside;
  beside.origin = Vec3(0.5, -2, 0.5);
  beside.direction = Vec3(0, 1, 0);
  hit = SurfaceHit();
  EXPECT_FALSE(intersect_object(cyl, beside, 1e-9, &hit));
}

TEST(Scene, DistanceToSurfaceIsExactForBoxesAndCylinders) {
  const SceneObject box = single(Shape::kBox, Vec3(0.2, 0.3, 0.5), pose(1, 2, 0.5, 0.4));
  const Pose& w = box.world_from_part[0];
  EXPECT_NEAR(distance_to_surface(box, w * Vec3(0.2, 0.1, 0.0)), 0.0, 1e-12);
  EXPECT_NEAR(distance_to_surface(box, w * Vec3(0.25, 0.1, 0.0)), 0.05, 1e-12);
  EXPECT_NEAR(distance_to_surface(box, w * Vec3(0.15, 0.0, 0.0)), 0.05, 1e-12);   // inside
  EXPECT_NEAR(distance_to_surface(box, w * Vec3(0.23, 0.34, 0.0)), 0.05, 1e-12);  // corner

  const SceneObject cyl = single(Shape::kCylinder, Vec3(0.1, 0.1, 0.2), pose(0, 0, 0.2, 0));
  EXPECT_NEAR(distance_to_surface(cyl, Vec3(0.13, 0, 0.2)), 0.03, 1e-12);
  EXPECT_NEAR(distance_to_surface(cyl, Vec3(0.0, 0, 0.45)), 0.05, 1e-12);

  const SceneObject ball = single(Shape::kEllipsoid, Vec3(0.1, 0.1, 0.1), pose(0, 0, 0, 0));
  EXPECT_NEAR(distance_to_surface(ball, Vec3(0.0, 0.13, 0.0)), 0.03, 1e-9);
  const SceneObject ell = single(Shape::kEllipsoid, Vec3(0.1, 0.2, 0.3), pose(0, 0, 0, 0));
  EXPECT_NEAR(distance_to_surface(ell, Vec3(0.0, 0.0, 0.3)), 0.0, 1e-12);
  EXPECT_NEAR(distance_to_surface(ell, Vec3(0.0, 0.201, 0.0)), 0.001, 1e-5);
}

TEST(Scene, CentroidAndVolumeOfSimpleSolids) {
  const SceneObject box = single(Shape::kBox, Vec3(0.1, 0.2, 0.3), pose(1, 2, 3, 0.3));
  EXPECT_LT((box.centroid - Vec3(1, 2, 3)).norm(), 1e-9);
  EXPECT_NEAR(box.volume_m3, 0.2 * 0.4 * 0.6, 1e-9);
  const SceneObject cyl = single(Shape::kCylinder, Vec3(0.05, 0.05, 0.1), pose(0, 0, 0, 0));
  EXPECT_NEAR(cyl.volume_m3, M_PI * 0.05 * 0.05 * 0.2, 0.02 * M_PI * 0.05 * 0.05 * 0.2);
  EXPECT_NEAR(cyl.obb.half_extent.x(), 0.05, 1e-12);
  EXPECT_NEAR(cyl.obb.half_extent.z(), 0.1, 1e-12);
}

TEST(Scene, PresetsHaveThePaperClassesAndTheirBoxesCoverEveryPart) {
  for (const std::string preset : {"tabletop", "office", "walkthrough"}) {
    const Scene scene = make_scene(preset, 3);
    std::multiset<std::string> classes;
    for (const auto& o : scene.objects) classes.insert(o.class_name);
    for (const auto& name : paper_classes()) EXPECT_GE(classes.count(name), 1u) << preset << name;
    EXPECT_GE(classes.count("cup"), 2u);
    EXPECT_GE(classes.count("book"), 3u);
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      const SceneObject& o = scene.objects[i];
      EXPECT_EQ(o.id, static_cast<int>(i) + 1);
      EXPECT_TRUE(o.obb.contains(o.centroid)) << o.class_name;
      EXPECT_TRUE(inside_object(o, o.centroid) || o.class_name == "chair" ||
                  o.class_name == "tv monitor")
          << o.class_name;  // compositions may have their centroid in a gap
      // Sample each part's box of points: those inside the part must be inside the object's OBB.
      for (std::size_t p = 0; p < o.parts.size(); ++p) {
        const Part& part = o.parts[p];
        int inside = 0;
        for (int a = -4; a <= 4; ++a)
          for (int b = -4; b <= 4; ++b)
            for (int c = -4; c <= 4; ++c) {
              const Vec3 q = Vec3(a, b, c).cwiseProduct(part.half_extent) / 4.0;
              if (!inside_part(part, q)) continue;
              ++inside;
              EXPECT_TRUE(o.obb.contains(o.world_from_part[p] * q, 1e-9)) << o.class_name;
            }
        EXPECT_GT(inside, 0);
      }
      // Plausible sizes: 3 cm .. 1 m.
      EXPECT_GT(o.obb.half_extent.maxCoeff(), 0.015) << o.class_name;
      EXPECT_LT(o.obb.half_extent.maxCoeff(), 0.5) << o.class_name;
    }
  }
}

TEST(Scene, EdgePresetObjectsStandOnTheTableCentimetresFromItsEdge) {
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    const Scene scene = make_scene("edge", seed);
    ASSERT_EQ(scene.objects.size(), 6u);
    // The table top: the structure part whose top is at table height.
    Vec3 top_half = Vec3::Zero(), top_center = Vec3::Zero();
    for (const auto& s : scene.structure)
      for (std::size_t p = 0; p < s.parts.size(); ++p)
        if (s.class_name == "table" && s.parts[p].half_extent.z() < 0.03) {
          top_half = s.parts[p].half_extent;
          top_center = s.world_from_part[p].translation();
        }
    ASSERT_GT(top_half.x(), 0.0);
    const double table_z = top_center.z() + top_half.z();
    for (const auto& o : scene.objects) {
      // Points sampled in its parts lie over the table, the outermost 1-3 cm from an edge.
      double gap_m = 1.0;
      for (std::size_t p = 0; p < o.parts.size(); ++p)
        for (int a = -8; a <= 8; ++a)
          for (int b = -8; b <= 8; ++b)
            for (int c = -8; c <= 8; ++c) {
              const Vec3 q = Vec3(a, b, c).cwiseProduct(o.parts[p].half_extent) / 8.0;
              if (!inside_part(o.parts[p], q)) continue;
              const Vec3 in_table = o.world_from_part[p] * q - top_center;
              gap_m = std::min({gap_m, top_half.x() - std::abs(in_table.x()),
                                top_half.y() - std::abs(in_table.y())});
            }
      EXPECT_GT(gap_m, 0.005) << o.class_name << " seed " << seed;
      EXPECT_LT(gap_m, 0.03) << o.class_name << " seed " << seed << " gap " << gap_m;
      // Standing on it (the teddy's legs sink 5 mm into it).
      EXPECT_NEAR(o.obb.center.z() - o.obb.half_extent.z(), table_z, 0.006) << o.class_name;
    }
  }
}

TEST(Scene, WalkthroughRoomHasTwelveChairsSomePackedSideBySide) {
  const Scene scene = make_scene("walkthrough", 5);
  EXPECT_EQ(scene.objects.size(), 32u);
  std::vector<Vec3> chairs;
  int on_floor = 0;
  for (const auto& o : scene.objects) {
    if (o.class_name == "chair") chairs.push_back(o.world_from_object.translation());
    on_floor += o.class_name != "chair" && o.world_from_object.translation().z() < 0.01;
  }
  EXPECT_EQ(chairs.size(), 12u);
  EXPECT_EQ(on_floor, 2) << "a teddy bear and a bottle on the floor";
  // Packed: a chair's nearest same-class neighbour 0.44-0.56 m away (seats 0.44 m wide) for the
  // dining table's long sides and the row along the wall: at least 8 chairs.
  int packed = 0;
  for (std::size_t i = 0; i < chairs.size(); ++i) {
    double nearest = 1e9;
    for (std::size_t j = 0; j < chairs.size(); ++j)
      if (j != i) nearest = std::min(nearest, (chairs[i] - chairs[j]).head<2>().norm());
    packed += nearest < 0.6;
  }
  EXPECT_GE(packed, 8);
}

TEST(Scene, ApartmentHasItsLargeFurnitureAtTheSizesOfItsClasses) {
  const Scene scene = make_scene("apartment", 2);
  EXPECT_EQ(scene.objects.size(), 10u);
  std::map<std::string, double> widest;  // the larger horizontal side of each class's box
  for (const auto& o : scene.objects)
    widest[o.class_name] = std::max(widest[o.class_name],
                                    2.0 * std::max(o.obb.half_extent.x(), o.obb.half_extent.y()));
  EXPECT_NEAR(widest["couch"], 2.0, 0.02);
  EXPECT_NEAR(widest["bed"], 2.0, 0.02);
  EXPECT_NEAR(widest["refrigerator"], 0.73, 0.02);
  EXPECT_NEAR(widest["toilet"], 0.68, 0.05);
  // Within the room (8 x 6 m) and standing on the floor, or on the bed (the teddy bear).
  for (const auto& o : scene.objects) {
    const Vec3 c = o.world_from_object.translation();
    EXPECT_LT(std::abs(c.x()) + 0.5 * widest[o.class_name], 4.0 + 1e-6) << o.class_name;
    EXPECT_LT(std::abs(c.y()), 3.0) << o.class_name;
  }
}

TEST(Scene, UnknownPresetIsAnInputError) {
  try {
    make_scene("garden", 1);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--preset");
    EXPECT_NE(std::string(e.what()).find("garden"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("tabletop, office, edge, walkthrough or apartment"),
              std::string::npos);
  }
}

TEST(Scene, SeedMovesObjectsByCentimetres) {
  const Scene a = make_scene("tabletop", 1);
  const Scene b = make_scene("tabletop", 2);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  double moved = 0.0;
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    const double d = (a.objects[i].centroid - b.objects[i].centroid).norm();
    EXPECT_LT(d, 0.1);
    moved = std::max(moved, d);
  }
  EXPECT_GT(moved, 0.002);
}

}  // namespace
}  // namespace objmap::sim

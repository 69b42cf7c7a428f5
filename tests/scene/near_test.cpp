// `near` as a person means it (docs/scene.md, "Relations"): the clearance between two objects'
// boxes against a reach scaled to the smaller one, on boxes made here (z up).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "objmap/core/error.h"
#include "objmap/scene/near.h"
#include "objmap/scene/scene.h"

namespace objmap::scene {
namespace {

// A box's surface points (5 mm apart, or 100 along a longer side), standing on z = base_z, its
// centre at (x, y); sides sx × sy, height h.
PointCloud near_box(double x, double y, double base_z, double sx, double sy, double h) {
  PointCloud c;
  const auto step = [](double side) { return std::max(0.005, side / 100.0); };
  for (double u = -sx / 2; u <= sx / 2 + 1e-9; u += step(sx))
    for (double v = -sy / 2; v <= sy / 2 + 1e-9; v += step(sy)) {
      c.push_back(Vec3f(x + u, y + v, base_z), Rgb{});
      c.push_back(Vec3f(x + u, y + v, base_z + h), Rgb{});
    }
  for (double z = 0.0; z <= h + 1e-9; z += step(h)) {
    for (double u = -sx / 2; u <= sx / 2 + 1e-9; u += step(sx)) {
      c.push_back(Vec3f(x + u, y - sy / 2, base_z + z), Rgb{});
      c.push_back(Vec3f(x + u, y + sy / 2, base_z + z), Rgb{});
    }
    for (double v = -sy / 2; v <= sy / 2 + 1e-9; v += step(sy)) {
      c.push_back(Vec3f(x - sx / 2, y + v, base_z + z), Rgb{});
      c.push_back(Vec3f(x + sx / 2, y + v, base_z + z), Rgb{});
    }
  }
  return c;
}

SceneObject near_object(int id, const char* name, const PointCloud& cloud) {
  Vec3 lo = Vec3::Constant(1e9), hi = Vec3::Constant(-1e9);
  for (const Vec3f& p : cloud.points) {
    lo = lo.cwiseMin(p.cast<double>());
    hi = hi.cwiseMax(p.cast<double>());
  }
  return {id, name, (lo + hi) / 2, &cloud};
}

std::vector<Relations> near_relate(const std::vector<SceneObject>& objects,
                                   const RelationOptions& options = {}) {
  std::vector<Surface> none;
  return relate_objects(objects, none, Vec3::UnitZ(), SurfaceOptions{}, options);
}

const Neighbour* near_entry(const Relations& r, int id) {
  for (const Neighbour& n : r.near)
    if (n.id == id) return &n;
  return nullptr;
}

TEST(Near, AChairPulledUpToALongTableIsNearItNotByItsCentre) {
  // A 1.8 × 0.9 m dining table; a 0.45 m chair 5 cm from its long edge, at its middle.
  const PointCloud table = near_box(0.0, 0.0, 0.0, 1.8, 0.9, 0.75);
  const PointCloud chair = near_box(0.0, 0.45 + 0.05 + 0.225, 0.0, 0.45, 0.45, 0.9);
  const std::vector<SceneObject> objects = {near_object(1, "dining table", table),
                                            near_object(2, "chair", chair)};
  const auto relations = near_relate(objects);
  const Neighbour* n = near_entry(relations[1], 1);
  ASSERT_NE(n, nullptr);
  EXPECT_NEAR(n->distance_m, 0.05, 0.01);  // the gap, not the centres' 0.72 m
  ASSERT_NE(near_entry(relations[0], 2), nullptr);
  RelationOptions centres;  // the old rule: centres 0.72 m apart, beyond its 0.5 m
  centres.near_by_centres = true;
  EXPECT_EQ(near_entry(near_relate(objects, centres)[1], 1), nullptr);
}

TEST(Near, ACupIsNearALaptop30cmAwayNot2mAwayNorAFridge1mAway) {
  const PointCloud laptop = near_box(0.0, 0.0, 0.75, 0.35, 0.25, 0.02);
  const PointCloud cup_30cm = near_box(0.175 + 0.3 + 0.04, 0.0, 0.75, 0.08, 0.08, 0.1);
  const PointCloud cup_2m = near_box(0.0, 0.125 + 2.0 + 0.04, 0.75, 0.08, 0.08, 0.1);
  const PointCloud fridge = near_box(3.0, 0.0, 0.0, 0.7, 0.7, 1.8);
  const PointCloud cup_1m = near_box(3.0 - 0.35 - 1.0 - 0.04, 0.0, 0.9, 0.08, 0.08, 0.1);
  const std::vector<SceneObject> objects = {
      near_object(1, "laptop", laptop), near_object(2, "cup", cup_30cm),
      near_object(3, "cup", cup_2m), near_object(4, "refrigerator", fridge),
      near_object(5, "cup", cup_1m)};
  const auto relations = near_relate(objects);
  const Neighbour* n = near_entry(relations[1], 1);
  ASSERT_NE(n, nullptr);
  EXPECT_NEAR(n->distance_m, 0.30, 0.01);
  EXPECT_EQ(near_entry(relations[2], 1), nullptr);
  EXPECT_EQ(near_entry(relations[4], 4), nullptr);
  EXPECT_TRUE(relations[3].near.empty());
}

TEST(Near, TheClearanceCountsTheHeightsGapAndTouchingIsZero) {
  // A book on a table (touching: 0); a lamp hanging 0.3 m over the table's top (its footprint over
  // the table: the gap is the heights' alone), another 1.2 m over it.
  const PointCloud table = near_box(0.0, 0.0, 0.0, 1.2, 0.8, 0.75);
  const PointCloud book = near_box(0.2, 0.1, 0.75, 0.2, 0.15, 0.03);
  const PointCloud low = near_box(0.0, 0.0, 1.05, 0.3, 0.3, 0.2);
  const PointCloud high = near_box(-0.4, 0.0, 1.95, 0.3, 0.3, 0.2);
  const auto relations =
      near_relate({near_object(1, "dining table", table), near_object(2, "book", book),
                   near_object(3, "vase", low), near_object(4, "vase", high)});
  ASSERT_NE(near_entry(relations[1], 1), nullptr);
  EXPECT_NEAR(near_entry(relations[1], 1)->distance_m, 0.0, 0.01);
  ASSERT_NE(near_entry(relations[2], 1), nullptr);  // reach 0.42 m (the lamp's diagonal)
  EXPECT_NEAR(near_entry(relations[2], 1)->distance_m, 0.3, 0.01);
  EXPECT_EQ(near_entry(relations[3], 1), nullptr);  // 1.2 m up
}

TEST(Near, ObjectsNearASurfaceByTheirClearanceToItsOutline) {
  const PointCloud chair = near_box(2.0 + 0.1 + 0.225, 0.5, 0.0, 0.45, 0.45, 0.9);
  const PointCloud cup = near_box(3.5, 0.5, 0.0, 0.08, 0.08, 0.1);
  std::vector<Surface> surfaces(1);
  surfaces[0].id = 1;
  surfaces[0].height_m = 0.75;
  surfaces[0].area_m2 = 2.0;
  surfaces[0].outline = {{0, 0, 0.75}, {2, 0, 0.75}, {2, 1, 0.75}, {0, 1, 0.75}};
  const auto relations =
      relate_objects({near_object(1, "chair", chair), near_object(2, "cup", cup)}, surfaces,
                     Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_EQ(relations[0].near_surfaces.size(), 1u);  // 10 cm beside, its top above the table's
  EXPECT_NEAR(relations[0].near_surfaces[0].distance_m, 0.1, 0.01);
  EXPECT_TRUE(relations[1].near_surfaces.empty());  // 1.5 m beside, 0.65 m below
}

TEST(Near, GapOfOutlinesPointsSegmentsAndPolygons) {
  using detail::hull_gap;
  const std::vector<cv::Point2f> square = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const std::vector<cv::Point2f> inner = {{0.4f, 0.4f}, {0.6f, 0.4f}, {0.5f, 0.6f}};
  const std::vector<cv::Point2f> crossing = {{0.5f, -1}, {0.6f, -1}, {0.6f, 2}, {0.5f, 2}};
  EXPECT_EQ(hull_gap(square, inner), 0.0);
  EXPECT_EQ(hull_gap(inner, square), 0.0);
  EXPECT_EQ(hull_gap(square, crossing), 0.0);  // no corner inside the other, edges cross
  EXPECT_NEAR(hull_gap(square, {{2, 0.5f}}), 1.0, 1e-6);
  EXPECT_NEAR(hull_gap(square, {{1.5f, 2}, {3, 2}}), std::hypot(0.5, 1.0), 1e-6);
  EXPECT_NEAR(hull_gap({{3, 0}, {4, 0}}, {{0, 0}, {1, 0}}), 2.0, 1e-6);  // collinear segments
  EXPECT_TRUE(std::isinf(hull_gap(square, {})));
  EXPECT_NEAR(detail::hull_extent(square), std::sqrt(2.0), 1e-6);
}

TEST(Near, OptionsAreChecked) {
  RelationOptions o;
  o.near_max_m = 0.3;  // below near_min_m
  EXPECT_THROW(o.check(), InputError);
  o = RelationOptions{};
  o.near_scale = 0.0;
  EXPECT_THROW(o.check(), InputError);
}

}  // namespace
}  // namespace objmap::scene

// The ground truth of gravity, surfaces and `on` relations of the synthetic scenes (support.h), its
// place in objects_gt.json, and estimated_slam_frame.txt.
#include "objmap/sim/support.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "objmap/io/trajectory.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/synth.h"
#include "objmap/sim/writer.h"
#include "support/test_support.h"

namespace objmap::sim {
namespace {

std::vector<const SupportSurface*> with_label(const SceneSupport& s, const std::string& label) {
  std::vector<const SupportSurface*> out;
  for (const SupportSurface& f : s.surfaces)
    if (f.label == label) out.push_back(&f);
  return out;
}

TEST(SceneSupport, TabletopSurfacesAreTheGeometrysFaces) {
  const Scene scene = make_scene("tabletop", 1);
  const SceneSupport s = scene_support(scene);
  EXPECT_TRUE(s.up == Vec3::UnitZ());
  ASSERT_EQ(s.surfaces.size(), 4u);  // floor, table, two seats
  const SupportSurface& floor = s.surfaces[0];
  EXPECT_EQ(floor.id, 1);
  EXPECT_EQ(floor.label, "floor");
  EXPECT_NEAR(floor.height_m, 0.0, 1e-12);
  EXPECT_NEAR(floor.area_m2, 25.0, 1e-12);  // the 5 x 5 m room
  const SupportSurface& table = s.surfaces[1];
  EXPECT_EQ(table.label, "table");
  EXPECT_NEAR(table.height_m, 0.75, 1e-12);  // presets.cpp kTableHeight
  EXPECT_NEAR(table.area_m2, 1.4 * 0.8, 1e-12);
  EXPECT_TRUE(table.center.isApprox(Vec3(0, 0, 0.75), 1e-12));
  ASSERT_EQ(table.outline.size(), 4u);
  for (const Vec3& corner : table.outline) {
    EXPECT_NEAR(std::abs(corner.x()), 0.7, 1e-12);
    EXPECT_NEAR(std::abs(corner.y()), 0.4, 1e-12);
    EXPECT_NEAR(corner.z(), 0.75, 1e-12);
  }
  const auto seats = with_label(s, "seat");
  ASSERT_EQ(seats.size(), 2u);
  for (const SupportSurface* seat : seats) {
    EXPECT_NEAR(seat->height_m, 0.475, 1e-12);  // the cushion: 0.45 + 0.025
    EXPECT_NEAR(seat->area_m2, 0.44 * 0.44, 1e-12);
    ASSERT_NE(scene.find(seat->object_id), nullptr);
    EXPECT_EQ(scene.find(seat->object_id)->class_name, "chair");
  }
}

TEST(SceneSupport, EveryPlacedObjectRestsOnWhatItWasPlacedOn) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Scene scene = make_scene("tabletop", seed);
    const SceneSupport s = scene_support(scene);
    ASSERT_EQ(s.on.size(), scene.objects.size());
    int books_seen = 0;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      const SceneObject& o = scene.objects[i];
      ASSERT_TRUE(s.on[i].has_value()) << o.class_name << " " << o.id << " seed " << seed;
      const SupportRelation& on = *s.on[i];
      EXPECT_LE(std::abs(on.gap_m), kSupportToleranceM);
      if (o.class_name == "chair") {
        EXPECT_EQ(on.kind, SupportRelation::Kind::kSurface);
        EXPECT_EQ(on.label, "floor");
        EXPECT_NEAR(on.gap_m, 0.0, 1e-12);
      } else if (o.class_name == "book" && ++books_seen == 2) {
        // The second book lies on the first (presets: 3 cm higher, same place).
        EXPECT_EQ(on.kind, SupportRelation::Kind::kObject);
        EXPECT_EQ(on.id, o.id - 1);
        EXPECT_EQ(on.label, "book");
      } else {
        EXPECT_EQ(on.kind, SupportRelation::Kind::kSurface) << o.class_name;
        EXPECT_EQ(on.label, "table") << o.class_name;
        EXPECT_EQ(on.id, 2);
      }
    }
    EXPECT_EQ(books_seen, 3);
  }
}

TEST(SceneSupport, OfficeObjectsRestOnTheTableUnderThem) {
  const Scene scene = make_scene("office", 4);
  const SceneSupport s = scene_support(scene);
  const auto tables = with_label(s, "table");
  ASSERT_EQ(tables.size(), 2u);
  EXPECT_EQ(with_label(s, "seat").size(), 3u);
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    ASSERT_TRUE(s.on[i].has_value()) << o.class_name << " " << o.id;
    if (o.class_name == "chair" || s.on[i]->kind == SupportRelation::Kind::kObject) continue;
    const bool left = o.centroid.x() < 0, first_left = tables[0]->center.x() < 0;
    const SupportSurface* under = left == first_left ? tables[0] : tables[1];
    EXPECT_EQ(s.on[i]->id, under->id) << o.class_name << " " << o.id;
  }
}

TEST(SceneSupport, EdgeObjectsAllStandOnTheTable) {
  const Scene scene = make_scene("edge", 2);
  const SceneSupport s = scene_support(scene);
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    ASSERT_TRUE(s.on[i].has_value()) << scene.objects[i].class_name;
    EXPECT_EQ(s.on[i]->label, "table");
  }
}

TEST(SceneSupport, AnObjectLiftedOrMovedOffItsSupportRestsOnNothing) {
  Scene scene = make_scene("tabletop", 1);
  SceneObject* cup = nullptr;
  for (SceneObject& o : scene.objects)
    if (o.class_name == "cup") cup = &o;
  ASSERT_NE(cup, nullptr);
  const std::size_t index = static_cast<std::size_t>(cup - scene.objects.data());
  const Pose placed = cup->world_from_object;
  cup->world_from_object.translation().z() += 0.02;  // 2 cm above the table
  cup->finalize(16);
  EXPECT_FALSE(scene_support(scene).on[index].has_value());
  cup->world_from_object = placed;
  cup->world_from_object.translation().x() = 0.9;  // beyond the table's edge (0.7), in the air
  cup->finalize(16);
  EXPECT_FALSE(scene_support(scene).on[index].has_value());
  cup->world_from_object = placed;
  cup->finalize(16);
  EXPECT_TRUE(scene_support(scene).on[index].has_value());
}

TEST(SceneSupport, ExtentsAlongUpAreExactForTurnedPrimitives) {
  SceneObject o;
  Part cylinder;
  cylinder.shape = Shape::kCylinder;
  cylinder.half_extent = Vec3(0.1, 0.1, 0.3);
  o.parts.push_back(cylinder);
  o.world_from_object = Pose::Identity();
  o.world_from_object.linear() = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  o.world_from_object.translation() = Vec3(0, 0, 1);
  o.finalize(16);
  EXPECT_NEAR(lowest_along(o, Vec3::UnitZ()), 0.9, 1e-12);  // lying: its radius below the axis
  EXPECT_NEAR(highest_along(o, Vec3::UnitZ()), 1.1, 1e-12);
  EXPECT_NEAR(lowest_along(o, Vec3::UnitY()), -0.3, 1e-12);  // its half length along y
}

// ---- objects_gt.json and estimated_slam_frame.txt
// ---------------------------------------------------------------

TEST(SynthGroundTruth, ObjectsGtJsonCarriesUpSurfacesAndOn) {
  const Scene scene = make_scene("tabletop", 1);
  const auto doc = nlohmann::json::parse(objects_gt_json(scene));
  EXPECT_EQ(doc.at("up_in_world"), nlohmann::json::array({0.0, 0.0, 1.0}));
  ASSERT_EQ(doc.at("surfaces").size(), 4u);
  const auto& table = doc.at("surfaces")[1];
  EXPECT_EQ(table.at("label"), "table");
  EXPECT_NEAR(table.at("height_m").get<double>(), 0.75, 1e-12);
  EXPECT_EQ(table.at("outline").size(), 4u);
  EXPECT_FALSE(table.contains("object"));
  EXPECT_TRUE(doc.at("surfaces")[2].contains("object"));  // a seat names its chair
  for (const auto& o : doc.at("objects")) {
    ASSERT_TRUE(o.at("on").is_object()) << o.dump();
    EXPECT_TRUE(o.at("on").at("kind") == "surface" || o.at("on").at("kind") == "object");
  }
}

TEST(SynthGroundTruth, SlamFrameEstimateStartsAtIdentityAndMapsBack) {
  test::TempDir dir;
  SynthOptions options;
  options.frames = 5;
  options.resolution_scale = 0.1;
  options.threads = 1;
  write_synthetic_sequence(dir / "seq", options);
  const Trajectory est = io::read_trajectory(dir / "seq" / "estimated.txt");
  const Trajectory slam = io::read_trajectory(dir / "seq" / "estimated_slam_frame.txt");
  ASSERT_EQ(slam.size(), est.size());
  EXPECT_TRUE(slam.poses[0].world_from_cam.isApprox(Pose::Identity(), 0.0));
  const Pose& t0 = est.poses[0].world_from_cam;
  for (std::size_t i = 0; i < est.size(); ++i) {
    EXPECT_EQ(slam.poses[i].timestamp, est.poses[i].timestamp);
    const Pose back = t0 * slam.poses[i].world_from_cam;
    EXPECT_LT((back.translation() - est.poses[i].world_from_cam.translation()).norm(), 1e-9) << i;
    EXPECT_LT((back.linear() - est.poses[i].world_from_cam.linear()).norm(), 1e-9) << i;
  }
  // The camera moved: the test is not about identities only.
  EXPECT_GT((slam.poses.back().world_from_cam.translation()).norm(), 0.01);
}

}  // namespace
}  // namespace objmap::sim

// objmap eval scene on hand-made objects.json files with known errors: the up-vector angle, the
// surfaces' matching and height errors, `on` precision and recall, a run without the scene fields,
// and the alignment of a map fused in another frame (--gt-trajectory / --trajectory).
#include "objmap/eval/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>

#include "eval_test_util.h"
#include "objmap/io/scene_json.h"
#include "objmap/io/trajectory.h"
#include "support/schema_check.h"
#include "support/test_support.h"

namespace objmap::eval {
namespace {

using nlohmann::json;
using objmap::test::error_of;
using objmap::test::read_text;
using objmap::test::run_objmap;
using objmap::test::TempDir;
using objmap::test::write_text;
namespace fs = std::filesystem;

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

json relation(const std::string& kind, int id, const std::string& label) {
  return {{"kind", kind}, {"id", id}, {"label", label}};
}

struct Surface {
  int id;
  std::string label;
  double height_m;
  Vec3 center;
  double half_x, half_y;  // of the rectangle around the centre (axis-aligned)
};

struct Object {
  int id;
  std::string cls;
  Vec3 centroid;
  json on;  // null or relation(...)
};

// A scene on either side: the up vector, the surfaces and the objects (0.1 m cubes).
struct Scene {
  Vec3 up = Vec3::UnitZ();
  std::vector<Surface> surfaces;
  std::vector<Object> objects;
};

// The ground truth: floor 1, table 2 (0.75 m); a cup and a book on the table, a book on that
// book, a chair on the floor.
Scene truth() {
  Scene s;
  s.surfaces = {{1, "floor", 0.0, Vec3(0, 0, 0), 2.5, 2.5},
                {2, "table", 0.75, Vec3(0, 0, 0.75), 0.7, 0.4}};
  s.objects = {{1, "cup", Vec3(0.3, 0, 0.8), relation("surface", 2, "table")},
               {2, "book", Vec3(-0.3, 0.1, 0.765), relation("surface", 2, "table")},
               {3, "book", Vec3(-0.3, 0.1, 0.795), relation("object", 2, "book")},
               {4, "chair", Vec3(0, -1, 0.5), relation("surface", 1, "floor")}};
  return s;
}

// The map of a perfect fuse: the same scene with its own ids (surfaces 5, 6; objects 11-14), the
// floor 3 mm and the table 1 cm too high.
Scene perfect_map() {
  Scene s;
  s.surfaces = {{5, "floor", 0.003, Vec3(0.2, 0.1, 0.003), 2.0, 2.0},
                {6, "table", 0.76, Vec3(0.05, 0, 0.76), 0.6, 0.35}};
  s.objects = {{11, "cup", Vec3(0.31, 0, 0.8), relation("surface", 6, "table")},
               {12, "book", Vec3(-0.3, 0.11, 0.765), relation("surface", 6, "table")},
               {13, "book", Vec3(-0.29, 0.1, 0.795), relation("object", 12, "book")},
               {14, "chair", Vec3(0, -1.02, 0.5), relation("surface", 5, "floor")}};
  return s;
}

json outline(const Surface& s, const Pose& t) {
  json corners = json::array();
  const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  for (int k = 0; k < 4; ++k)
    corners.push_back(vec(t * (s.center + Vec3(sx[k] * s.half_x, sy[k] * s.half_y, 0))));
  return corners;
}

json obb(const Vec3& center, const Pose& t) {
  json rotation = json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rotation.push_back(t.linear()(r, c));
  return {{"center", vec(t * center)}, {"rotation", rotation}, {"half_extent", {0.05, 0.05, 0.05}}};
}

// objects.json as objmap fuse writes it (the fields io::read_objects_json and eval scene read),
// everything mapped by `t` (the run's world from the ground truth's).
json map_json(const Scene& s, const Pose& t = Pose::Identity()) {
  const Vec3 up = t.linear() * s.up;
  json surfaces = json::array();
  for (const Surface& f : s.surfaces)
    surfaces.push_back({{"id", f.id},
                        {"label", f.label},
                        {"height_m", f.height_m + up.dot(t.translation())},
                        {"center", vec(t * f.center)},
                        {"area_m2", 4 * f.half_x * f.half_y},
                        {"outline", outline(f, t)},
                        {"points", 1000}});
  json objects = json::array();
  for (const Object& o : s.objects) {
    const Vec3 c = t * o.centroid;
    json on = o.on;
    if (!on.is_null()) on["gap_m"] = 0.0;  // fuse writes the gap to the support
    objects.push_back(
        {{"id", o.id},
         {"class", o.cls},
         {"score", 0.9},
         {"centroid", vec(c)},
         {"position", vec(c)},
         {"aabb", {{"min", vec(c - Vec3::Constant(0.05))}, {"max", vec(c + Vec3::Constant(0.05))}}},
         {"obb", obb(o.centroid, t)},
         {"points", {{"outlier_filtered", 100}}},
         {"observation_count", 10},
         {"ply", "objects/x.ply"},
         {"relations",
          {{"on", on},
           {"near", json::array()},
           {"above", json::array()},
           {"under", json::array()}}}});
  }
  json gravity = json::array();  // takes up to +z when the truth's up is z
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) gravity.push_back(t.linear()(c, r));
  return {{"up_in_world", vec(up)},
          {"gravity_from_world", gravity},
          {"surfaces", surfaces},
          {"objects", objects}};
}

// objects_gt.json as objmap synth writes it.
json gt_json(const Scene& s) {
  json surfaces = json::array();
  for (const Surface& f : s.surfaces)
    surfaces.push_back({{"id", f.id},
                        {"label", f.label},
                        {"height_m", f.height_m},
                        {"center", vec(f.center)},
                        {"outline", outline(f, Pose::Identity())},
                        {"area_m2", 4 * f.half_x * f.half_y}});
  json objects = json::array();
  for (const Object& o : s.objects)
    objects.push_back({{"id", o.id},
                       {"class", o.cls},
                       {"centroid", vec(o.centroid)},
                       {"obb", obb(o.centroid, Pose::Identity())},
                       {"on", o.on}});
  return {{"up_in_world", vec(s.up)}, {"surfaces", surfaces}, {"objects", objects}};
}

// Files of one evaluation, in a temporary folder.
struct Files {
  TempDir dir;
  fs::path map, gt;
  Files(const json& map_doc, const json& gt_doc) : map(dir / "objects.json"), gt(dir / "gt.json") {
    write_text(map, map_doc.dump(2));
    write_text(gt, gt_doc.dump(2));
  }
};

SceneEvalResult evaluate(const json& map_doc, const json& gt_doc = gt_json(truth())) {
  Files f(map_doc, gt_doc);
  return evaluate_scene(io::read_objects_json(f.map), io::read_map_scene(f.map),
                        read_objects_gt(f.gt), io::read_gt_scene(f.gt), ObjectEvalOptions{});
}

TEST(EvalScene, PerfectMapScoresOneAndGivesTheHeightErrors) {
  const SceneEvalResult r = evaluate(map_json(perfect_map()));
  EXPECT_NEAR(r.up_angle_deg, 0.0, 1e-9);
  EXPECT_EQ(r.found, 2u);
  EXPECT_EQ(r.missed, 0u);
  ASSERT_EQ(r.surfaces.size(), 2u);
  EXPECT_EQ(r.surfaces[0].map_id, 5);
  EXPECT_NEAR(r.surfaces[0].height_error_m, 0.003, 1e-12);
  EXPECT_EQ(r.surfaces[1].map_id, 6);
  EXPECT_NEAR(r.surfaces[1].height_error_m, 0.01, 1e-12);
  EXPECT_NEAR(r.height_abs_error_m.max, 0.01, 1e-12);
  EXPECT_EQ(r.relations.size(), 4u);
  EXPECT_EQ(r.on.correct, 4u);
  EXPECT_DOUBLE_EQ(r.on.precision, 1.0);
  EXPECT_DOUBLE_EQ(r.on.recall, 1.0);
}

TEST(EvalScene, RotatedUpGivesItsAngle) {
  Scene map = perfect_map();
  const double angle = 3.0 * test::kPi / 180.0;
  map.up = Vec3(std::sin(angle), 0, std::cos(angle));
  EXPECT_NEAR(evaluate(map_json(map)).up_angle_deg, 3.0, 1e-9);
  map.up = Vec3(0, -2 * std::sin(angle), 2 * std::cos(angle));  // not unit: read as its direction
  EXPECT_NEAR(evaluate(map_json(map)).up_angle_deg, 3.0, 1e-9);
}

TEST(EvalScene, AWrongOnLowersPrecision) {
  Scene map = perfect_map();
  map.objects[2].on = relation("surface", 6, "table");  // the top book: on the table, not the book
  const SceneEvalResult r = evaluate(map_json(map));
  EXPECT_EQ(r.on.predicted, 4u);
  EXPECT_EQ(r.on.correct, 3u);
  EXPECT_DOUBLE_EQ(r.on.precision, 0.75);
  EXPECT_FALSE(r.relations[2].correct);
  EXPECT_EQ(r.relations[2].gt_id, 3);
  // On another object than the one matched to the true support: wrong as well.
  map.objects[2].on = relation("object", 11, "cup");
  EXPECT_DOUBLE_EQ(evaluate(map_json(map)).on.precision, 0.75);
}

TEST(EvalScene, AMissingOnLowersRecallNotPrecision) {
  Scene map = perfect_map();
  map.objects[0].on = nullptr;
  const SceneEvalResult r = evaluate(map_json(map));
  EXPECT_EQ(r.on.predicted, 3u);
  EXPECT_EQ(r.on.relevant, 4u);
  EXPECT_DOUBLE_EQ(r.on.precision, 1.0);
  EXPECT_DOUBLE_EQ(r.on.recall, 0.75);
}

TEST(EvalScene, SurfaceAtTheWrongHeightGivesThatError) {
  Scene map = perfect_map();
  map.surfaces[1].height_m = 0.80;
  map.surfaces[1].center.z() = 0.80;
  const SceneEvalResult r = evaluate(map_json(map));
  EXPECT_EQ(r.found, 2u);
  EXPECT_NEAR(r.surfaces[1].height_error_m, 0.05, 1e-12);
  EXPECT_NEAR(r.height_abs_error_m.max, 0.05, 1e-12);
}

TEST(EvalScene, SurfaceOfAnotherLabelIsMatchedByItsOutlineAndAMissingOneIsMissed) {
  Scene map = perfect_map();
  map.surfaces[1].label = "surface";
  map.objects[0].on = relation("surface", 6, "surface");
  SceneEvalResult r = evaluate(map_json(map));
  EXPECT_EQ(r.surfaces[1].map_id, 6);
  EXPECT_FALSE(r.surfaces[1].same_label);
  EXPECT_TRUE(r.relations[0].correct);  // the map surface matched to the table

  // A table outside the true outline is no match: the table is missed and the cup's relation to
  // it is wrong.
  map.surfaces[1].center = Vec3(1.5, 1.5, 0.76);
  r = evaluate(map_json(map));
  EXPECT_FALSE(r.surfaces[1].map_id.has_value());
  EXPECT_EQ(r.found, 1u);
  EXPECT_EQ(r.missed, 1u);
  EXPECT_FALSE(r.relations[0].correct);
}

TEST(EvalScene, ARelationToAnySurfaceLabelledTableCountsForATable) {
  Scene map = perfect_map();
  map.surfaces.push_back({7, "table", 0.75, Vec3(2, 2, 0.75), 0.2, 0.2});  // another table
  map.objects[0].on = relation("surface", 7, "table");
  EXPECT_TRUE(evaluate(map_json(map)).relations[0].correct);
}

TEST(EvalScene, UnmatchedObjectsStayOutOfTheScoresAndAreCounted) {
  Scene map = perfect_map();
  map.objects[0].centroid = Vec3(2, 2, 0.8);  // the cup, far beyond the gate
  const SceneEvalResult r = evaluate(map_json(map));
  EXPECT_EQ(r.relations.size(), 3u);
  EXPECT_EQ(r.on.unmatched_map_with_on, 1u);
  EXPECT_EQ(r.on.unmatched_gt_with_on, 1u);
  EXPECT_DOUBLE_EQ(r.on.precision, 1.0);
  EXPECT_DOUBLE_EQ(r.on.recall, 1.0);
}

TEST(EvalScene, ARunWithoutTheSceneFieldsIsNamed) {
  TempDir dir;
  const fs::path file = dir / "objects.json";
  // The message of read_map_scene for the perfect map with one field removed by `remove`.
  const auto message_without = [&](const std::function<void(json&)>& remove) {
    json doc = map_json(perfect_map());
    remove(doc);
    write_text(file, doc.dump());
    return error_of([&] { io::read_map_scene(file); });
  };
  const std::string where = file.string() + ": ";
  EXPECT_EQ(message_without([](json& d) {
              d.erase("up_in_world");
            }).rfind(where + "missing field 'up_in_world'", 0),
            0u);
  EXPECT_EQ(message_without([](json& d) {
              d["objects"][2].erase("relations");
            }).rfind(where + "objects[2]: missing field 'relations'", 0),
            0u);
  EXPECT_EQ(message_without([](json& d) {
              d["surfaces"][1].erase("height_m");
            }).rfind(where + "surfaces[1]: missing field 'height_m'", 0),
            0u);
}

// ---- the CLI
// ------------------------------------------------------------------------------------

// Runs `objmap eval scene` on the files with `extra` flags; returns its --json document.
json run_eval_scene(const Files& f, const std::vector<std::string>& extra) {
  std::vector<std::string> args{"eval", "scene",       "--run",  f.map.string(),
                                "--gt", f.gt.string(), "--json", (f.dir / "scene.json").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = run_objmap(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? json::parse(read_text(f.dir / "scene.json")) : json::object();
}

TEST(EvalSceneCli, WritesTheJsonItsSchemaAcceptsAndPrintsTheScores) {
  Files f(map_json(perfect_map()), gt_json(truth()));
  const fs::path out = f.dir / "scene.json";
  const auto r = run_objmap({"eval", "scene", "--run", f.dir.path().string(), "--gt", f.gt.string(),
                             "--json", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("precision 1.000 (4/4)"), std::string::npos) << r.out;
  const json doc = json::parse(read_text(out));
  EXPECT_TRUE(doc.at("alignment").is_null());
  EXPECT_EQ(doc.at("surfaces").at("found"), 2);
  EXPECT_DOUBLE_EQ(doc.at("on").at("recall").get<double>(), 1.0);
  const auto errors =
      objmap::test::validate_json(doc, objmap::test::load_schema("eval_scene.schema.json"));
  EXPECT_TRUE(errors.empty()) << errors.front();
}

TEST(EvalSceneCli, ARunWithoutTheFieldsIsExitTwoNamingFileAndField) {
  json doc = map_json(perfect_map());
  doc.erase("surfaces");
  Files f(doc, gt_json(truth()));
  const auto r = run_objmap({"eval", "scene", "--run", f.map.string(), "--gt", f.gt.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("objmap: error: " + f.map.string() + ": missing field 'surfaces'", 0), 0u)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

// The run's world differs from the ground truth's by `est_from_gt`; its trajectory is the ground
// truth's mapped by it. Aligning by the trajectories gives the result of the untransformed map.
TEST(EvalSceneCli, AMapInAnotherFrameAlignedByTheTrajectoriesGivesTheSameResult) {
  Scene map = perfect_map();
  map.up = Vec3(0.02, -0.01, 1).normalized();
  map.objects[0].on = nullptr;
  const Pose est_from_gt =
      test::make_pose(Eigen::AngleAxisd(0.7, Vec3(0.3, -0.5, 1).normalized()).toRotationMatrix(),
                      Vec3(1.5, -0.4, 2.0));
  Files plain(map_json(map), gt_json(truth()));
  Files moved(map_json(map, est_from_gt), gt_json(truth()));
  std::vector<double> stamps;
  std::vector<Pose> gt_poses, est_poses;
  for (int i = 0; i < 12; ++i) {
    const double a = 0.4 * i;
    stamps.push_back(100 + 0.1 * i);
    gt_poses.push_back(test::make_pose(
        test::rot_z(a), Vec3(2 * std::cos(a), 2 * std::sin(a), 1.2 + 0.1 * std::sin(3 * a))));
    est_poses.push_back(est_from_gt * gt_poses.back());
  }
  io::write_trajectory(moved.dir / "gt.txt", test::make_trajectory(stamps, gt_poses));
  io::write_trajectory(moved.dir / "est.txt", test::make_trajectory(stamps, est_poses));

  const json a = run_eval_scene(plain, {});
  const json b = run_eval_scene(moved, {"--gt-trajectory", (moved.dir / "gt.txt").string(),
                                        "--trajectory", (moved.dir / "est.txt").string()});
  EXPECT_NEAR(a.at("up_angle_deg").get<double>(), b.at("up_angle_deg").get<double>(), 1e-6);
  EXPECT_GT(a.at("up_angle_deg").get<double>(), 1.0);
  for (int k = 0; k < 2; ++k) {
    const json& sa = a.at("surfaces").at("matches")[k];
    const json& sb = b.at("surfaces").at("matches")[k];
    EXPECT_EQ(sa.at("map_id"), sb.at("map_id"));
    EXPECT_NEAR(sa.at("height_error_m").get<double>(), sb.at("height_error_m").get<double>(), 1e-6);
  }
  EXPECT_EQ(a.at("on").at("correct"), 3);
  EXPECT_EQ(a.at("on"), b.at("on"));
  EXPECT_NEAR(b.at("alignment").at("ate_m").at("rmse").get<double>(), 0.0, 1e-6);
  // Without the alignment nothing of the moved map matches.
  const json c = run_eval_scene(moved, {});
  EXPECT_EQ(c.at("on").at("pairs").size(), 0u);
}

// objects_gt.json of a noise-free synthetic sequence turned into the objects.json of a perfect map
// fused with estimated_slam_frame.txt: everything in the first camera's frame (T_0^-1).
json perfect_map_in_slam_frame(const json& gt, const Pose& t0) {
  const Pose slam_from_world = t0.inverse();
  const auto moved = [&](const json& p) {
    return vec(slam_from_world * Vec3(p[0].get<double>(), p[1].get<double>(), p[2].get<double>()));
  };
  const Vec3 up = t0.linear().transpose() * Vec3::UnitZ();  // R_0^T up (docs/formats.md)
  json gravity = json::array();                             // takes that up to +z: R_0
  for (int k = 0; k < 9; ++k) gravity.push_back(t0.linear()(k / 3, k % 3));
  json doc = {{"up_in_world", vec(up)},
              {"gravity_from_world", gravity},
              {"surfaces", json::array()},
              {"objects", json::array()}};
  for (const json& f : gt.at("surfaces")) {
    json s = {{"id", f.at("id")}, {"label", f.at("label")}, {"center", moved(f.at("center"))}};
    s["height_m"] =
        up.dot(slam_from_world * Vec3(f["center"][0].get<double>(), f["center"][1].get<double>(),
                                      f["center"][2].get<double>()));
    if (f.at("label") == "seat") s["label"] = "surface";
    doc["surfaces"].push_back(s);
  }
  for (const json& o : gt.at("objects")) {
    const json c = moved(o.at("centroid"));
    json on = o.at("on");
    if (!on.is_null()) on["gap_m"] = 0.0;  // fuse writes the gap to the support
    json rotation = json::array();
    Eigen::Matrix3d r;
    for (int k = 0; k < 9; ++k) r(k / 3, k % 3) = o["obb"]["rotation"][k].get<double>();
    r = slam_from_world.linear() * r;
    for (int k = 0; k < 9; ++k) rotation.push_back(r(k / 3, k % 3));
    doc["objects"].push_back({{"id", o.at("id")},
                              {"class", o.at("class")},
                              {"score", 1.0},
                              {"centroid", c},
                              {"aabb", {{"min", c}, {"max", c}}},
                              {"obb",
                               {{"center", moved(o["obb"]["center"])},
                                {"rotation", rotation},
                                {"half_extent", o["obb"]["half_extent"]}}},
                              {"points", {{"outlier_filtered", 100}}},
                              {"observation_count", 10},
                              {"ply", ""},
                              {"position", c},
                              {"relations",
                               {{"on", on},
                                {"near", json::array()},
                                {"above", json::array()},
                                {"under", json::array()}}}});
  }
  return doc;
}

// The whole chain on a synthetic sequence: synth's ground truth and estimated_slam_frame.txt, a
// map in the first camera's frame, eval scene aligning it back.
TEST(EvalSceneCli, PerfectMapInTheSlamFrameScoresPerfectlyOnceAligned) {
  objmap::test::RunResult failure;
  const fs::path seq =
      objmap::test::cached_output("evalscene_synth_noisefree",
                                  {"synth", "--out", "{OUT}", "--frames", "30", "--scale", "0.1",
                                   "--orbit-speed", "60", "--noise-free"},
                                  &failure);
  ASSERT_FALSE(seq.empty()) << failure.err;
  const json gt = json::parse(read_text(seq / "objects_gt.json"));
  const Trajectory slam = io::read_trajectory(seq / "estimated_slam_frame.txt");
  const Pose t0 = io::read_trajectory(seq / "groundtruth.txt").poses.front().world_from_cam;
  Files f(perfect_map_in_slam_frame(gt, t0), gt);
  const json aligned =
      run_eval_scene(f, {"--gt-trajectory", (seq / "groundtruth.txt").string(), "--trajectory",
                         (seq / "estimated_slam_frame.txt").string()});
  EXPECT_LT(aligned.at("up_angle_deg").get<double>(), 1e-5);
  EXPECT_EQ(aligned.at("surfaces").at("found"), 2);  // tabletop: the floor and the table
  EXPECT_LT(aligned.at("surfaces").at("height_abs_error_m").at("max").get<double>(), 1e-6);
  for (const json& m : aligned.at("surfaces").at("matches"))
    EXPECT_EQ(m.at("map_id"), m.at("gt_id"));  // the seats too, by their outlines
  EXPECT_EQ(aligned.at("on").at("relevant"), 12);
  EXPECT_EQ(aligned.at("on").at("correct"), 12);
  // Taken as it is, the map's up is the camera's: tens of degrees off, nothing matched.
  const json plain = run_eval_scene(f, {});
  EXPECT_GT(plain.at("up_angle_deg").get<double>(), 20.0);
  EXPECT_EQ(plain.at("on").at("correct"), 0);
  EXPECT_EQ(slam.poses.size(), 30u);
}

TEST(EvalSceneCli, OneTrajectoryWithoutTheOtherIsAUsageError) {
  Files f(map_json(perfect_map()), gt_json(truth()));
  const auto r = run_objmap({"eval", "scene", "--run", f.map.string(), "--gt", f.gt.string(),
                             "--trajectory", (f.dir / "est.txt").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--gt-trajectory"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace objmap::eval

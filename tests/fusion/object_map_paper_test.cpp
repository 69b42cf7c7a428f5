// The paper's rules of the object map (`objmap fuse --method paper`, docs/fusion.md "The paper's
// method"): each one on observations built so that only that rule decides.
#include <gtest/gtest.h>

#include <set>

#include "objmap/core/error.h"
#include "objmap/fusion/object_map.h"
#include "objmap/geometry/voxel_key.h"

namespace objmap::fusion {
namespace {

ObjectMapOptions paper_options() {
  ObjectMapOptions o;
  set_paper_rules(o);
  return o;
}

// The surface of an axis-aligned cube of 2·half + 1 voxels a side centred on `center` (a voxel
// centre), one point per 1 cm voxel.
PointCloud cube(const Vec3& center, int half) {
  PointCloud c;
  for (int i = -half; i <= half; ++i)
    for (int j = -half; j <= half; ++j)
      for (int k = -half; k <= half; ++k)
        if (std::abs(i) == half || std::abs(j) == half || std::abs(k) == half)
          c.push_back((center + 0.01 * Vec3(i, j, k)).cast<float>(), Rgb{90, 60, 30});
  return c;
}

Observation obs(double t, std::optional<int> id, PointCloud points) {
  Observation o;
  o.timestamp = t;
  o.track_id = id;
  o.class_name = "cup";
  o.score = 0.9;
  o.points_in_world = std::move(points);
  return o;
}

AddResult add_paper(ObjectMap& map, const Observation& o) { return map.add_frame({o}).front(); }

std::set<VoxelKey> keys_of(const PointCloud& c) {
  std::set<VoxelKey> keys;
  for (const Vec3f& p : c.points) keys.insert(geometry::voxel_key(p, 100.0f));
  return keys;
}

const Vec3 kCentre(0.305, 0.105, 0.905);

TEST(ObjectMapPaper, TheSameIdAloneJoinsAnObjectHalfAMetreAway) {
  ObjectMap map(paper_options());
  add_paper(map, obs(0, 4, cube(kCentre, 3)));
  const AddResult r = add_paper(map, obs(1, 4, cube(kCentre + Vec3(0.5, 0, 0), 3)));
  EXPECT_FALSE(r.created);
  EXPECT_EQ(r.object_id, 0);
  EXPECT_DOUBLE_EQ(r.p_id, 1.0);
  EXPECT_NEAR(r.distance_m, 0.5, 1e-6);
  EXPECT_DOUBLE_EQ(r.overlap, 0.0);
  EXPECT_DOUBLE_EQ(r.score_p, 0.5);  // w_id = 0.5 > K = 0.4
}

TEST(ObjectMapPaper, ACentroidWithinTheGateAloneJoinsAnotherIdBeyondItNot) {
  ObjectMap map(paper_options());
  add_paper(map, obs(0, 1, cube(kCentre, 3)));
  // 9 cm away, another id, the cubes (7 cm) do not touch: only D < 0.1 m.
  const AddResult near = add_paper(map, obs(1, 2, cube(kCentre + Vec3(0.09, 0, 0), 3)));
  EXPECT_FALSE(near.created);
  EXPECT_DOUBLE_EQ(near.p_id, 0.0);
  EXPECT_DOUBLE_EQ(near.overlap, 0.0);
  EXPECT_DOUBLE_EQ(near.score_p, 0.5);
  // The object's centroid is now 4.5 cm from the first cube's: a cube 7 cm on the other side is
  // 11.5 cm from it, beyond the gate, and starts an object (objmap's linear f(D) = 0.43).
  const AddResult far = add_paper(map, obs(2, 3, cube(kCentre - Vec3(0.07, 0, 0), 3)));
  EXPECT_TRUE(far.created);
  EXPECT_EQ(map.size(), 2u);
}

TEST(ObjectMapPaper, OverlapIsTheIouOfTheExactVoxelSets) {
  ObjectMap map(paper_options());
  const PointCloud whole = cube(kCentre, 10);  // 21 cm a side
  add_paper(map, obs(0, 1, whole));
  // The same cube 1 cm over under another id: D = 1 cm joins; M is |A∩B| / |A∪B| of the exact
  // voxels (no 1-voxel tolerance), not |A∩B| / |A|.
  const PointCloud moved = cube(kCentre + Vec3(0.01, 0, 0), 10);
  const AddResult r = add_paper(map, obs(1, 2, moved));
  ASSERT_FALSE(r.created);
  const std::set<VoxelKey> a = keys_of(moved), b = keys_of(whole);
  std::size_t common = 0;
  for (VoxelKey k : a) common += b.count(k);
  const double iou =
      static_cast<double>(common) / static_cast<double>(a.size() + b.size() - common);
  const double containment = static_cast<double>(common) / static_cast<double>(a.size());
  EXPECT_DOUBLE_EQ(r.overlap, iou);
  EXPECT_LT(iou, containment - 0.1) << iou << " vs " << containment;
  EXPECT_DOUBLE_EQ(r.score_p, 0.5 + 0.5 * iou);  // D < 0.1 m and M
}

TEST(ObjectMapPaper, AnOverlapAboveEightTenthsAloneJoins) {
  // A square of (2·half + 1)² voxels moved 1 cm within its plane, under another id; the gate made
  // smaller than 1 cm so that only M (IoU) can join: 40/42 = 0.95 joins, 6/8 = 0.75 does not.
  ObjectMapOptions options = paper_options();
  options.distance_gate_m = 0.005;
  const auto square = [](const Vec3& centre, int half) {
    PointCloud c;
    for (int i = -half; i <= half; ++i)
      for (int j = -half; j <= half; ++j)
        c.push_back((centre + 0.01 * Vec3(i, j, 0)).cast<float>(), Rgb{90, 60, 30});
    return c;
  };
  for (int half : {20, 3}) {
    ObjectMap map(options);
    add_paper(map, obs(0, 1, square(kCentre, half)));
    const AddResult r = add_paper(map, obs(1, 2, square(kCentre + Vec3(0.01, 0, 0), half)));
    if (half == 20) {
      EXPECT_FALSE(r.created);
      EXPECT_DOUBLE_EQ(r.p_id, 0.0);
      EXPECT_NEAR(r.distance_m, 0.01, 1e-6);
      EXPECT_DOUBLE_EQ(r.overlap, 40.0 / 42.0);
    } else {
      EXPECT_TRUE(r.created);
    }
  }
}

TEST(ObjectMapPaper, ConfirmedOnceTheObjectsIdWasSeenInThreeKeyframes) {
  ObjectMap map(paper_options());
  // Four observations of one cube (each joins by D = 0): ids 1, 2, 1 — three observations, but
  // id 1 in two keyframes only.
  add_paper(map, obs(0, 1, cube(kCentre, 3)));
  add_paper(map, obs(1, 2, cube(kCentre, 3)));
  add_paper(map, obs(2, 1, cube(kCentre, 3)));
  EXPECT_EQ(map.confirmed_count(), 0u);
  RecordOptions all;
  all.confirmed_only = false;
  ASSERT_EQ(map.records(all).size(), 1u);
  EXPECT_EQ(map.records(all)[0].observations, 3);
  EXPECT_EQ(count_id_keyframes(map.records(all)[0].provenance), 2);
  // objmap's count (views; without poses every observation is one) confirms it already.
  ObjectMapOptions views = paper_options();
  views.confirmation = Confirmation::kViews;
  ObjectMap by_views(views);
  for (int t : {0, 1, 2}) add_paper(by_views, obs(t, t == 1 ? 2 : 1, cube(kCentre, 3)));
  EXPECT_EQ(by_views.confirmed_count(), 1u);
  // The third keyframe of id 1 confirms it.
  add_paper(map, obs(3, 1, cube(kCentre, 3)));
  EXPECT_EQ(map.confirmed_count(), 1u);
}

TEST(ObjectMapPaper, EachInstanceInTurnTakesItsBestObject) {
  // Keyframe 1 lists a cube 1 cm off first, then the cube itself, both with the object's id. In
  // turn, the first takes the object and the second (no longer the same object's only view) joins
  // it too: no one-per-keyframe rule.
  ObjectMap map(paper_options());
  add_paper(map, obs(0, 1, cube(kCentre, 3)));
  const std::vector<AddResult> r =
      map.add_frame({obs(1, 1, cube(kCentre + Vec3(0.01, 0, 0), 3)), obs(1, 1, cube(kCentre, 3))});
  EXPECT_EQ(r[0].object_id, 0);
  EXPECT_EQ(r[1].object_id, 0);
  EXPECT_EQ(map.size(), 1u);
}

TEST(ObjectMapPaper, NoFinalMergePass) {
  // objmap's defaults but the pass: track 1 sees the -x -y -z faces of a cube, then track 2 the
  // +x +y +z faces and then the whole cube (the ID-switch case the pass repairs, see
  // object_map_test.cpp): the two objects stay two.
  ObjectMapOptions options;
  options.final_merge = false;
  options.merge_class_confusions = false;
  ObjectMap map(options);
  const PointCloud whole = cube(kCentre, 10);
  PointCloud low, high;
  for (const Vec3f& p : whole.points) {
    const Vec3f d = (p - kCentre.cast<float>()) / 0.01f;
    if (d.minCoeff() < -9.5f) low.push_back(p, Rgb{1, 2, 3});
    if (d.maxCoeff() > 9.5f) high.push_back(p, Rgb{1, 2, 3});
  }
  for (int f = 0; f < 3; ++f) add_paper(map, obs(f, 1, low));
  for (int f = 3; f < 6; ++f) add_paper(map, obs(f, 2, high));
  add_paper(map, obs(6, 2, whole));
  ASSERT_EQ(map.size(), 2u);
  EXPECT_TRUE(map.merge_pass().empty());
  EXPECT_EQ(map.size(), 2u);
}

TEST(ObjectMapPaper, OutlierFilterOnThePointsThenTheVoxelPointNearestTheCentre) {
  ObjectMap map(paper_options());
  // Per voxel of a 7 cm cube: a point 1 mm from the voxel's centre and one 4 mm from it; and a
  // stray point 1 m away.
  PointCloud points;
  for (const Vec3f& p : cube(kCentre, 3).points) {
    points.push_back(p + Vec3f(0.001f, 0, 0), Rgb{1, 1, 1});
    points.push_back(p + Vec3f(0.004f, 0, 0), Rgb{2, 2, 2});
  }
  points.push_back((kCentre + Vec3(1.0, 0, 0)).cast<float>(), Rgb{3, 3, 3});
  for (int t = 0; t < 3; ++t) add_paper(map, obs(t, 1, points));
  RecordOptions paper;
  paper.min_voxel_support = 0.0;
  paper.outlier_on_points = true;
  paper.voxel_nearest_centre = true;
  const std::vector<ObjectRecord> records = map.records(paper);
  ASSERT_EQ(records.size(), 1u);
  const ObjectRecord& r = records[0];
  const std::size_t voxels = cube(kCentre, 3).size();
  EXPECT_EQ(r.points_raw, 3 * points.size());
  EXPECT_EQ(r.points_voxel, voxels);  // the stray point went before the voxel filter
  ASSERT_EQ(r.cloud.size(), voxels);
  for (std::size_t i = 0; i < r.cloud.size(); ++i) EXPECT_EQ(r.cloud.colors[i], (Rgb{1, 1, 1}));
  // Eq 16: the centroid is the mean of the kept points (the cube's centre + 1 mm).
  EXPECT_NEAR((r.centroid - (kCentre + Vec3(0.001, 0, 0))).norm(), 0.0, 1e-6);
  // Without keep_points the paper's filters cannot run.
  ObjectMapOptions no_points = paper_options();
  no_points.keep_points = false;
  ObjectMap without(no_points);
  add_paper(without, obs(0, 1, points));
  RecordOptions all = paper;
  all.confirmed_only = false;
  EXPECT_THROW(without.records(all), InputError);
}

TEST(ObjectMapPaper, VoxelNearestCentreKeepsThePointNearestEachVoxelsCentre) {
  PointCloud c;
  c.push_back(Vec3f(0.0080f, 0.005f, 0.005f), Rgb{1, 0, 0});
  c.push_back(Vec3f(0.0051f, 0.005f, 0.005f), Rgb{2, 0, 0});  // nearer the centre (5 mm)
  c.push_back(Vec3f(0.0020f, 0.005f, 0.005f), Rgb{4, 0, 0});
  c.push_back(Vec3f(0.0150f, 0.005f, 0.005f), Rgb{3, 0, 0});  // the next voxel
  const PointCloud kept = voxel_nearest_centre(c, 0.01);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept.colors[0], (Rgb{2, 0, 0}));
  EXPECT_EQ(kept.points[0], c.points[1]);  // the point itself, not a mean
  EXPECT_EQ(kept.colors[1], (Rgb{3, 0, 0}));
  const PointCloud one = voxel_nearest_centre(
      c, 0.01, [](VoxelKey key) { return geometry::unpack_voxel(key).x() == 1; });
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one.colors[0], (Rgb{3, 0, 0}));
}

TEST(ObjectMapPaper, MethodNamesParseAndBadOnesAreNamed) {
  EXPECT_EQ(parse_distance_score("gate", "x"), DistanceScore::kGate);
  EXPECT_STREQ(to_string(DistanceScore::kLinear), "linear");
  EXPECT_EQ(parse_confirmation("id_keyframes", "x"), Confirmation::kIdKeyframes);
  EXPECT_STREQ(to_string(Confirmation::kViews), "views");
  try {
    parse_confirmation("frames", "objects.confirmation");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "objects.confirmation: unknown confirmation 'frames'; expected views or "
                 "id_keyframes");
  }
}

}  // namespace
}  // namespace objmap::fusion

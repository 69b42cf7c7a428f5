#include "objmap/fusion/object_map.h"

#include <gtest/gtest.h>

#include <random>

#include "objmap/core/error.h"
#include "objmap/fusion/palette.h"

namespace objmap::fusion {
namespace {

// Surface points of an axis-aligned box at 1 cm voxel centres: `center` must be a voxel centre
// (x.xx5) and `half_cells` the half size in voxels, so the box is symmetric about `center`.
// `faces`: bit 0 = -x, 1 = +x, 2 = -y, 3 = +y, 4 = -z, 5 = +z.
PointCloud box(const Vec3& center, int half_cells, int faces = 63, Rgb colour = {200, 100, 50}) {
  PointCloud c;
  const int h = half_cells;
  for (int i = -h; i <= h; ++i)
    for (int j = -h; j <= h; ++j)
      for (int k = -h; k <= h; ++k) {
        const bool on = ((faces & 1) && i == -h) || ((faces & 2) && i == h) ||
                        ((faces & 4) && j == -h) || ((faces & 8) && j == h) ||
                        ((faces & 16) && k == -h) || ((faces & 32) && k == h);
        if (on) c.push_back((center + 0.01 * Vec3(i, j, k)).cast<float>(), colour);
      }
  return c;
}

Observation obs(double t, std::optional<int> id, const std::string& cls, double score,
                PointCloud points) {
  Observation o;
  o.timestamp = t;
  o.track_id = id;
  o.class_name = cls;
  o.score = score;
  o.points_in_world = std::move(points);
  return o;
}

RecordOptions no_outlier_filter() {
  RecordOptions r;
  r.outlier_filter = false;
  return r;
}

TEST(ObjectMap, TwoSeparateBoxesGiveTwoConfirmedObjectsWithExactCentroids) {
  ObjectMap map;
  const Vec3 a(0.505, 0.205, 1.005), b(1.505, -0.195, 1.205);
  for (int f = 0; f < 5; ++f) {
    map.add(obs(f, 1, "cup", 0.9, box(a, 5)));
    map.add(obs(f, 2, "book", 0.8, box(b, 8)));
  }
  map.merge_pass();
  for (const RecordOptions& options : {RecordOptions{}, no_outlier_filter()}) {
    const auto records = map.records(options);
    ASSERT_EQ(records.size(), 2u);
    EXPECT_EQ(records[0].class_name, "cup");
    EXPECT_EQ(records[1].class_name, "book");
    EXPECT_LT((records[0].centroid - a).norm(), 1e-5);
    EXPECT_LT((records[1].centroid - b).norm(), 1e-5);
    EXPECT_EQ(records[0].observations, 5);
    EXPECT_TRUE(records[0].confirmed);
    EXPECT_EQ(records[0].points_raw, 5 * box(a, 5).size());
    EXPECT_EQ(records[0].points_voxel, box(a, 5).size());
    EXPECT_NEAR(records[0].obb.half_extent.maxCoeff(), 0.05, 1e-5);
    EXPECT_NEAR(records[1].aabb.max.x(), b.x() + 0.08, 1e-5);
  }
  // Provenance: the first observation created the object, the others matched on all three criteria.
  const auto r = map.records()[0];
  ASSERT_EQ(r.provenance.size(), 5u);
  EXPECT_TRUE(r.provenance[0].created);
  EXPECT_FALSE(r.provenance[1].created);
  EXPECT_EQ(r.provenance[1].p_id, 1.0);
  EXPECT_NEAR(r.provenance[1].distance_m, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(r.provenance[1].overlap, 1.0);
  EXPECT_DOUBLE_EQ(r.provenance[1].score_p, 1.0);
}

TEST(ObjectMap, IdSwitchWithHighOverlapJoinsTheSameObject) {
  ObjectMap map;
  const Vec3 c(0.305, 0.105, 0.905);
  for (int f = 0; f < 3; ++f) map.add(obs(f, 4, "chair", 0.7, box(c, 10)));
  const AddResult switched = map.add(obs(3, 11, "chair", 0.7, box(c, 10)));  // new id, same object
  EXPECT_FALSE(switched.created);
  EXPECT_EQ(switched.p_id, 0.0);
  EXPECT_GT(switched.overlap, 0.8);
  map.add(obs(4, 11, "chair", 0.7, box(c, 10)));
  map.merge_pass();
  const auto records = map.records();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].track_ids, (std::vector<int>{4, 11}));
  EXPECT_EQ(records[0].observations, 5);
}

TEST(ObjectMap, FinalMergePassRepairsAnIdSwitchTheOnlineStepMissed) {
  ObjectMap map;
  const Vec3 c(0.305, 0.105, 0.905);
  // Two ids see opposite halves of one box: little overlap, so two objects at first.
  for (int f = 0; f < 3; ++f) {
    map.add(obs(f, 1, "tv", 0.8, box(c, 10, 1 | 4 | 16)));  // -x, -y, -z faces
    map.add(obs(f, 2, "tv", 0.6, box(c, 10, 2 | 8 | 32)));  // +x, +y, +z faces
  }
  EXPECT_EQ(map.size(), 2u);
  // Later both ids see the whole box and grow their objects into the same surface.
  map.add(obs(3, 1, "tv", 0.8, box(c, 10)));
  map.add(obs(3, 2, "tv", 0.6, box(c, 10)));
  EXPECT_EQ(map.size(), 2u);
  const auto merges = map.merge_pass();
  ASSERT_EQ(merges.size(), 1u);
  EXPECT_EQ(merges[0].into, 0);
  EXPECT_EQ(merges[0].absorbed, 1);
  EXPECT_GT(merges[0].overlap, 0.8);
  EXPECT_EQ(map.resolve(1), 0);
  EXPECT_TRUE(map.merge_pass().empty());  // nothing left to merge
  const auto records = map.records();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].observations, 8);
  EXPECT_EQ(records[0].provenance.size(), 8u);
  EXPECT_EQ(records[0].merges.size(), 1u);
  EXPECT_LT((records[0].centroid - c).norm(), 1e-5);
}

TEST(ObjectMap, TwoObjectsFiveCentimetresApartWithDifferentIdsStayTwo) {
  ObjectMap map;
  const Vec3 a(0.005, 0.005, 1.005),
      b(0.055, 0.005, 1.005);  // 3 cm boxes, 2 cm gap, no shared voxel
  for (int f = 0; f < 4; ++f) {
    map.add(obs(f, 1, "cup", 0.9, box(a, 1)));
    const AddResult r = map.add(obs(f, 2, "cup", 0.9, box(b, 1)));
    if (f == 0) {
      EXPECT_TRUE(r.created);
    }
  }
  map.merge_pass();
  const auto records = map.records();
  ASSERT_EQ(records.size(), 2u);
  EXPECT_LT((records[0].centroid - a).norm(), 1e-5);
  EXPECT_LT((records[1].centroid - b).norm(), 1e-5);
}

TEST(ObjectMap, ClassIsTheScoreWeightedVote) {
  ObjectMap map;
  const Vec3 c(0.105, 0.105, 0.705);
  for (int f = 0; f < 3; ++f) map.add(obs(f, 3, "teddy bear", 0.9, box(c, 6)));
  for (int f = 3; f < 5; ++f) map.add(obs(f, 3, "person", 0.5, box(c, 6)));
  const auto records = map.records();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].class_name, "teddy bear");
  EXPECT_NEAR(records[0].class_histogram.at("teddy bear").score_sum, 2.7, 1e-12);
  EXPECT_EQ(records[0].class_histogram.at("person").count, 2);
  EXPECT_NEAR(records[0].mean_score, (3 * 0.9 + 2 * 0.5) / 5, 1e-12);
  EXPECT_EQ(records[0].first_seen, 0.0);
  EXPECT_EQ(records[0].last_seen, 4.0);
}

TEST(ObjectMap, ObjectSeenFewerThanThreeTimesIsNotConfirmed) {
  ObjectMap map;
  map.add(obs(0, 1, "cup", 0.9, box(Vec3(0.005, 0.005, 0.505), 3)));
  map.add(obs(1, 1, "cup", 0.9, box(Vec3(0.005, 0.005, 0.505), 3)));
  for (int f = 0; f < 3; ++f) map.add(obs(f, 2, "book", 0.9, box(Vec3(1.005, 0.005, 0.505), 3)));
  EXPECT_EQ(map.size(), 2u);
  EXPECT_EQ(map.confirmed_count(), 1u);
  const auto confirmed = map.records();
  ASSERT_EQ(confirmed.size(), 1u);
  EXPECT_EQ(confirmed[0].class_name, "book");
  RecordOptions all;
  all.confirmed_only = false;
  const auto both = map.records(all);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_FALSE(both[0].confirmed);
  // Too small observations are ignored.
  EXPECT_EQ(map.add(obs(5, 3, "cup", 0.9, box(Vec3(3.005, 0, 0), 0))).object_id, -1);
}

// A noisy sequence: several objects, jittered points, random ids with switches.
std::vector<Observation> noisy_sequence() {
  std::mt19937 rng(42);
  std::normal_distribution<float> noise(0.f, 0.004f);
  std::vector<Observation> seq;
  const Vec3 centres[3] = {{0.305, 0.105, 0.905}, {0.805, 0.105, 1.105}, {0.305, 0.605, 1.505}};
  for (int f = 0; f < 12; ++f)
    for (int k = 0; k < 3; ++k) {
      PointCloud c = box(centres[k], 4 + 2 * k);
      for (Vec3f& p : c.points) p += Vec3f(noise(rng), noise(rng), noise(rng));
      const int id = (f < 6 ? 1 : 10) + k;  // every track switches id at frame 6
      seq.push_back(obs(f, id, k == 1 ? "cup" : "book", 0.5 + 0.1 * k, std::move(c)));
    }
  return seq;
}

TEST(ObjectMap, DeterministicRecords) {
  auto run = [] {
    ObjectMap map;
    for (const Observation& o : noisy_sequence()) map.add(o);
    map.merge_pass();
    return map.records();
  };
  const auto a = run(), b = run();
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].centroid, b[i].centroid);  // bit-identical
    EXPECT_EQ(a[i].cloud.points, b[i].cloud.points);
    EXPECT_EQ(a[i].cloud.colors, b[i].cloud.colors);
    EXPECT_EQ(a[i].points_filtered, b[i].points_filtered);
    EXPECT_EQ(a[i].observations, 12);
  }
}

TEST(ObjectMap, SemanticMapsPaintObjectVoxelsByClass) {
  ObjectMap map;
  VoxelMap dense;
  const Vec3 c(0.305, 0.105, 0.905);
  PointCloud wall;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j)
      wall.push_back(Vec3f(0.01f * i + 0.005f, 0.01f * j + 0.005f, 2.005f), Rgb{50, 50, 50});
  for (int f = 0; f < 3; ++f) {
    map.add(obs(f, 1, "cup", 0.9, box(c, 5)));
    dense.insert(box(c, 5));
    dense.insert(wall);
  }
  RecordOptions options;
  options.outlier_filter = false;
  const SemanticMaps maps = make_semantic_maps(dense, map.records(options));
  EXPECT_EQ(maps.semantic.size(), dense.size());
  EXPECT_EQ(maps.voxels_painted, box(c, 5).size());
  EXPECT_EQ(maps.objects_only.size(), box(c, 5).size());
  std::size_t cup = 0, grey = 0;
  for (const Rgb& rgb : maps.semantic.colors) {
    cup += rgb == class_color("cup");
    grey += rgb == Rgb{50, 50, 50};
  }
  EXPECT_EQ(cup, box(c, 5).size());
  EXPECT_EQ(grey, wall.size());
}

TEST(ObjectMap, BadOptionsAreNamed) {
  ObjectMapOptions o;
  o.distance_gate_m = 0.0;
  try {
    ObjectMap map(o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "ObjectMapOptions.distance_gate_m: must be > 0, got 0.000000");
  }
}

}  // namespace
}  // namespace objmap::fusion

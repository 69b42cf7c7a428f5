#include "objmap/fusion/object_map.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "fusion_test_util.h"
#include "objmap/core/error.h"
#include "objmap/fusion/palette.h"
#include "objmap/fusion/record_cache.h"

namespace objmap::fusion {
namespace {

// One observation as a keyframe of its own.
AddResult add_one(ObjectMap& map, const Observation& observation) {
  return map.add_frame({observation}).front();
}

using test::box;

Observation obs(double t, std::optional<int> id, const std::string& cls, double score,
                PointCloud points) {
  return test::instance(t, id, cls, std::move(points), score);
}

RecordOptions no_outlier_filter() {
  RecordOptions r;
  r.outlier_filter = false;
  return r;
}

// add_frame() fuses the best (observation, object) pair of a keyframe first; add() takes the
// observations in their order. Object 0: a box seen with track 1. Next keyframe: first the box 1 cm
// over, also with track 1 (P = 0.3 + 0.2 · 0.95 + 0.5 = 0.99), then the box itself (P = 1).
TEST(ObjectMap, AddFrameFusesTheBestMatchOfAKeyframeFirst) {
  const Vec3 a(0.505, 0.205, 1.005);
  const auto first_frame = [&](ObjectMap& map) { add_one(map, obs(0, 1, "book", 0.9, box(a, 5))); };
  const std::vector<Observation> frame{obs(1, 1, "book", 0.9, box(a + Vec3(0.01, 0, 0), 5)),
                                       obs(1, 1, "book", 0.9, box(a, 5))};

  ObjectMap in_order;
  first_frame(in_order);
  const AddResult r0 = add_one(in_order, frame[0]);
  const AddResult r1 = add_one(in_order, frame[1]);
  EXPECT_EQ(r0.object_id, 0);  // the offset box takes the object: listed first
  EXPECT_NEAR(r0.score_p, 0.99, 1e-9);
  EXPECT_TRUE(r1.created);  // and the box itself starts a second one

  ObjectMap best_first;
  first_frame(best_first);
  const std::vector<AddResult> r = best_first.add_frame(frame);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[1].object_id, 0);          // the box itself (P = 1) goes first
  EXPECT_NEAR(r[1].score_p, 1.0, 1e-6);  // centroids to float precision
  EXPECT_FALSE(r[1].created);
  EXPECT_TRUE(r[0].created);  // one observation per keyframe: the other starts an object
  EXPECT_EQ(r[0].object_id, 1);
  EXPECT_EQ(best_first.size(), 2u);

  // A keyframe of one observation: add_frame() is add().
  ObjectMap single_a, single_b;
  first_frame(single_a);
  first_frame(single_b);
  const AddResult x = add_one(single_a, frame[0]);
  const std::vector<AddResult> y = single_b.add_frame({frame[0]});
  ASSERT_EQ(y.size(), 1u);
  EXPECT_EQ(x.object_id, y[0].object_id);
  EXPECT_EQ(x.score_p, y[0].score_p);
  // Too few points: ignored, as by add().
  ObjectMap small;
  EXPECT_EQ(small.add_frame({obs(0, 1, "book", 0.9, PointCloud{})})[0].object_id, -1);
}

TEST(ObjectMap, TwoSeparateBoxesGiveTwoConfirmedObjectsWithExactCentroids) {
  ObjectMap map;
  const Vec3 a(0.505, 0.205, 1.005), b(1.505, -0.195, 1.205);
  for (int f = 0; f < 5; ++f) {
    add_one(map, obs(f, 1, "cup", 0.9, box(a, 5)));
    add_one(map, obs(f, 2, "book", 0.8, box(b, 8)));
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
  EXPECT_NEAR(r.provenance[1].distance_m, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(r.provenance[1].overlap, 1.0);
  EXPECT_NEAR(r.provenance[1].score_p, 1.0, 1e-6);
}

TEST(ObjectMap, IdSwitchWithHighOverlapJoinsTheSameObject) {
  ObjectMap map;
  const Vec3 c(0.305, 0.105, 0.905);
  for (int f = 0; f < 3; ++f) add_one(map, obs(f, 4, "chair", 0.7, box(c, 10)));
  const AddResult switched =
      add_one(map, obs(3, 11, "chair", 0.7, box(c, 10)));  // new id, same object
  EXPECT_FALSE(switched.created);
  EXPECT_EQ(switched.p_id, 0.0);
  EXPECT_GT(switched.overlap, 0.8);
  add_one(map, obs(4, 11, "chair", 0.7, box(c, 10)));
  map.merge_pass();
  const auto records = map.records();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].track_ids, (std::vector<int>{4, 11}));
  EXPECT_EQ(records[0].observations, 5);
}

TEST(ObjectMap, FinalMergePassRepairsAnIdSwitchTheOnlineStepMissed) {
  ObjectMap map;
  const Vec3 c(0.305, 0.105, 0.905);
  // Track 1 sees one half of a box, then the track switches to id 2, which sees the other half:
  // little overlap, so two objects at first.
  for (int f = 0; f < 3; ++f)
    add_one(map, obs(f, 1, "tv", 0.8, box(c, 10, 1 | 4 | 16)));  // -x -y -z
  for (int f = 3; f < 6; ++f)
    add_one(map, obs(f, 2, "tv", 0.6, box(c, 10, 2 | 8 | 32)));  // +x +y +z
  EXPECT_EQ(map.size(), 2u);
  // Later id 2 sees the whole box: its object now contains the first one.
  add_one(map, obs(6, 2, "tv", 0.6, box(c, 10)));
  EXPECT_EQ(map.size(), 2u);
  const auto merges = map.merge_pass();
  ASSERT_EQ(merges.size(), 1u);
  EXPECT_EQ(merges[0].into, 0);
  EXPECT_EQ(merges[0].absorbed, 1);
  EXPECT_DOUBLE_EQ(merges[0].overlap, 1.0);  // containment of the half in the whole
  EXPECT_EQ(map.resolve(1), 0);
  EXPECT_TRUE(map.merge_pass().empty());  // nothing left to merge
  const auto records = map.records();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].observations, 7);
  EXPECT_EQ(records[0].provenance.size(), 7u);
  EXPECT_EQ(records[0].merges.size(), 1u);
  EXPECT_LT((records[0].centroid - c).norm(), 1e-5);
  EXPECT_LT((records[0].position - c).norm(), 1e-5);
}

TEST(ObjectMap, TwoObjectsFiveCentimetresApartWithDifferentIdsStayTwo) {
  ObjectMap map;
  const Vec3 a(0.005, 0.005, 1.005),
      b(0.055, 0.005, 1.005);  // 3 cm boxes, 2 cm gap, no shared voxel
  for (int f = 0; f < 4; ++f) {
    add_one(map, obs(f, 1, "cup", 0.9, box(a, 1)));
    const AddResult r = add_one(map, obs(f, 2, "cup", 0.9, box(b, 1)));
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
  for (int f = 0; f < 3; ++f) add_one(map, obs(f, 3, "teddy bear", 0.9, box(c, 6)));
  for (int f = 3; f < 5; ++f) add_one(map, obs(f, 3, "person", 0.5, box(c, 6)));
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
  add_one(map, obs(0, 1, "cup", 0.9, box(Vec3(0.005, 0.005, 0.505), 3)));
  add_one(map, obs(1, 1, "cup", 0.9, box(Vec3(0.005, 0.005, 0.505), 3)));
  for (int f = 0; f < 3; ++f)
    add_one(map, obs(f, 2, "book", 0.9, box(Vec3(1.005, 0.005, 0.505), 3)));
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
  EXPECT_EQ(add_one(map, obs(5, 3, "cup", 0.9, box(Vec3(3.005, 0, 0), 0))).object_id, -1);
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
    for (const Observation& o : noisy_sequence()) add_one(map, o);
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

// A record cache (objmap follow's publishes) gives the records a map without one gives, as the
// objects grow and merge; an object unchanged since the last records() is taken from it.
TEST(ObjectMap, RecordsFromTheCacheAreThoseMadeAfresh) {
  const std::vector<Observation> seq = noisy_sequence();
  auto cache = std::make_shared<RecordCache>();
  ObjectMap live;
  live.set_record_cache(cache);
  const auto expect_same = [](const std::vector<ObjectRecord>& a,
                              const std::vector<ObjectRecord>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].id, b[i].id);
      EXPECT_EQ(a[i].cloud.points, b[i].cloud.points);
      EXPECT_EQ(a[i].cloud.colors, b[i].cloud.colors);
      EXPECT_EQ(a[i].position, b[i].position);
      EXPECT_EQ(a[i].centroid, b[i].centroid);
      EXPECT_EQ(a[i].obb.center, b[i].obb.center);
      EXPECT_EQ(a[i].points_voxel, b[i].points_voxel);
      EXPECT_EQ(a[i].points_filtered, b[i].points_filtered);
      EXPECT_EQ(a[i].outlier_threshold, b[i].outlier_threshold);
      EXPECT_EQ(a[i].observations, b[i].observations);
    }
  };
  for (std::size_t n = 0; n < seq.size(); ++n) {
    add_one(live, seq[n]);
    if (n % 6 != 5) continue;
    ObjectMap published = live;  // shares the cache
    ObjectMap plain = live;
    plain.set_record_cache(nullptr);
    published.merge_pass();
    plain.merge_pass();
    expect_same(published.records(), plain.records());
  }
  const std::size_t misses = cache->misses();
  ObjectMap again = live;
  again.merge_pass();
  const auto records = again.records();  // nothing changed since the last: every record cached
  EXPECT_EQ(cache->misses(), misses);
  EXPECT_GE(cache->hits(), records.size());
  Observation later = seq.front();  // the first object seen once more; the others unchanged
  later.timestamp = 100.0;
  add_one(live, later);
  ObjectMap changed = live;
  changed.merge_pass();
  changed.records();
  EXPECT_EQ(cache->misses(), misses + 1);
}

// A pair cache (objmap follow's publishes) gives the merges of a map without one: the same links
// with the same scores, as the objects grow (every track switches id half-way: the pass joins).
TEST(ObjectMap, MergesWithThePairCacheAreThoseMadeAfresh) {
  // Three boxes seen with noise, and a tv seen in halves by two tracks, then whole by the second:
  // the final merge joins its two objects (FinalMergePassRepairsAnIdSwitchTheOnlineStepMissed).
  std::vector<Observation> seq = noisy_sequence();
  const Vec3 c(2.005, 0.105, 0.905);
  for (int f = 0; f < 7; ++f) {
    const int half = f < 3 ? (1 | 4 | 16) : f < 6 ? (2 | 8 | 32) : 0;
    seq.push_back(obs(100 + f, f < 3 ? 1 : 2, "tv", 0.7, half ? box(c, 10, half) : box(c, 10)));
  }
  auto cache = std::make_shared<PairCache>();
  ObjectMap live;
  live.set_pair_cache(cache);
  std::size_t merges = 0;
  for (std::size_t n = 0; n < seq.size(); ++n) {
    add_one(live, seq[n]);
    ObjectMap published = live;  // shares the cache
    ObjectMap plain = live;
    plain.set_pair_cache(nullptr);
    const std::vector<MergeLink> a = published.merge_pass(), b = plain.merge_pass();
    ASSERT_EQ(a.size(), b.size()) << n;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].into, b[i].into);
      EXPECT_EQ(a[i].absorbed, b[i].absorbed);
      EXPECT_EQ(a[i].score_p, b[i].score_p);
      EXPECT_EQ(a[i].overlap, b[i].overlap);
      EXPECT_EQ(a[i].distance_m, b[i].distance_m);
    }
    merges += a.size();
  }
  EXPECT_GT(merges, 0u);
  EXPECT_GT(cache->hits(), 0u);  // the pairs of objects a keyframe did not change
  EXPECT_GT(cache->misses(), 0u);
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
    add_one(map, obs(f, 1, "cup", 0.9, box(c, 5)));
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

// A flat box (a book): `half` cells in x and y, `half_z` in z, every face.
PointCloud slab(const Vec3& center, int half, int half_z) {
  PointCloud c;
  for (int i = -half; i <= half; ++i)
    for (int j = -half; j <= half; ++j)
      for (int k = -half_z; k <= half_z; ++k)
        if (std::abs(i) == half || std::abs(j) == half || std::abs(k) == half_z)
          c.push_back((center + 0.01 * Vec3(i, j, k)).cast<float>(), Rgb{10, 20, 30});
  return c;
}

PointCloud shifted(PointCloud c, const Vec3& by) {
  for (Vec3f& p : c.points) p += by.cast<float>();
  return c;
}

TEST(ObjectMap, ContainmentMatchesAPartialViewOfALargeFusedObjectIouDoesNot) {
  // An object fused from whole views; then one face of it under a new track id (a re-seen object
  // after an id switch): every point of the view is on the object, but the view is 1/6 of it.
  const Vec3 c(0.305, 0.105, 0.905);
  for (OverlapMeasure m : {OverlapMeasure::kContainment, OverlapMeasure::kIou}) {
    ObjectMapOptions options;
    options.overlap_measure = m;
    ObjectMap map(options);
    for (int f = 0; f < 3; ++f) add_one(map, obs(f, 1, "cabinet", 0.9, box(c, 20)));
    const AddResult r = add_one(map, obs(3, 7, "cabinet", 0.9, box(c, 20, 2)));  // +x face only
    if (m == OverlapMeasure::kContainment) {
      EXPECT_FALSE(r.created);
      EXPECT_DOUBLE_EQ(r.overlap, 1.0);
    } else {
      EXPECT_TRUE(r.created);
      EXPECT_LT(r.overlap, 0.2);
    }
  }
}

TEST(ObjectMap, OneVoxelToleranceMatchesAViewShiftedByDepthNoise) {
  // The same surface re-observed 1 cm further away (depth noise), under a new id.
  const Vec3 c(0.305, 0.105, 0.905);
  for (int tolerance : {1, 0}) {
    ObjectMapOptions options;
    options.overlap_tolerance_voxels = tolerance;
    ObjectMap map(options);
    for (int f = 0; f < 3; ++f) add_one(map, obs(f, 1, "cup", 0.9, box(c, 5)));
    const AddResult r =
        add_one(map, obs(3, 2, "cup", 0.9, shifted(box(c, 5), Vec3(0.01, 0.01, 0))));
    if (tolerance == 1) {
      EXPECT_FALSE(r.created);
      EXPECT_DOUBLE_EQ(r.overlap, 1.0);
    } else {
      EXPECT_TRUE(r.created);
      EXPECT_LT(r.overlap, 0.3);
    }
  }
}

TEST(ObjectMap, DistanceGateGrowsWithTheObjectsRadius) {
  // Only id and distance count (w_m = 0): a match needs the same id and D < G.
  ObjectMapOptions options;
  options.weight_overlap = 0.0;
  options.weight_id = 0.3;
  options.weight_distance = 0.2;
  const Vec3 c(0.305, 0.105, 0.905);
  PointCloud cluster = box(c + Vec3(0.2, 0, 0), 2);  // a few points 0.2 m from the centre
  for (double factor : {0.5, 0.0}) {
    options.gate_radius_factor = factor;
    // A 0.8 m cabinet: RMS radius of its surface ~0.52 m, so G = 0.26 m with factor 0.5.
    ObjectMap big(options);
    for (int f = 0; f < 3; ++f) add_one(big, obs(f, 1, "cabinet", 0.9, box(c, 40)));
    const AddResult r = add_one(big, obs(3, 1, "cabinet", 0.9, cluster));
    EXPECT_EQ(r.created, factor == 0.0) << factor;
    if (!r.created) {
      EXPECT_NEAR(r.distance_m, 0.2, 1e-3);
      EXPECT_NEAR(r.score_p, 0.3 + 0.2 * (1.0 - 0.2 / (2.0 * 0.5 * 0.5164)), 0.01);
    }
    // A 6 cm cup: G stays the paper's 0.1 m, the same offset is a new object.
    ObjectMap small(options);
    for (int f = 0; f < 3; ++f) add_one(small, obs(f, 1, "cup", 0.9, box(c, 3)));
    EXPECT_TRUE(add_one(small, obs(3, 1, "cup", 0.9, cluster)).created);
  }
}

TEST(ObjectMap, StackedBooksSeenTogetherStayTwoEvenAfterIdSwitches) {
  // Two 3 cm thick books, one on the other, seen in the same frames; the ids switch halfway.
  const Vec3 lower(0.505, -0.205, 0.765), upper(0.515, -0.195, 0.795);
  ObjectMap map;
  for (int f = 0; f < 8; ++f) {
    const int shift = f < 4 ? 0 : 10;
    add_one(map, obs(f, 1 + shift, "book", 0.8, slab(lower, 10, 1)));
    add_one(map, obs(f, 2 + shift, "book", 0.8, slab(upper, 10, 1)));
  }
  map.merge_pass();
  const auto records = map.records(no_outlier_filter());
  ASSERT_EQ(records.size(), 2u);
  EXPECT_LT((records[0].centroid - lower).norm(), 1e-4);
  EXPECT_LT((records[1].centroid - upper).norm(), 1e-4);
  EXPECT_EQ(records[0].observations, 8);
  EXPECT_EQ(records[1].observations, 8);
}

TEST(ObjectMap, MergePassNeverJoinsObjectsSeenTogetherInTheSameKeyframes) {
  // Two overlapping objects of one class, seen as two instances in the same keyframes (in the
  // synthetic scene: two stacked books whose masks bleed into each other, containment ~0.7).
  const Vec3 a(0.305, 0.105, 0.905), b(0.325, 0.105, 0.905);  // 2 cm apart, mostly overlapping
  ObjectMap map;
  for (int f = 0; f < 4; ++f) {
    add_one(map, obs(f, 1, "book", 0.8, box(a, 5)));
    add_one(map, obs(f, 2, "book", 0.8, box(b, 5)));  // object 0 already has frame f
  }
  EXPECT_TRUE(map.merge_pass().empty());
  EXPECT_EQ(map.size(), 2u);
  ObjectMapOptions loose;
  loose.merge_max_shared_frames = 1.0;
  ObjectMap joined(loose);
  for (int f = 0; f < 4; ++f) {
    add_one(joined, obs(f, 1, "book", 0.8, box(a, 5)));
    add_one(joined, obs(f, 2, "book", 0.8, box(b, 5)));
  }
  EXPECT_EQ(joined.merge_pass().size(), 1u);
  EXPECT_EQ(joined.size(), 1u);
}

TEST(ObjectMap, TwoCupsFiveCentimetresApartStayTwoThroughIdSwitches) {
  // Centres 5 cm apart (1 cm gap), the ids swap between the two cups halfway.
  const Vec3 a(0.005, 0.005, 1.005), b(0.055, 0.005, 1.005);
  ObjectMap map;
  for (int f = 0; f < 8; ++f) {
    add_one(map, obs(f, f < 4 ? 1 : 2, "cup", 0.9, box(a, 2)));
    add_one(map, obs(f, f < 4 ? 2 : 1, "cup", 0.9, box(b, 2)));
  }
  map.merge_pass();
  const auto records = map.records(no_outlier_filter());
  ASSERT_EQ(records.size(), 2u);
  EXPECT_LT((records[0].centroid - a).norm(), 1e-5);
  EXPECT_LT((records[1].centroid - b).norm(), 1e-5);
  EXPECT_EQ(records[0].observations, 8);
}

TEST(ObjectMap, MouseTouchingAKeyboardStaysAMouse) {
  // A mouse next to a keyboard, seen in different frames (no keyframe rule applies), touching it.
  const Vec3 keyboard(0.005, 0.005, 0.765), mouse(0.265, 0.005, 0.775);
  ObjectMap map;
  for (int f = 0; f < 4; ++f) add_one(map, obs(f, 1, "keyboard", 0.9, slab(keyboard, 22, 1)));
  for (int f = 4; f < 8; ++f) add_one(map, obs(f, 2, "mouse", 0.9, box(mouse, 3)));
  map.merge_pass();
  const auto records = map.records(no_outlier_filter());
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(records[0].class_name, "keyboard");
  EXPECT_EQ(records[1].class_name, "mouse");
  EXPECT_LT((records[1].centroid - mouse).norm(), 1e-5);
}

TEST(ObjectMap, AnObjectTakesOneObservationPerKeyframe) {
  // Two detections of one frame on the same spot (a duplicate box) are two objects.
  const Vec3 c(0.305, 0.105, 0.905);
  ObjectMap map;
  EXPECT_TRUE(add_one(map, obs(0, 1, "cup", 0.9, box(c, 5))).created);
  EXPECT_TRUE(add_one(map, obs(0, 2, "cup", 0.9, box(c, 5))).created);
  EXPECT_EQ(add_one(map, obs(1, 3, "cup", 0.9, box(c, 5))).object_id, 0);
  ObjectMapOptions off;
  off.one_observation_per_frame = false;
  ObjectMap loose(off);
  add_one(loose, obs(0, 1, "cup", 0.9, box(c, 5)));
  EXPECT_FALSE(add_one(loose, obs(0, 2, "cup", 0.9, box(c, 5))).created);
}

TEST(ObjectMap, VoxelsSeenInFewObservationsAreDroppedFromTheRecord) {
  // 20 views of a cup, each with a different 1-voxel strip of the table behind it (mask bleed):
  // a voxel must be in max(1, 0.1 × 20) = 2 observations.
  const Vec3 c(0.305, 0.105, 0.905);
  ObjectMap map;
  for (int f = 0; f < 20; ++f) {
    PointCloud view = box(c, 5);
    for (int i = 0; i < 30; ++i)
      view.push_back(Vec3f(0.2f + 0.01f * i + 0.005f, 0.3f + 0.01f * f + 0.005f, 0.845f),
                     Rgb{1, 2, 3});
    add_one(map, obs(f, 1, "cup", 0.9, std::move(view)));
  }
  const auto kept = map.records(no_outlier_filter());
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].points_voxel, box(c, 5).size());
  EXPECT_LT((kept[0].centroid - c).norm(), 1e-5);
  RecordOptions all = no_outlier_filter();
  all.min_voxel_support = 0.0;
  EXPECT_EQ(map.records(all)[0].points_voxel, box(c, 5).size() + 600);
}

TEST(ObjectMap, PositionIsTheCentreOfTheSeenExtentNotThePointMean) {
  // Seen from above: top and the four sides, never the bottom. The point mean is pulled up; the
  // position (centre of the percentile box) is the box centre.
  const Vec3 c(0.305, 0.105, 0.905);
  ObjectMap map;
  for (int f = 0; f < 3; ++f) add_one(map, obs(f, 1, "cup", 0.9, box(c, 5, 63 & ~16)));
  const auto r = map.records(no_outlier_filter());
  ASSERT_EQ(r.size(), 1u);
  EXPECT_GT(r[0].centroid.z() - c.z(), 0.005);
  EXPECT_LT((r[0].position - c).norm(), 1e-5);
}

TEST(ObjectMap, LargeObservationsJoinTheirObject) {
  // ~20k points (a chair at 2 m: 4 mm pixel footprint, ~3k voxels) added to an object fused from
  // earlier views, next to 10 other objects: every view joins the chair.
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, 0.003f);
  auto view = [&](float shift) {
    PointCloud c;
    for (int i = 0; i < 140; ++i)
      for (int j = 0; j < 143; ++j)
        c.push_back(Vec3f(0.3f + shift + 0.004f * i + noise(rng), 0.5f + noise(rng),
                          0.2f + 0.004f * j + noise(rng)),
                    Rgb{1, 1, 1});
    return c;
  };
  ObjectMap map;
  for (int k = 0; k < 10; ++k)
    for (int f = 0; f < 3; ++f)
      add_one(map, obs(f, 100 + k, "cup", 0.9, box(Vec3(0.2 * k, 2, 1), 4)));
  for (int f = 0; f < 3; ++f) add_one(map, obs(f, 1, "chair", 0.9, view(0.01f * f)));
  std::vector<PointCloud> views;
  for (int f = 0; f < 10; ++f) views.push_back(view(0.01f * f));
  for (int f = 0; f < 10; ++f) add_one(map, obs(10 + f, 2, "chair", 0.9, views[f]));
  EXPECT_EQ(map.size(), 11u);  // the later views of the chair joined it (speed: BM_ObjectMapAdd)
  int chair_observations = 0;
  for (const auto& r : map.records(no_outlier_filter()))
    if (r.class_name == "chair") chair_observations = r.observations;
  EXPECT_EQ(chair_observations, 13);
}

TEST(ObjectMap, OverlapMeasureNames) {
  EXPECT_EQ(parse_overlap_measure("iou", "x"), OverlapMeasure::kIou);
  EXPECT_EQ(parse_overlap_measure("containment", "x"), OverlapMeasure::kContainment);
  EXPECT_STREQ(to_string(OverlapMeasure::kIou), "iou");
  try {
    parse_overlap_measure("dice", "--overlap");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "--overlap: unknown overlap measure 'dice'; expected iou or containment");
  }
  ObjectMapOptions o;
  o.overlap_tolerance_voxels = 2;
  try {
    o.check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "ObjectMapOptions.overlap_tolerance_voxels: must be 0 or 1, got 2");
  }
}

// A camera pose at `x` metres along the world's x axis, turned `yaw_deg` about its y axis.
Pose camera_at(double x, double yaw_deg = 0.0) {
  Pose p = Pose::Identity();
  p.translate(Vec3(x, 0, 0));
  p.rotate(Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Vec3::UnitY()));
  return p;
}

Observation posed(double t, std::optional<int> id, const std::string& cls, PointCloud points,
                  const Pose& world_from_cam) {
  Observation o = obs(t, id, cls, 0.9, std::move(points));
  o.world_from_cam = world_from_cam;
  return o;
}

TEST(ObjectMap, ConfirmationCountsViewsNotFrames) {
  // A false positive in five consecutive frames of a 30 Hz video (the camera moves 1 cm per
  // frame) is one view; the object seen from three places 5 cm apart is three.
  const Vec3 c(0.305, 0.105, 0.905);
  ObjectMap map;
  for (int f = 0; f < 5; ++f) add_one(map, posed(f, 1, "cup", box(c, 3), camera_at(0.01 * f)));
  const Vec3 d(1.305, 0.105, 0.905);
  for (int f = 0; f < 3; ++f)
    add_one(map, posed(10 + f, 2, "book", box(d, 3), camera_at(0.05 * f)));
  ASSERT_EQ(map.size(), 2u);
  EXPECT_EQ(map.confirmed_count(), 1u);
  auto all = no_outlier_filter();
  all.confirmed_only = false;
  const auto records = map.records(all);
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(records[0].observations, 5);
  EXPECT_EQ(records[0].views, 1);  // 0.04 m from the first: not a new view
  EXPECT_FALSE(records[0].confirmed);
  EXPECT_EQ(records[1].views, 3);
  EXPECT_TRUE(records[1].confirmed);

  // A turn is a view too; without a pose every observation is; 0 and 0: the paper's count.
  std::vector<ObservationLink> links(3);
  links[0].world_from_cam = camera_at(0.0, 0.0);
  links[1].world_from_cam = camera_at(0.0, 4.0);
  links[2].world_from_cam = camera_at(0.0, 6.0);
  EXPECT_EQ(count_views(links, ObjectMapOptions{}), 2);
  links[1].world_from_cam.reset();
  EXPECT_EQ(count_views(links, ObjectMapOptions{}), 3);
  ObjectMapOptions paper;
  paper.view_min_translation_m = paper.view_min_rotation_deg = 0.0;
  ObjectMap counted(paper);
  for (int f = 0; f < 5; ++f) add_one(counted, posed(f, 1, "cup", box(c, 3), camera_at(0.01 * f)));
  EXPECT_EQ(counted.confirmed_count(), 1u);
}

TEST(ObjectMap, AClassConfusionJoinsTheObjectItLiesOn) {
  // A keyboard seen from 12 places; in 3 of them the detector also boxed it as "book" (the same
  // surface, a second instance of the frame, so it cannot join the keyboard there).
  const Vec3 keyboard(0.005, 0.005, 0.765);
  ObjectMap map;
  for (int f = 0; f < 12; ++f) {
    std::vector<Observation> frame{
        posed(f, 1, "keyboard", slab(keyboard, 22, 1), camera_at(0.1 * f))};
    if (f % 4 == 0) frame.push_back(posed(f, 2, "book", slab(keyboard, 20, 1), camera_at(0.1 * f)));
    map.add_frame(frame);
  }
  EXPECT_EQ(map.confirmed_count(), 2u) << "before the merge pass: a keyboard and a book";
  const auto merges = map.merge_pass();
  ASSERT_EQ(merges.size(), 1u);
  EXPECT_TRUE(merges[0].class_confusion);
  EXPECT_EQ(merges[0].into, 0);
  EXPECT_NEAR(merges[0].overlap, 1.0, 1e-9);
  const auto records = map.records(no_outlier_filter());
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].class_name, "keyboard");
  EXPECT_EQ(records[0].observations, 15);

  // Seen about as often as the larger object (a cup on a table), or switched off: it stays.
  ObjectMap often;
  for (int f = 0; f < 12; ++f)
    often.add_frame({posed(f, 1, "keyboard", slab(keyboard, 22, 1), camera_at(0.1 * f)),
                     posed(f, 2, "book", slab(keyboard, 20, 1), camera_at(0.1 * f))});
  EXPECT_TRUE(often.merge_pass().empty());
  ObjectMapOptions off;
  off.merge_class_confusions = false;
  ObjectMap kept(off);
  for (int f = 0; f < 12; ++f) {
    std::vector<Observation> frame{
        posed(f, 1, "keyboard", slab(keyboard, 22, 1), camera_at(0.1 * f))};
    if (f % 4 == 0) frame.push_back(posed(f, 2, "book", slab(keyboard, 20, 1), camera_at(0.1 * f)));
    kept.add_frame(frame);
  }
  EXPECT_TRUE(kept.merge_pass().empty());
}

// objmap follow's publishes score class confusions through the pair cache: as the map grows, the
// merges of copies sharing one cache are those of the map made afresh without it.
TEST(ObjectMap, ClassConfusionsWithThePairCacheAreThoseMadeAfresh) {
  const Vec3 keyboard(0.005, 0.005, 0.765);
  std::vector<std::vector<Observation>> frames;
  for (int f = 0; f < 16; ++f) {
    // Now and then a frame sees only a cup elsewhere: the keyboard and the book do not change.
    if (f % 4 == 2) {
      frames.push_back({posed(f, 3, "cup", box(Vec3(1.505, 0.005, 0.805), 3), camera_at(0.1 * f))});
      continue;
    }
    frames.push_back({posed(f, 1, "keyboard", slab(keyboard, 22, 1), camera_at(0.1 * f))});
    // The book boxed on the keyboard, then further along it (less of it on the keyboard's
    // surface).
    const Vec3 at = keyboard + Vec3(f < 8 ? 0.0 : 0.12, 0.0, 0.0);
    if (f % 4 == 0)
      frames.back().push_back(posed(f, 2, "book", slab(at, 20, 1), camera_at(0.1 * f)));
  }
  auto cache = std::make_shared<PairCache>();
  ObjectMap live;
  live.set_pair_cache(cache);
  std::size_t confusions = 0;
  for (std::size_t n = 0; n < frames.size(); ++n) {
    live.add_frame(frames[n]);
    ObjectMap published = live;
    ObjectMap fresh;
    for (std::size_t k = 0; k <= n; ++k) fresh.add_frame(frames[k]);
    const std::vector<MergeLink> a = published.merge_pass(), b = fresh.merge_pass();
    ASSERT_EQ(a.size(), b.size()) << n;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].into, b[i].into) << n;
      EXPECT_EQ(a[i].absorbed, b[i].absorbed) << n;
      EXPECT_EQ(a[i].overlap, b[i].overlap) << n;
      EXPECT_EQ(a[i].class_confusion, b[i].class_confusion) << n;
      confusions += a[i].class_confusion;
    }
  }
  EXPECT_GT(confusions, 0u);
  EXPECT_GT(cache->shares.hits(), 0u);  // the pairs no frame changed
}

TEST(ObjectMap, AMouseOnAKeyboardsBleedIsNoClassConfusion) {
  // The keyboard's masks took the mouse beside it in 1 of its 12 views: the mouse's voxels lie on
  // the keyboard's voxels, but not on its surface (voxels in >= 10% of its observations).
  const Vec3 keyboard(0.005, 0.005, 0.765), mouse(0.305, 0.005, 0.775);
  ObjectMap map;
  for (int f = 0; f < 12; ++f) {
    PointCloud seen = slab(keyboard, 22, 1);
    if (f == 0) {
      const PointCloud bleed = box(mouse, 3);
      for (std::size_t i = 0; i < bleed.size(); ++i)
        seen.push_back(bleed.points[i], bleed.colors[i]);
    }
    std::vector<Observation> frame{posed(f, 1, "keyboard", seen, camera_at(0.1 * f))};
    if (f % 3 == 0) frame.push_back(posed(f, 2, "mouse", box(mouse, 3), camera_at(0.1 * f)));
    map.add_frame(frame);
  }
  map.merge_pass();
  const auto records = map.records(no_outlier_filter());
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(records[1].class_name, "mouse");
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

// A copy of the map (objmap follow's publish) shares the objects' voxels until one side changes
// them: the copy, merged while the map it came from goes on fusing, ends as a map of its own
// frames alone, and the map as one of every frame (clouds bit for bit).
TEST(ObjectMap, ACopyGoesOnAsItWasWhileTheMapItCameFromGrows) {
  // A tv seen in halves by tracks 1 and 2, then whole by 2 (the merge pass joins the halves: as
  // in FinalMergePassRepairsAnIdSwitchTheOnlineStepMissed), and a cup beside it.
  const Vec3 tv(0.305, 0.105, 0.905), cup(1.505, 0.105, 0.905);
  const auto frame = [&](int t) {
    const int faces = t < 3 ? 1 | 4 | 16 : t < 6 ? 2 | 8 | 32 : 63;
    return std::vector<Observation>{obs(t, t < 3 ? 1 : 2, "tv", 0.8, box(tv, 10, faces)),
                                    obs(t, 7, "cup", 0.9, box(cup, 3 + t % 2))};
  };
  const auto made_of = [&](int frames) {
    ObjectMap map;
    for (int t = 0; t < frames; ++t) map.add_frame(frame(t));
    return map;
  };
  const auto expect_same = [](const std::vector<ObjectRecord>& x,
                              const std::vector<ObjectRecord>& y) {
    ASSERT_EQ(x.size(), y.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      EXPECT_EQ(x[i].id, y[i].id);
      EXPECT_EQ(x[i].observations, y[i].observations);
      ASSERT_EQ(x[i].cloud.points, y[i].cloud.points) << "object " << x[i].id;
    }
  };
  ObjectMap live = made_of(7);
  ObjectMap copy = live;
  for (int t = 7; t < 12; ++t) live.add_frame(frame(t));
  const std::vector<MergeLink> merged = copy.merge_pass();
  EXPECT_EQ(merged.size(), 1u);  // the copy changes too: the halves joined
  ObjectMap seven = made_of(7);
  EXPECT_EQ(seven.merge_pass().size(), merged.size());
  expect_same(copy.records(no_outlier_filter()), seven.records(no_outlier_filter()));
  expect_same(live.records(no_outlier_filter()), made_of(12).records(no_outlier_filter()));
  const auto observations = [](const ObjectMap& map) {
    int n = 0;
    for (const ObjectRecord& r : map.records(no_outlier_filter())) n += r.observations;
    return n;
  };
  EXPECT_EQ(observations(live), 24);
  EXPECT_EQ(observations(copy), 14);
}

}  // namespace
}  // namespace objmap::fusion

#include "objmap/fusion/duplicates.h"

#include <gtest/gtest.h>

#include "fusion_test_util.h"
#include "objmap/core/error.h"
#include "objmap/fusion/record_cache.h"

namespace objmap::fusion {
namespace {

// One observation as a keyframe of its own.
AddResult add_alone(ObjectMap& map, const Observation& observation) {
  return map.add_frame({observation}).front();
}

// Surface points of an axis-aligned box at 1 cm steps: `half` cells to each side of `center`
// along each axis (distinct halves give distinct PCA axes, so the record's OBB is the box).
PointCloud brick(const Vec3& center, const Eigen::Vector3i& half) {
  PointCloud cloud;
  const Eigen::Vector3i size = 2 * half + Eigen::Vector3i::Ones();
  for (int n = 0; n < size.prod(); ++n) {
    const Eigen::Vector3i ijk(n % size.x(), (n / size.x()) % size.y(), n / (size.x() * size.y()));
    const Eigen::Vector3i offset = ijk - half;
    if ((offset.cwiseAbs().array() == half.array()).any())
      cloud.push_back((center + 0.01 * offset.cast<double>()).cast<float>(), Rgb{90, 90, 90});
  }
  return cloud;
}

PointCloud keep_if(const PointCloud& cloud, double min_x) {
  PointCloud out;
  for (const Vec3f& p : cloud.points)
    if (p.x() >= min_x) out.push_back(p, Rgb{90, 90, 90});
  return out;
}

Observation seen(double t, int track_id, const std::string& cls, PointCloud points) {
  return test::instance(t, track_id, cls, std::move(points));
}

std::vector<ObjectRecord> records_of(ObjectMap& map) {
  map.merge_pass();
  RecordOptions options;
  options.outlier_filter = false;  // the clouds are the voxel means: exact figures
  return map.records(options);
}

const Vec3 kBoxCentre(0.305, 0.105, 0.905);
const Eigen::Vector3i kHalf(10, 7, 5);  // a 20 × 14 × 10 cm box

// One object detected twice in every keyframe (the whole and its +x half, two track ids): the
// merge pass refuses to join two objects seen in the same keyframes, so two objects stay.
void add_whole_and_half(ObjectMap& map) {
  const PointCloud whole = brick(kBoxCentre, kHalf);
  for (int f = 0; f < 4; ++f)
    map.add_frame(
        {seen(f, 1, "chair", whole), seen(f, 2, "chair", keep_if(whole, kBoxCentre.x()))});
}

TEST(Duplicates, FragmentSeenInTheSameKeyframesIsReportedWithThatReason) {
  ObjectMap map;
  add_whole_and_half(map);
  const auto records = records_of(map);
  ASSERT_EQ(records.size(), 2u);
  const DuplicateReport report = find_duplicates(records, map);
  EXPECT_EQ(report.pairs_checked, 1u);
  ASSERT_EQ(report.pairs.size(), 1u);
  const DuplicatePair& p = report.pairs[0];
  EXPECT_EQ(p.a, records[0].id);
  EXPECT_EQ(p.b, records[1].id);
  EXPECT_EQ(p.class_name, "chair");
  EXPECT_NEAR(p.obb_overlap, 1.0, 1e-9);         // the half's box lies in the whole's
  EXPECT_NEAR(p.surface_distance_m, 0.0, 1e-6);  // the half's points are the whole's
  EXPECT_NEAR(p.touching_share, 1.0, 1e-9);
  EXPECT_EQ(p.merge.refused, MergeRefusal::kSharedFrames);
  EXPECT_EQ(p.merge.shared_frames, 4);
  EXPECT_EQ(p.merge.smaller_frames, 4);
  EXPECT_NEAR(p.merge.overlap, 1.0, 1e-9);  // computed although an earlier rule refused
  EXPECT_GT(p.merge.score_p, map.options().merge_threshold);
  EXPECT_EQ(describe_refusal(p.merge, map.options()),
            "seen together in 4 of 4 keyframes (more than 30%)");

  // That rule alone kept them apart: without it the pass joins them.
  ObjectMapOptions loose;
  loose.merge_max_shared_frames = 1.0;
  ObjectMap joined(loose);
  add_whole_and_half(joined);
  EXPECT_EQ(joined.merge_verdict(0, 1).refused, MergeRefusal::kNone);
  EXPECT_EQ(joined.merge_pass().size(), 1u);
}

TEST(Duplicates, PartlyOverlappingObjectsBelowTheMergeContainmentAreReported) {
  // One track id over two boxes that overlap by a quarter of their length, seen in different
  // keyframes. A strict online match (K = 0.95) keeps them apart; in the merge pass P passes
  // (same track) but the containment of one in the other is below merge_min_overlap.
  ObjectMapOptions options;
  options.match_threshold = 0.95;
  ObjectMap map(options);
  const Vec3 shift(0.15, 0.0, 0.0);
  for (int f = 0; f < 4; ++f) add_alone(map, seen(f, 7, "book", brick(kBoxCentre, kHalf)));
  for (int f = 4; f < 8; ++f) add_alone(map, seen(f, 7, "book", brick(kBoxCentre + shift, kHalf)));
  const auto records = records_of(map);
  ASSERT_EQ(records.size(), 2u);
  const DuplicateReport report = find_duplicates(records, map);
  ASSERT_EQ(report.pairs.size(), 1u);
  const DuplicatePair& p = report.pairs[0];
  // Equal boxes overlapping over 5 of 20 cm along x: a quarter of either (the sample grid of 20
  // per axis puts 5 of 20 cell centres in the overlap).
  EXPECT_NEAR(p.obb_overlap, 0.25, 1e-9);
  EXPECT_NEAR(p.surface_distance_m, 0.0, 1e-6);  // the side faces coincide where they overlap
  EXPECT_GT(p.touching_share, 0.0);
  EXPECT_LT(p.touching_share, 0.5);
  EXPECT_EQ(p.merge.refused, MergeRefusal::kOverlap);
  EXPECT_EQ(p.merge.p_id, 1.0);
  EXPECT_GT(p.merge.score_p, options.merge_threshold);
  EXPECT_LT(p.merge.overlap, options.merge_min_overlap);
  EXPECT_GT(p.merge.overlap, 0.0);
  EXPECT_EQ(p.merge.shared_frames, 0);
  EXPECT_EQ(describe_refusal(p.merge, options).rfind("containment M ", 0), 0u);
}

// Two objects, each seen in keyframes 0-3 with its own track id, after the merge pass.
struct TwoObjects {
  ObjectMap map;
  std::vector<ObjectRecord> records;
};
TwoObjects two_objects(const std::string& class_a, const PointCloud& a, const std::string& class_b,
                       const PointCloud& b) {
  TwoObjects t;
  for (int f = 0; f < 4; ++f) {
    add_alone(t.map, seen(f, 1, class_a, a));
    add_alone(t.map, seen(f, 2, class_b, b));
  }
  t.records = records_of(t.map);
  return t;
}

// The report on two objects that stayed two confirmed objects.
DuplicateReport report_on(const TwoObjects& t) {
  EXPECT_EQ(t.records.size(), 2u);
  return find_duplicates(t.records, t.map);
}

TEST(Duplicates, SameClassFarApartIsNotReported) {
  const PointCloud far = brick(kBoxCentre + Vec3(1.0, 0.0, 0.0), kHalf);
  const DuplicateReport report =
      report_on(two_objects("cup", brick(kBoxCentre, kHalf), "cup", far));
  EXPECT_EQ(report.pairs_checked, 1u);
  EXPECT_TRUE(report.pairs.empty());
}

TEST(Duplicates, TouchingSurfacesWithoutBoxOverlapAreReported) {
  // Two boxes side by side, a 1 cm gap between their faces (the faces' points 1 cm apart).
  const PointCloud next = brick(kBoxCentre + Vec3(0.21, 0.0, 0.0), kHalf);
  const TwoObjects t = two_objects("cup", brick(kBoxCentre, kHalf), "cup", next);
  const DuplicateReport report = report_on(t);
  ASSERT_EQ(report.pairs.size(), 1u);
  EXPECT_EQ(report.pairs[0].obb_overlap, 0.0);
  EXPECT_NEAR(report.pairs[0].surface_distance_m, 0.01, 1e-6);
  // A 1 cm gap is too wide for touch_distance_m = 0.5 cm.
  DuplicateOptions tight;
  tight.touch_distance_m = 0.005;
  EXPECT_TRUE(find_duplicates(t.records, t.map, tight).pairs.empty());
}

TEST(Duplicates, DifferentClassesTouchingAreNotReported) {
  const PointCloud mouse = brick(kBoxCentre + Vec3(0.2, 0.0, 0.0), Eigen::Vector3i(3, 2, 1));
  const DuplicateReport report =
      report_on(two_objects("keyboard", brick(kBoxCentre, kHalf), "mouse", mouse));
  EXPECT_EQ(report.pairs_checked, 0u);
  EXPECT_TRUE(report.pairs.empty());
}

TEST(Duplicates, VerdictAgreesWithTheMergePass) {
  // An ID switch the online step missed (track 1 sees one half, track 2 the other and later the
  // whole): the pass joins them; its verdict before the pass says so, with the same scores.
  ObjectMap map;
  const PointCloud whole = brick(kBoxCentre, kHalf);
  for (int f = 0; f < 3; ++f)
    add_alone(map, seen(f, 1, "tv", keep_if(whole, kBoxCentre.x() + 0.051)));
  for (int f = 3; f < 6; ++f) add_alone(map, seen(f, 2, "tv", keep_if(whole, -1.0)));
  // A second tv far away, seen later: never joined, for its score.
  for (int f = 6; f < 9; ++f)
    add_alone(map, seen(f, 3, "tv", brick(kBoxCentre + Vec3(2, 0, 0), kHalf)));
  ASSERT_EQ(map.size(), 3u);
  const MergeVerdict before = map.merge_verdict(1, 0);  // either order: the pass's (0, 1)
  EXPECT_EQ(before.a, 0);
  EXPECT_EQ(before.b, 1);
  EXPECT_EQ(before.refused, MergeRefusal::kNone);
  EXPECT_EQ(describe_refusal(before, map.options()), "would merge");
  EXPECT_EQ(map.merge_verdict(0, 2).refused, MergeRefusal::kScore);
  EXPECT_EQ(map.merge_verdict(1, 2).refused, MergeRefusal::kScore);
  const auto merges = map.merge_pass();
  ASSERT_EQ(merges.size(), 1u);
  EXPECT_EQ(merges[0].into, 0);
  EXPECT_EQ(merges[0].absorbed, 1);
  EXPECT_EQ(merges[0].score_p, before.score_p);
  EXPECT_EQ(merges[0].overlap, before.overlap);
  EXPECT_EQ(merges[0].distance_m, before.distance_m);
  // After the pass: the remaining pair is refused, and an absorbed id is no live object.
  EXPECT_EQ(map.merge_verdict(0, 2).refused, MergeRefusal::kScore);
  EXPECT_THROW(map.merge_verdict(0, 1), InputError);
  EXPECT_THROW(map.merge_verdict(0, 0), InputError);
}

TEST(Duplicates, VerdictAndMergePassAgreeOnAClutteredMap) {
  // Fragments and neighbours of a few boxes under track switches: the first merge the pass makes
  // is the pair with the highest P among those whose verdict is "none", and after the pass no live
  // pair has that verdict (the pass stops when none is left).
  ObjectMapOptions options;
  options.match_threshold = 0.9;  // strict online matching leaves fragments for the pass
  ObjectMap map(options);
  const PointCloud whole = brick(kBoxCentre, kHalf);
  for (int f = 0; f < 12; ++f) {
    const Vec3 step(0.04 * (f % 4), 0.0, 0.0);
    add_alone(map, seen(f, 1 + f / 3, "chair",
                        keep_if(brick(kBoxCentre + step, kHalf), kBoxCentre.x() + 0.02)));
    add_alone(map,
              seen(f, 9, f % 2 ? "chair" : "book", brick(kBoxCentre + Vec3(0.0, 0.3, 0.0), kHalf)));
  }
  RecordOptions all;
  all.confirmed_only = false;
  all.outlier_filter = false;
  const auto live_ids = [&] {
    std::vector<int> ids;
    for (const ObjectRecord& r : map.records(all)) ids.push_back(r.id);
    return ids;
  };
  const std::vector<int> before = live_ids();
  ASSERT_GE(before.size(), 3u);
  const MergeVerdict* best = nullptr;
  std::vector<MergeVerdict> verdicts;
  for (std::size_t i = 0; i < before.size(); ++i)
    for (std::size_t j = i + 1; j < before.size(); ++j)
      verdicts.push_back(map.merge_verdict(before[i], before[j]));
  for (const MergeVerdict& v : verdicts)
    if (v.refused == MergeRefusal::kNone && (!best || v.score_p > best->score_p)) best = &v;
  const auto merges = map.merge_pass();
  ASSERT_EQ(merges.empty(), best == nullptr);
  if (best) {
    EXPECT_EQ(merges[0].into, best->a);
    EXPECT_EQ(merges[0].absorbed, best->b);
    EXPECT_EQ(merges[0].score_p, best->score_p);
  }
  const std::vector<int> after = live_ids();
  EXPECT_EQ(after.size(), before.size() - merges.size());
  for (std::size_t i = 0; i < after.size(); ++i)
    for (std::size_t j = i + 1; j < after.size(); ++j)
      EXPECT_NE(map.merge_verdict(after[i], after[j]).refused, MergeRefusal::kNone)
          << after[i] << " " << after[j];
}

TEST(Duplicates, BoxContainmentIsTheSharedVolumeOfTheSmaller) {
  Obb large;
  large.half_extent = Vec3(1.0, 1.0, 1.0);
  Obb small = large;
  small.half_extent = Vec3(0.5, 0.5, 0.5);
  EXPECT_DOUBLE_EQ(obb_containment(small, large, 10), 1.0);
  small.center = Vec3(1.0, 0.0, 0.0);  // half of it sticks out along x
  EXPECT_DOUBLE_EQ(obb_containment(small, large, 10), 0.5);
  // Rotated by 45 degrees about z: the samples stay in the box's own frame.
  small.center = Vec3::Zero();
  small.rotation = Eigen::AngleAxisd(M_PI / 4, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_DOUBLE_EQ(obb_containment(small, large, 10), 1.0);
  small.center = Vec3(5.0, 0.0, 0.0);
  EXPECT_EQ(obb_containment(small, large, 10), 0.0);
}

TEST(Duplicates, OptionsAreChecked) {
  DuplicateOptions bad;
  bad.touch_distance_m = -0.01;
  EXPECT_THROW(bad.check(), InputError);
  bad = DuplicateOptions{};
  bad.obb_samples_per_axis = 0;
  EXPECT_THROW(bad.check(), InputError);
  EXPECT_NO_THROW(DuplicateOptions{}.check());
}

TEST(Duplicates, TheContactCacheGivesTheFiguresMadeAfreshAndMissesAChangedCloud) {
  // Three chairs: the whole, its half (touching) and one far away (boxes apart: no contact asked).
  ObjectMap map;
  const PointCloud whole = brick(kBoxCentre, kHalf);
  for (int f = 0; f < 4; ++f)
    map.add_frame({seen(f, 1, "chair", whole), seen(f, 2, "chair", keep_if(whole, kBoxCentre.x())),
                   seen(f, 3, "chair", brick(kBoxCentre + Vec3(0.0, 0.5, 0.0), kHalf))});
  std::vector<ObjectRecord> records = records_of(map);
  ASSERT_EQ(records.size(), 3u);
  const DuplicateReport fresh = find_duplicates(records, map);
  auto cache = std::make_shared<ContactCache>();
  map.set_contact_cache(cache);
  auto expect_same = [&](const DuplicateReport& got, const DuplicateReport& want) {
    ASSERT_EQ(got.pairs_checked, want.pairs_checked);
    ASSERT_EQ(got.pairs.size(), want.pairs.size());
    for (std::size_t i = 0; i < got.pairs.size(); ++i) {
      EXPECT_EQ(got.pairs[i].a, want.pairs[i].a);
      EXPECT_EQ(got.pairs[i].surface_distance_m, want.pairs[i].surface_distance_m);  // exact
      EXPECT_EQ(got.pairs[i].touching_share, want.pairs[i].touching_share);
    }
  };
  expect_same(find_duplicates(records, map), fresh);  // made and put
  EXPECT_EQ(cache->hits(), 0u);
  const std::size_t made = cache->misses();
  EXPECT_GE(made, 1u);
  expect_same(find_duplicates(records, map), fresh);  // every contact from the cache
  EXPECT_EQ(cache->hits(), made);
  EXPECT_EQ(cache->misses(), made);
  const ObjectMap copy(map);  // a publish's copy shares the cache
  expect_same(find_duplicates(records, copy), fresh);
  EXPECT_EQ(cache->hits(), 2 * made);
  // The half moved by 1 cm: its contacts are made again, and they are the fresh figures.
  ObjectRecord& half = records[0].cloud.size() < records[1].cloud.size() ? records[0] : records[1];
  for (Vec3f& p : half.cloud.points) p.y() += 0.01f;
  map.set_contact_cache(nullptr);
  const DuplicateReport moved = find_duplicates(records, map);
  map.set_contact_cache(cache);
  expect_same(find_duplicates(records, map), moved);
  EXPECT_EQ(cache->misses(), 2 * made);
  // Another touch distance is another contact.
  DuplicateOptions wider;
  wider.touch_distance_m = 0.05;
  find_duplicates(records, map, wider);
  EXPECT_EQ(cache->misses(), 3 * made);
}

}  // namespace
}  // namespace objmap::fusion

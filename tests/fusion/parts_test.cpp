// Parts of one instance (ObjectMap::join_parts) and the trim of another instance's part
// (ObjectMap::cut_oversize), once the up is known: docs/fusion.md "The extent of one instance".
#include <gtest/gtest.h>

#include "fusion_test_util.h"
#include "objmap/fusion/object_map.h"
#include "objmap/fusion/record_cache.h"
#include "objmap/segmentation/class_sizes.h"

namespace objmap::fusion {
namespace {

using test::box;
using test::instance;

// Only the rules under test: no merge pass, no fragment or class-confusion merges.
ObjectMapOptions parts_options() {
  ObjectMapOptions o;
  o.final_merge = false;
  o.merge_fragments_in_box = false;
  o.merge_class_confusions = false;
  return o;
}

// A chair's seat and legs as a 0.41 m box seen from the front (no -y face), x 0.305-0.705,
// y -0.095-0.305, z 0.005-0.405.
PointCloud parts_seat(double x = 0.505) { return box(Vec3(x, 0.105, 0.205), 20, 63 & ~4); }

// The back of that chair seen from behind over a table: a slab 2 cm behind the seat's back edge,
// from just above the seat to 0.815 m.
PointCloud parts_back(double x = 0.505) {
  PointCloud back;
  for (int i = -20; i <= 20; ++i)
    for (int k = 0; k <= 40; ++k)
      back.push_back(Vec3f(static_cast<float>(x + 0.01 * i), -0.115f, 0.415f + 0.01f * k));
  return back;
}

double parts_width_x(const ObjectRecord& r) { return r.aabb.max.x() - r.aabb.min.x(); }

TEST(ObjectMap, AChairsBackSeenAloneInOtherKeyframesJoinsTheChair) {
  ObjectMap map(parts_options());
  for (int f = 0; f < 6; ++f) map.add_frame({instance(f, 1, "chair", parts_seat())});
  for (int f = 10; f < 16; ++f) map.add_frame({instance(f, 2, "chair", parts_back())});
  ASSERT_EQ(map.records(RecordOptions{}).size(), 2u);  // two objects before the rule
  const std::vector<MergeLink> joins = map.join_parts(Vec3::UnitZ(), {});
  ASSERT_EQ(joins.size(), 1u);
  EXPECT_TRUE(joins[0].part);
  EXPECT_GE(joins[0].overlap, 0.8);  // the back lies over the seat's footprint
  const auto records = map.records(RecordOptions{});
  ASSERT_EQ(records.size(), 1u);
  EXPECT_LT(parts_width_x(records[0]), 0.45);
  EXPECT_GT(records[0].aabb.max.z(), 0.75);  // the back is the chair's (the seat: 0.405)
  EXPECT_LT(records[0].aabb.min.z(), 0.03);
  EXPECT_TRUE(map.join_parts(Vec3::UnitZ(), {}).empty());  // nothing is left to join
}

TEST(ObjectMap, PackedChairsCupsApartAndFragmentsAloneAreNotJoined) {
  // Two chairs 6 cm apart, seen by turns, with one track id or two: together 0.87 m wide, more
  // than a chair.
  for (int second_track : {1, 2}) {
    ObjectMap map(parts_options());
    for (int f = 0; f < 6; ++f) map.add_frame({instance(f, 1, "chair", parts_seat(0.505))});
    for (int f = 10; f < 16; ++f)
      map.add_frame({instance(f, second_track, "chair", parts_seat(0.975))});
    ASSERT_EQ(map.records(RecordOptions{}).size(), 2u);
    EXPECT_TRUE(map.join_parts(Vec3::UnitZ(), {}).empty()) << "track " << second_track;
  }
  // Two cups (5 cm cubes) 8 cm apart, seen by turns: together no wider than a cup, but neither
  // lies over the other's footprint and they share no track id.
  {
    ObjectMap map(parts_options());
    for (int f = 0; f < 6; ++f)
      map.add_frame({instance(f, 1, "cup", box(Vec3(0.505, 0.105, 0.025), 2))});
    for (int f = 10; f < 16; ++f)
      map.add_frame({instance(f, 2, "cup", box(Vec3(0.585, 0.105, 0.025), 2))});
    ASSERT_EQ(map.records(RecordOptions{}).size(), 2u);
    EXPECT_TRUE(map.join_parts(Vec3::UnitZ(), {}).empty());
  }
  // A back and a seat seen twice each: neither is confirmed, so no object is made of them.
  {
    ObjectMap map(parts_options());
    for (int f = 0; f < 2; ++f) map.add_frame({instance(f, 1, "chair", parts_seat())});
    for (int f = 10; f < 12; ++f) map.add_frame({instance(f, 2, "chair", parts_back())});
    EXPECT_TRUE(map.join_parts(Vec3::UnitZ(), {}).empty());
  }
  // --method paper (oversize off) and join_parts off: no joins.
  for (bool enabled : {false, true}) {
    ObjectMapOptions o = parts_options();
    o.oversize.enabled = enabled;
    o.oversize.join_parts = false;
    ObjectMap map(o);
    for (int f = 0; f < 6; ++f) map.add_frame({instance(f, 1, "chair", parts_seat())});
    for (int f = 10; f < 16; ++f) map.add_frame({instance(f, 2, "chair", parts_back())});
    EXPECT_TRUE(map.join_parts(Vec3::UnitZ(), {}).empty());
  }
}

// A mask over a chair and the side of the chair beside it (x 1.18, a tall face): not two
// instances (the side is under a quarter of the surface) and not a flat strip, so without the
// neighbour as an object nothing is cut; with it confirmed, the side is trimmed off as its part.
TEST(ObjectMap, ATallPartBeyondTheCutIsTrimmedOnlyWhenItIsAnotherInstances) {
  const PointCloud side = box(Vec3(0.975, 0.105, 0.205), 20, 2);  // +x face of the next chair
  PointCloud joined = box(Vec3(0.505, 0.105, 0.205), 20);
  for (std::size_t i = 0; i < side.size(); ++i) joined.push_back(side.points[i], side.colors[i]);
  for (bool neighbour : {false, true}) {
    ObjectMap map(parts_options());
    for (int f = 0; f < 6; ++f) map.add_frame({instance(f, 1, "chair", joined)});
    if (neighbour)
      for (int f = 10; f < 16; ++f)
        map.add_frame({instance(f, 2, "chair", box(Vec3(0.975, 0.105, 0.205), 20))});
    const auto cuts = map.split_oversize(Vec3::UnitZ(), {});
    EXPECT_EQ(cuts.size(), neighbour ? 1u : 0u);
    const auto records = map.records(RecordOptions{});
    ASSERT_EQ(records.size(), neighbour ? 2u : 1u);
    EXPECT_NEAR(parts_width_x(records[0]), neighbour ? 0.40 : 0.88, 0.02);
  }
}

// Points 1 cm apart filling the box lo-hi.
PointCloud parts_slab(const Vec3& lo, const Vec3& hi) {
  PointCloud c;
  const Eigen::Vector3i n = ((hi - lo) / 0.01).array().round().cast<int>();
  for (int i = 0; i <= n.x(); ++i)
    for (int j = 0; j <= n.y(); ++j)
      for (int k = 0; k <= n.z(); ++k)
        c.push_back((lo + 0.01 * Vec3(i, j, k)).cast<float>(), Rgb{40, 40, 40});
  return c;
}

// A monitor (0.50 m wide, 5 cm deep, 0.35 m tall, its bottom 0.93 m up) called "tv" in 6
// keyframes, and its domed foot (0.30 x 0.16 m, 5 cm high, on a desk at 0.78 m) called "mouse" in
// 6 others: too wide for a mouse (0.14 m), nothing flat to trim and no other name, its middle
// under the monitor, 10 cm below it (the stand's neck unseen). The foot joins the monitor; not with
// join_under off, nor when it lies 0.6 m aside.
TEST(ObjectMap, AMonitorsFootTooWideForAMouseJoinsTheMonitorAboveIt) {
  const PointCloud screen = parts_slab(Vec3(0.25, 0.975, 0.93), Vec3(0.75, 1.025, 1.28));
  const auto fused = [&](bool join_under, double foot_x, std::vector<MergeLink>* joins) {
    ObjectMapOptions options = parts_options();
    options.oversize.join_under = join_under;
    ObjectMap map(options);
    for (int f = 0; f < 6; ++f) map.add_frame({instance(f, 1, "tv", screen)});
    PointCloud foot;  // domed: 0.78 m at its rim, 0.83 m in the middle
    for (int i = -15; i <= 15; ++i)
      for (int j = -8; j <= 8; ++j) {
        const double rim = std::max(std::abs(i) / 15.0, std::abs(j) / 8.0);
        foot.push_back(Vec3f(static_cast<float>(foot_x + 0.01 * i), 1.0f + 0.01f * j,
                             static_cast<float>(0.78 + 0.05 * (1.0 - rim * rim))),
                       Rgb{40, 40, 40});
      }
    for (int f = 10; f < 16; ++f) map.add_frame({instance(f, 2, "mouse", foot)});
    EXPECT_TRUE(map.split_oversize(Vec3::UnitZ(), {}).empty());  // nothing to cut
    *joins = map.join_parts(Vec3::UnitZ(), {});
    return map.records(RecordOptions{});
  };
  std::vector<MergeLink> joins;
  auto records = fused(true, 0.5, &joins);
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].class_name, "tv");
  // Its points lie beyond eq 18's bound around the monitor's: the box stays the screen's.
  EXPECT_NEAR(records[0].aabb.min.z(), 0.93, 0.02);
  EXPECT_NEAR(records[0].position.x(), 0.5, 0.01);
  ASSERT_EQ(joins.size(), 1u);
  EXPECT_TRUE(joins[0].part);
  EXPECT_EQ(joins[0].into, records[0].id);
  for (const auto& [under, x] : {std::pair{false, 0.5}, std::pair{true, 1.1}}) {
    records = fused(under, x, &joins);
    EXPECT_TRUE(joins.empty()) << under << " " << x;
    ASSERT_EQ(records.size(), 2u) << under << " " << x;
    EXPECT_EQ(records[1].class_name, "mouse");
  }
}

// objmap follow's publishes run the rules on copies of the live map; a copy shares each object's
// memo (surface points, content hash) with the live map until either changes. The rules on such
// copies give what they give on a map made afresh from the same frames, as the back joins the seat
// and is then seen again further along after its memo was filled.
TEST(ObjectMap, RulesOnCopiesOfAGrowingMapAreThoseOfAMapMadeAfresh) {
  std::vector<std::vector<Observation>> frames;
  for (int f = 0; f < 6; ++f) frames.push_back({instance(f, 1, "chair", parts_seat())});
  for (int f = 10; f < 16; ++f) frames.push_back({instance(f, 2, "chair", parts_back())});
  for (int f = 20; f < 26; ++f) frames.push_back({instance(f, 2, "chair", parts_back(0.605))});
  ObjectMapOptions o;  // every merge rule on
  ObjectMap live(o);
  live.set_pair_cache(std::make_shared<PairCache>());
  const auto rules = [](ObjectMap& map) {
    std::vector<MergeLink> links = map.merge_pass();
    for (const MergeLink& l : map.join_parts(Vec3::UnitZ(), {})) links.push_back(l);
    return links;
  };
  std::size_t joined = 0;
  for (std::size_t n = 0; n < frames.size(); ++n) {
    live.add_frame(frames[n]);
    ObjectMap published = live;
    ObjectMap fresh(o);
    for (std::size_t k = 0; k <= n; ++k) fresh.add_frame(frames[k]);
    const std::vector<MergeLink> a = rules(published), b = rules(fresh);
    ASSERT_EQ(a.size(), b.size()) << n;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].into, b[i].into) << n;
      EXPECT_EQ(a[i].absorbed, b[i].absorbed) << n;
      EXPECT_EQ(a[i].overlap, b[i].overlap) << n;  // the share inside: from the surfaces
      EXPECT_EQ(a[i].distance_m, b[i].distance_m) << n;
    }
    joined += a.size();
    const auto ra = published.records(RecordOptions{}), rb = fresh.records(RecordOptions{});
    ASSERT_EQ(ra.size(), rb.size()) << n;
    for (std::size_t i = 0; i < ra.size(); ++i) {
      EXPECT_EQ(ra[i].centroid, rb[i].centroid) << n;
      EXPECT_EQ(ra[i].aabb.min, rb[i].aabb.min) << n;
      EXPECT_EQ(ra[i].aabb.max, rb[i].aabb.max) << n;
    }
  }
  EXPECT_GT(joined, 0u);
}

}  // namespace
}  // namespace objmap::fusion

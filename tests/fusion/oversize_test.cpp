// The extent of one instance: objects wider than their class allows are cut (fusion/oversize.h,
// ObjectMap::split_oversize).
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "fusion_test_util.h"
#include "objmap/core/error.h"
#include "objmap/fusion/object_map.h"
#include "objmap/fusion/oversize.h"
#include "objmap/segmentation/class_sizes.h"

namespace objmap::fusion {
namespace {

using test::box;
using test::instance;

PointCloud oversize_joined(const std::vector<PointCloud>& parts) {
  PointCloud all;
  for (const PointCloud& p : parts)
    for (std::size_t i = 0; i < p.size(); ++i)
      all.push_back(p.points[i], p.colors.empty() ? Rgb{200, 100, 50} : p.colors[i]);
  return all;
}

double oversize_width_x(const ObjectRecord& r) { return r.aabb.max.x() - r.aabb.min.x(); }

std::vector<Vec3> oversize_points(const PointCloud& cloud) {
  std::vector<Vec3> out;
  for (const Vec3f& p : cloud.points) out.push_back(p.cast<double>());
  return out;
}

TEST(Oversize, TheExtentIsTheLongHorizontalAxisWhateverTheWorldFrame) {
  // A 0.41 x 0.41 x 0.41 m box: its horizontal extent is its side (its diagonal's quantiles
  // would be wider), with up along any axis.
  const std::vector<Vec3> cube = oversize_points(box(Vec3(0.005, 0.005, 0.005), 20));
  for (const Vec3& up : {Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(1, 0, 0)})
    EXPECT_NEAR(horizontal_extent(cube, up, 0.0), 0.40, 0.07) << up.transpose();
  // Two such boxes 6 cm apart along x, up +z: 0.88 m along x; with up +x, their horizontal
  // extent is one box's side.
  std::vector<Vec3> two = cube;
  for (const Vec3& p : cube) two.push_back(p + Vec3(0.47, 0, 0));
  Vec3 axis;
  EXPECT_NEAR(horizontal_extent(two, Vec3::UnitZ(), 0.0, &axis), 0.87, 0.01);
  EXPECT_NEAR(std::fabs(axis.x()), 1.0, 1e-6);
  EXPECT_NEAR(horizontal_extent(two, Vec3::UnitX(), 0.0), 0.40, 0.07);
}

TEST(Oversize, TheCutGoesThroughTheGapBetweenTwoChairs) {
  const std::vector<Vec3> a = oversize_points(box(Vec3(0.505, 0.105, 0.505), 20));
  std::vector<Vec3> two = a;
  for (const Vec3& p : a) two.push_back(p + Vec3(0.47, 0, 0));  // 6 cm gap at x 0.715-0.765
  OversizeOptions options;
  const auto cut = plan_oversize_cut(two, Vec3::UnitZ(), 0.4, 0.7, options);
  ASSERT_TRUE(cut.has_value());
  EXPECT_NEAR(cut->limit_m, 0.805, 1e-9);
  EXPECT_GT(cut->extent_m, 0.8);
  EXPECT_GT(cut->axis.x() * cut->cut, 0.715);
  EXPECT_LT(cut->axis.x() * cut->cut, 0.765);
  EXPECT_TRUE(cut->apart);  // a valley between two halves: two instances
  // One chair is not cut; neither are the two as a table; nor with the rule off.
  EXPECT_FALSE(plan_oversize_cut(a, Vec3::UnitZ(), 0.4, 0.7, options).has_value());
  EXPECT_FALSE(plan_oversize_cut(two, Vec3::UnitZ(), 0.5, 4.0, options).has_value());
  options.enabled = false;
  EXPECT_FALSE(plan_oversize_cut(two, Vec3::UnitZ(), 0.4, 0.7, options).has_value());
}

TEST(Oversize, OneInstanceWhosePartBeyondTheCutIsTallIsNotCut) {
  // A monitor's screen (0.66 m wide, 0.40 m tall, no gap) that the detector named "laptop"
  // (largest 0.5 m): what lies beyond the cut is as tall as the rest, no strip of the table, so
  // the object is left whole rather than trimmed to a laptop's width.
  std::vector<Vec3> screen;
  for (int i = 0; i <= 66; ++i)
    for (int k = 0; k <= 40; ++k) screen.push_back(Vec3(0.01 * i, 0.0, 0.8 + 0.01 * k));
  EXPECT_FALSE(plan_oversize_cut(screen, Vec3::UnitZ(), 0.25, 0.5, OversizeOptions{}).has_value());
}

// Parts of one instance seen apart (ObjectMap::join_parts, join_continuous): a 2 m couch's two
// views, each its nearer 1.2 m, overlap in the middle, where each saw it aslant (together half the
// density): one surface. Two chairs 6 cm apart: an empty band between them. Two halves of a couch
// with a 5 cm band cut out of the middle: two objects side by side.
TEST(Oversize, PartsAreOneSurfaceUnlessAnEmptyBandLiesBetweenThem) {
  const auto strip = [](double x0, double x1, double every_m, int height_step = 1) {
    std::vector<Vec3> out;
    for (double x = x0; x <= x1 + 1e-9; x += every_m)
      for (int k = 0; k <= 40; k += height_step) out.push_back(Vec3(x, 0.0, 0.01 * k));
    return out;
  };
  std::vector<Vec3> left = strip(0.0, 0.8, 0.01), right = strip(1.2, 2.0, 0.01);
  // The middle, seen aslant by both: each a quarter of the density, together half.
  for (const Vec3& p : strip(0.805, 1.195, 0.02, 2)) {
    left.push_back(p);
    right.push_back(p);
  }
  OversizeOptions options;
  EXPECT_TRUE(continuous_parts(left, right, Vec3::UnitZ(), options));
  EXPECT_TRUE(continuous_parts(right, left, Vec3::UnitZ(), options));
  // A 5 cm empty band at x 0.975-1.025: two couches side by side.
  const auto without_band = [](std::vector<Vec3> part) {
    part.erase(std::remove_if(part.begin(), part.end(),
                              [](const Vec3& p) { return p.x() > 0.975 && p.x() < 1.025; }),
               part.end());
    return part;
  };
  EXPECT_FALSE(continuous_parts(without_band(left), without_band(right), Vec3::UnitZ(), options));
  // Two chairs (0.41 m boxes) 6 cm apart.
  const std::vector<Vec3> a = oversize_points(box(Vec3(0.505, 0.105, 0.505), 20));
  std::vector<Vec3> b;
  for (const Vec3& p : a) b.push_back(p + Vec3(0.47, 0, 0));
  EXPECT_FALSE(continuous_parts(a, b, Vec3::UnitZ(), options));
  // With a valley ratio of 0.8 the aslant middle is a gap too (half the sides' density; each
  // side's mean holds some of the middle).
  options.join_valley_ratio = 0.8;
  EXPECT_FALSE(continuous_parts(left, right, Vec3::UnitZ(), options));
}

TEST(Oversize, OptionsAreChecked) {
  OversizeOptions o;
  o.margin = -0.1;
  EXPECT_THROW(o.check(), InputError);
  o = {};
  o.bin_m = 0.0;
  EXPECT_THROW(o.check(), InputError);
  o = {};
  o.percentile = 0.5;
  EXPECT_THROW(o.check(), InputError);
  o = {};
  o.join_valley_ratio = 1.5;
  EXPECT_THROW(o.check(), InputError);
  o = {};
  o.under_gap_m = -0.01;
  EXPECT_THROW(o.check(), InputError);
  EXPECT_NO_THROW(OversizeOptions{}.check());
}

// `n` chairs (0.41 m boxes) packed 6 cm apart along x, one track id for all of them: each
// keyframe's mask covers all of them (a detector's one mask over packed chairs) or, now and then,
// one chair. One object 0.9-1.4 m wide without the rule; one object per chair with it.
std::vector<ObjectRecord> oversize_packed_chairs(int n, bool rule, std::vector<SplitLink>* cuts) {
  std::vector<PointCloud> chairs;
  for (int k = 0; k < n; ++k) chairs.push_back(box(Vec3(0.505 + 0.47 * k, 0.105, 0.505), 20));
  ObjectMapOptions options;
  options.oversize.enabled = rule;
  ObjectMap map(options);
  for (int f = 0; f < 12; ++f) {
    const PointCloud seen = f % 4 == 3 ? chairs[f % n] : oversize_joined(chairs);
    EXPECT_EQ(map.add_frame({instance(f, 1, "chair", seen)}).front().object_id, 0);
  }
  map.merge_pass();
  map.split_pass();
  const std::vector<SplitLink> made = map.split_oversize(Vec3::UnitZ(), {});
  if (cuts) *cuts = made;
  EXPECT_TRUE(map.split_oversize(Vec3::UnitZ(), {}).empty());  // nothing is left too wide
  return map.records(RecordOptions{});
}

TEST(ObjectMap, OneMaskOverTwoOrThreePackedChairsIsCutIntoOneObjectPerChair) {
  for (int n : {2, 3}) {
    const auto joined = oversize_packed_chairs(n, false, nullptr);
    ASSERT_EQ(joined.size(), 1u);
    EXPECT_GT(oversize_width_x(joined[0]), 0.85);
    std::vector<SplitLink> cuts;
    const auto apart = oversize_packed_chairs(n, true, &cuts);
    EXPECT_EQ(cuts.size(), static_cast<std::size_t>(n - 1));
    ASSERT_EQ(apart.size(), static_cast<std::size_t>(n)) << n << " chairs";
    std::vector<double> xs;
    for (const ObjectRecord& r : apart) {
      EXPECT_LT(oversize_width_x(r), 0.45) << r.id;
      EXPECT_EQ(r.class_name, "chair");
      EXPECT_GE(r.views, 3) << r.id;  // the masks over all of them are every part's observations
      xs.push_back(r.position.x());
    }
    std::sort(xs.begin(), xs.end());
    for (int k = 0; k < n; ++k) EXPECT_NEAR(xs[k], 0.505 + 0.47 * k, 0.02) << n << " chairs";
  }
}

// A mouse (a 6 x 10 x 3 cm box) whose box masks also held a strip of the desk beside it, 30 cm
// long, seen in every observation: no valley between two instances, so the strip is cut off and
// the mouse stays one object, its position on the mouse.
TEST(ObjectMap, AnObjectWithAStripAttachedIsTrimmedNotSplit) {
  PointCloud mouse;
  for (int i = -3; i <= 3; ++i)
    for (int j = -5; j <= 5; ++j)
      for (int k = 0; k <= 3; ++k) mouse.push_back(Vec3f(0.5f + 0.01f * i, 0.01f * j, 0.01f * k));
  PointCloud strip;
  for (int i = 4; i <= 33; ++i)
    for (int j = -5; j <= 5; ++j) strip.push_back(Vec3f(0.5f + 0.01f * i, 0.01f * j, 0.0f));
  const auto cut = plan_oversize_cut(oversize_points(oversize_joined({mouse, strip})),
                                     Vec3::UnitZ(), 0.05, 0.14, OversizeOptions{});
  ASSERT_TRUE(cut.has_value());
  EXPECT_FALSE(cut->apart);
  ObjectMap map;
  for (int f = 0; f < 6; ++f)
    map.add_frame({instance(f, 1, "mouse", oversize_joined({mouse, strip}))});
  EXPECT_FALSE(map.split_oversize(Vec3::UnitZ(), {}).empty());
  const auto records = map.records(RecordOptions{});
  ASSERT_EQ(records.size(), 1u);
  EXPECT_LT(oversize_width_x(records[0]), 0.14 * 1.15);
  EXPECT_LT(std::fabs(records[0].position.x() - 0.5), 0.04);
}

TEST(ObjectMap, AMonitorCalledLaptopTooWideForALaptopIsNamedAfterItsOtherVote) {
  // A monitor's screen (0.66 m wide, 0.40 m tall, 3 cm deep) that the detector called "laptop" in
  // 7 keyframes (largest 0.5 m) and "tv" in 6: one instance with nothing to trim, named after the
  // class of its votes that admits its width; with too few "tv" votes or the rule off it keeps
  // its vote, uncut.
  PointCloud screen;
  for (int i = 0; i <= 66; ++i)
    for (int k = 0; k <= 40; ++k)
      for (int d = 0; d <= 3; ++d) screen.push_back(Vec3f(0.01f * i, 0.01f * d, 0.8f + 0.01f * k));
  const auto fused = [&](int tv_frames, bool rename, std::vector<ClassRename>* renamed) {
    ObjectMapOptions options;
    options.oversize.rename = rename;
    ObjectMap map(options);
    for (int f = 0; f < 7 + tv_frames; ++f)
      map.add_frame({instance(f, 1, f < 7 ? "laptop" : "tv", screen)});
    EXPECT_TRUE(map.split_oversize(Vec3::UnitZ(), {}, renamed).empty());  // nothing cut
    const auto records = map.records(RecordOptions{});
    EXPECT_EQ(records.size(), 1u);
    EXPECT_GT(oversize_width_x(records[0]), 0.6);
    return records.empty() ? std::string() : records[0].class_name;
  };
  std::vector<ClassRename> renamed;
  EXPECT_EQ(fused(6, true, &renamed), "tv");
  ASSERT_EQ(renamed.size(), 1u);
  EXPECT_EQ(renamed[0].from, "laptop");
  EXPECT_EQ(renamed[0].to, "tv");
  EXPECT_NEAR(renamed[0].extent_m, 0.66, 0.03);
  EXPECT_EQ(fused(6, false, nullptr), "laptop");
  EXPECT_EQ(fused(2, true, nullptr), "laptop");  // 2 of 7: below the 0.3 share
}

TEST(ObjectMap, AClassWithoutASizeOrWideEnoughIsNotCut) {
  const PointCloud a = box(Vec3(0.505, 0.105, 0.505), 20);
  const PointCloud b = box(Vec3(0.975, 0.105, 0.505), 20);
  for (const char* cls : {"dining table", "009 gelatin box"}) {
    ObjectMap map;
    for (int f = 0; f < 6; ++f) map.add_frame({instance(f, 1, cls, oversize_joined({a, b}))});
    EXPECT_TRUE(map.split_oversize(Vec3::UnitZ(), {}).empty()) << cls;
    EXPECT_EQ(map.records(RecordOptions{}).size(), 1u);
  }
  // --class-sizes none: no class has a size.
  ObjectMap map;
  for (int f = 0; f < 6; ++f) map.add_frame({instance(f, 1, "chair", oversize_joined({a, b}))});
  EXPECT_TRUE(map.split_oversize(Vec3::UnitZ(), segmentation::ClassSizes::none()).empty());
}

TEST(ClassSizes, TheBuiltInTableHasEveryCocoClassAndAFileAddsOrReplaces) {
  const segmentation::ClassSizes sizes;
  EXPECT_EQ(sizes.table().size(), 80u);
  ASSERT_TRUE(sizes.find("Chair").has_value());
  EXPECT_DOUBLE_EQ(sizes.find("chair")->max_m, 0.7);
  EXPECT_TRUE(sizes.find("tvmonitor").has_value());  // any spelling canonical_class accepts
  EXPECT_TRUE(sizes.find("sofa").has_value());
  EXPECT_FALSE(sizes.find("009_gelatin_box").has_value());
  segmentation::ClassSizes mine;
  mine.update(
      nlohmann::json::parse(
          R"({"sizes": {"009_gelatin_box": [0.03, 0.1], "chair": [0.4, 0.9], "cup": null}})"),
      "sizes.json");
  EXPECT_DOUBLE_EQ(mine.find("009 gelatin box")->max_m, 0.1);
  EXPECT_DOUBLE_EQ(mine.find("chair")->max_m, 0.9);
  EXPECT_FALSE(mine.find("cup").has_value());
  for (const char* bad : {R"({"sizes": {"chair": [0.9, 0.4]}})", R"({"sizes": {"chair": 0.7}})",
                          R"({"sizes": {"chair": [0, 0.7]}})", R"({"size": {}})"}) {
    try {
      mine.update(nlohmann::json::parse(bad), "sizes.json");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("sizes.json", 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace objmap::fusion

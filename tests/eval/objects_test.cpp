// objmap eval objects: Hungarian assignment, oriented-box IoU, ground-truth readers, the tables on
// hand-made files with known errors, bad input, and the CLI end to end on a small synthetic scene.
#include "objmap/eval/objects.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>

#include "eval_test_util.h"
#include "objmap/core/error.h"
#include "objmap/io/trajectory.h"
#include "support/schema_check.h"
#include "support/test_support.h"

namespace objmap::eval {
namespace {

using objmap::test::assignment_cost;
using objmap::test::read_text;
using objmap::test::run_objmap;
using objmap::test::TempDir;
using objmap::test::write_text;
namespace fs = std::filesystem;

constexpr double kInf = std::numeric_limits<double>::infinity();
using test::kPi;

bool mentions(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

// ---- Hungarian
// ----------------------------------------------------------------------------------

TEST(Hungarian, BeatsGreedyOnTwoByTwo) {
  // Greedy takes (0,0) = 1 first and is left with (1,1) = 100: 101. Optimum: 2 + 2 = 4.
  Eigen::MatrixXd cost(2, 2);
  cost << 1, 2, 2, 100;
  EXPECT_EQ(hungarian_assign(cost), (std::vector<int>{1, 0}));
}

TEST(Hungarian, ThreeByThreeKnownOptimum) {
  Eigen::MatrixXd cost(3, 3);
  cost << 4, 1, 3,  //
      2, 0, 5,      //
      3, 2, 2;
  // Optimal: row0→1 (1), row1→0 (2), row2→2 (2) = 5; greedy takes (1,1) = 0 first → 0 + 3 + 3 = 6.
  const std::vector<int> a = hungarian_assign(cost);
  EXPECT_EQ(a, (std::vector<int>{1, 0, 2}));
  EXPECT_DOUBLE_EQ(assignment_cost(cost, a), 5.0);
}

TEST(Hungarian, RectangularBothWays) {
  Eigen::MatrixXd wide(2, 3);
  wide << 5, 1, 9,  //
      1, 2, 9;
  EXPECT_EQ(hungarian_assign(wide), (std::vector<int>{1, 0}));
  const Eigen::MatrixXd tall = wide.transpose();
  EXPECT_EQ(hungarian_assign(tall), (std::vector<int>{1, 0, -1}));
}

TEST(Hungarian, ForbiddenPairsMaximiseTheMatchedCountFirst) {
  // Gate case: a–1 0.05, a–2 0.10, b–1 0.08, b–2 forbidden (over the gate). Greedy (and plain
  // min-cost) takes a–1 and leaves b alone; the optimum matches both: a–2, b–1.
  Eigen::MatrixXd cost(2, 2);
  cost << 0.05, 0.10, 0.08, kInf;
  EXPECT_EQ(hungarian_assign(cost), (std::vector<int>{1, 0}));
  // All forbidden, empty.
  Eigen::MatrixXd none(2, 2);
  none << kInf, kInf, kInf, kInf;
  EXPECT_EQ(hungarian_assign(none), (std::vector<int>{-1, -1}));
  EXPECT_TRUE(hungarian_assign(Eigen::MatrixXd(0, 3)).empty());
  EXPECT_EQ(hungarian_assign(Eigen::MatrixXd(2, 0)), (std::vector<int>{-1, -1}));
}

TEST(Hungarian, MatchesBruteForceOnRandomMatrices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 10.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + trial % 6;
    Eigen::MatrixXd cost(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) cost(i, j) = uniform(rng);
    std::vector<int> perm(n);
    std::iota(perm.begin(), perm.end(), 0);
    double best = kInf;
    do best = std::min(best, assignment_cost(cost, perm));
    while (std::next_permutation(perm.begin(), perm.end()));
    const std::vector<int> a = hungarian_assign(cost);
    std::vector<int> sorted = a;
    std::sort(sorted.begin(), sorted.end());
    std::vector<int> expected(n);
    std::iota(expected.begin(), expected.end(), 0);
    ASSERT_EQ(sorted, expected) << "not a permutation, trial " << trial;
    EXPECT_NEAR(assignment_cost(cost, a), best, 1e-9) << "trial " << trial;
  }
}

// ---- oriented-box IoU
// ---------------------------------------------------------------------------

Obb box(const Vec3& center, const Vec3& half, double yaw = 0.0) {
  Obb b;
  b.center = center;
  b.half_extent = half;
  b.rotation = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  return b;
}

TEST(ObbIou, KnownValues) {
  const Obb unit = box({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5});
  EXPECT_NEAR(obb_iou(unit, unit), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(obb_iou(unit, box({3, 0, 0}, {0.5, 0.5, 0.5})), 0.0);
  // Disjoint but within the bounding spheres: touching along x after a 45° turn would overlap; this
  // pair is 1.2 m apart on x with half sizes 0.5: no overlap.
  EXPECT_NEAR(obb_iou(unit, box({1.7, 0.5, 0.5}, {0.5, 0.5, 0.5}, 0.3)), 0.0, 1e-12);
  // Axis-aligned half overlap: intersection 0.5, union 1.5.
  EXPECT_NEAR(obb_iou(unit, box({1.0, 0.5, 0.5}, {0.5, 0.5, 0.5})), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(obb_intersection_volume(unit, box({1.0, 0.5, 0.5}, {0.5, 0.5, 0.5})), 0.5, 1e-12);
  // A cube turned 45° about z against itself: the cross-section is a regular octagon of area
  // 2(√2 − 1); IoU = 2(√2 − 1) / (2 − 2(√2 − 1)) = 1/√2.
  const Obb turned = box({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, kPi / 4);
  EXPECT_NEAR(obb_intersection_volume(unit, turned), 2 * (std::sqrt(2.0) - 1), 1e-12);
  EXPECT_NEAR(obb_iou(unit, turned), 1 / std::sqrt(2.0), 1e-12);
  // Nested: a box inside another, IoU = volume ratio.
  EXPECT_NEAR(obb_iou(box({0, 0, 0}, {1, 1, 1}), box({0.1, 0, 0}, {0.5, 0.5, 0.5}, 0.7)), 1.0 / 8,
              1e-12);
  // Degenerate (flat) box: no volume, IoU 0.
  EXPECT_DOUBLE_EQ(obb_iou(unit, box({0.5, 0.5, 0.5}, {0.5, 0.5, 0.0})), 0.0);
}

TEST(ObbIou, SameOrientationIsTheProductOfTheOverlaps) {
  // Boxes with one common (random) rotation: the intersection is a box whose sides are the
  // overlaps along each axis; includes coplanar faces, touching and nested boxes.
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> step(-4, 4);
  const Eigen::Matrix3d r = Eigen::Quaterniond(0.3, -0.5, 0.2, 0.7).normalized().toRotationMatrix();
  for (int trial = 0; trial < 300; ++trial) {
    Vec3 lo_a, hi_a, lo_b, hi_b;  // in the boxes' own frame, on a 0.1 grid: many coplanar faces
    for (int k = 0; k < 3; ++k) {
      lo_a[k] = 0.1 * step(rng);
      hi_a[k] = lo_a[k] + 0.1 * (1 + std::abs(step(rng)));
      lo_b[k] = 0.1 * step(rng);
      hi_b[k] = lo_b[k] + 0.1 * (1 + std::abs(step(rng)));
    }
    const auto make = [&](const Vec3& lo, const Vec3& hi) {
      Obb b;
      b.rotation = r;
      b.center = Vec3(0.3, -0.2, 1.0) + r * (0.5 * (lo + hi));
      b.half_extent = 0.5 * (hi - lo);
      return b;
    };
    double expected = 1.0;
    for (int k = 0; k < 3; ++k)
      expected *= std::max(0.0, std::min(hi_a[k], hi_b[k]) - std::max(lo_a[k], lo_b[k]));
    EXPECT_NEAR(obb_intersection_volume(make(lo_a, hi_a), make(lo_b, hi_b)), expected, 1e-9)
        << "trial " << trial;
  }
}

TEST(ObbIou, AgreesWithMonteCarloOnGeneralBoxes) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    Obb a, b;
    a.center = Vec3(u(rng), u(rng), u(rng)) * 0.2;
    b.center = Vec3(u(rng), u(rng), u(rng)) * 0.2;
    a.half_extent = Vec3(0.3 + 0.2 * u(rng), 0.3 + 0.2 * u(rng), 0.3 + 0.2 * u(rng));
    b.half_extent = Vec3(0.3 + 0.2 * u(rng), 0.3 + 0.2 * u(rng), 0.3 + 0.2 * u(rng));
    a.rotation = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    b.rotation = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    // Sample box a uniformly; the share inside b is intersection / volume(a).
    const int n = 200000;
    int inside = 0;
    for (int k = 0; k < n; ++k) {
      const Vec3 local(u(rng) * a.half_extent.x(), u(rng) * a.half_extent.y(),
                       u(rng) * a.half_extent.z());
      inside += b.contains(a.center + a.rotation * local) ? 1 : 0;
    }
    const double sampled = obb_volume(a) * inside / n;
    const double exact = obb_intersection_volume(a, b);
    EXPECT_NEAR(exact, sampled, 0.01 * obb_volume(a)) << "trial " << trial;
    EXPECT_NEAR(exact, obb_intersection_volume(b, a), 1e-12) << "symmetric";
  }
}

// ---- ground-truth readers
// -----------------------------------------------------------------------

TEST(ObjectsGt, ReadsTheFr3CabinetCuboid) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr3_cabinet_58kf");
  const auto objects = read_objects_gt(dir / "objects_gt.txt");
  ASSERT_EQ(objects.size(), 1u);
  const ReferenceObject& o = objects[0];
  EXPECT_EQ(o.id, 1);
  EXPECT_EQ(o.class_name, "object");
  EXPECT_TRUE(o.centroid.isApprox(Vec3(-1.52988, 0.456476, 0.281575)));
  EXPECT_TRUE(o.obb.center.isApprox(o.centroid));
  EXPECT_TRUE(o.obb.half_extent.isApprox(Vec3(0.396318, 0.222742, 0.272709)));
  EXPECT_NEAR(o.obb.rotation(0, 0), std::cos(3.10232), 1e-12);
  EXPECT_NEAR(o.obb.rotation(1, 0), std::sin(3.10232), 1e-12);
  EXPECT_NEAR(o.obb.rotation(2, 2), 1.0, 1e-12);
  EXPECT_EQ(read_objects_gt(dir / "objects_gt.txt", "cabinet")[0].class_name, "cabinet");
}

TEST(ObjectsGt, ReadsTheYcbvPositionList) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f");
  const auto objects = read_objects_gt(dir / "objects_gt.txt");
  ASSERT_EQ(objects.size(), 3u);
  EXPECT_EQ(objects[0].id, 8);
  EXPECT_EQ(objects[0].class_name, "009 gelatin box");
  EXPECT_TRUE(objects[0].centroid.isApprox(Vec3(-0.08726, 0.01807, 0.03214)));
  EXPECT_EQ(objects[0].obb.half_extent, Vec3::Zero());  // a position, no extent
  EXPECT_EQ(objects[2].class_name, "061 foam brick");
}

TEST(ObjectsGt, ReadsJsonAndRejectsBadFiles) {
  TempDir tmp;
  write_text(tmp / "gt.json",
             R"(  {"objects":[{"id":3,"class":"cup","centroid":[1,2,3],
                 "obb":{"center":[1,2,3.5],"rotation":[0,-1,0, 1,0,0, 0,0,1],
                        "half_extent":[0.1,0.2,0.3]}}]})");
  const auto objects = read_objects_gt(tmp / "gt.json");
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].id, 3);
  EXPECT_EQ(objects[0].class_name, "cup");
  EXPECT_TRUE(objects[0].centroid.isApprox(Vec3(1, 2, 3)));
  EXPECT_DOUBLE_EQ(objects[0].obb.rotation(0, 1), -1.0);  // row-major
  EXPECT_DOUBLE_EQ(objects[0].obb.rotation(1, 0), 1.0);

  const auto message = [&](const std::string& name, const std::string& text) -> std::string {
    write_text(tmp / name, text);
    try {
      read_objects_gt(tmp / name);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_TRUE(mentions(message("a.json", "{\"objects\": [}"), "a.json: malformed JSON"));
  EXPECT_TRUE(
      mentions(message("b.json", R"({"objects":[{"id":1,"class":"cup","centroid":[1,2]}]})"),
               "b.json: objects[0].centroid: expected an array of 3 numbers"));
  EXPECT_TRUE(
      mentions(message("c.json", R"({"objects":[{"id":1,"class":"cup","centroid":[1,2,3]}]})"),
               "missing field 'obb'"));
  EXPECT_TRUE(mentions(message("d.txt", "# cuboid\n1 2 3 0.5 0.1 0.2\n"),
                       "d.txt:2: 6 fields; expected 7: x y z yaw half_x half_y half_z"));
  EXPECT_TRUE(mentions(message("e.txt", "1 2 3 0.5 0.1 0.2 abc\n"), "e.txt:1"));
  EXPECT_TRUE(mentions(message("f.txt", "# nothing\n"), "f.txt: no cuboid"));
  EXPECT_TRUE(
      mentions(message("g.txt", "1 2 3 0 0.1 -0.2 0.3\n"), "g.txt:1: negative half extent"));
  // The id of a position line was a double cast to int (undefined for 1e300: UBSan
  // float-cast-overflow in the fuzz build, fuzz_objects_gt); it is an integer now.
  EXPECT_TRUE(mentions(message("h.txt", "1e300 009_gelatin_box 1 2 3\n"),
                       "h.txt:1: id is '1e300'; expected an integer"));
  EXPECT_TRUE(mentions(message("i.txt", "3000000000 mug 1 2 3\n"),
                       "i.txt:1: id 3000000000; expected an int"));
  try {
    read_objects_gt(tmp / "missing.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_TRUE(mentions(e.what(), "missing.json: cannot open")) << e.what();
  }
}

// ---- the tables on hand-made maps
// ---------------------------------------------------------------

io::MappedObject mapped(int id, const std::string& cls, const Vec3& c, const Vec3& half) {
  io::MappedObject o;
  o.id = id;
  o.class_name = cls;
  o.centroid = c;
  o.position = c;
  o.obb.center = c;
  o.obb.half_extent = half;
  return o;
}

ReferenceObject ref(int id, const std::string& cls, const Vec3& c, const Vec3& half) {
  ReferenceObject o;
  o.id = id;
  o.class_name = cls;
  o.centroid = c;
  o.position = c;
  o.obb.center = c;
  o.obb.half_extent = half;
  return o;
}

TEST(EvaluateObjects, PositionsAreScoredAgainstTheTrueBoxCentre) {
  // A chair whose volume centroid (seat and back) lies 12 cm above its box centre, as objmap
  // synth's: the map object's centroid is near the volume centroid, its position near the box
  // centre. distance_m is the paper's centroid measure, position_distance_m objmap's.
  TempDir tmp;
  write_text(tmp / "gt.json",
             R"({"objects":[{"id":1,"class":"chair","centroid":[1,2,0.57],
                 "obb":{"center":[1,2,0.45],"rotation":[1,0,0, 0,1,0, 0,0,1],
                        "half_extent":[0.25,0.25,0.45]}}]})");
  const auto gt = read_objects_gt(tmp / "gt.json");
  ASSERT_EQ(gt.size(), 1u);
  EXPECT_TRUE(gt[0].position.isApprox(Vec3(1, 2, 0.45)));
  io::MappedObject chair = mapped(7, "chair", {1, 2, 0.6}, Vec3(0.25, 0.25, 0.45));
  chair.position = Vec3(1.03, 2, 0.49);
  const ObjectEvalResult r = evaluate_objects({chair}, gt, ObjectEvalOptions{});
  ASSERT_EQ(r.matches.size(), 1u);
  EXPECT_NEAR(r.matches[0].distance_m, 0.03, 1e-12);
  EXPECT_NEAR(r.matches[0].position_distance_m, 0.05, 1e-12);
  EXPECT_NEAR(r.errors.back().position_distance_m.mean, 0.05, 1e-12);
  // A fr3_cabinet-style cuboid: its position is its centre.
  write_text(tmp / "cuboid.txt", "1 2 0.3 0.0 0.4 0.2 0.3\n");
  EXPECT_TRUE(read_objects_gt(tmp / "cuboid.txt")[0].position.isApprox(Vec3(1, 2, 0.3)));
}

TEST(EvaluateObjects, KnownCountsErrorsAndPrecisionRecall) {
  const Vec3 h(0.05, 0.05, 0.05);
  // Ground truth: cups 1 (0,0,0), 2 (0.2,0,0); chair 3 (1,1,0); book 4 (5,5,5).
  const std::vector<ReferenceObject> gt = {
      ref(1, "cup", {0, 0, 0}, h), ref(2, "cup", {0.2, 0, 0}, h), ref(3, "chair", {1, 1, 0}, h),
      ref(4, "book", {5, 5, 5}, h)};
  // Map: cup 10 at 0.06 from gt 1 and 0.14 from gt 2, cup 11 at 0.08 from gt 1 (gt 2 is
  // 0.2154 away): greedy would pair 10–1 and then 11–2; Hungarian pairs 10–2 (0.14), 11–1 (0.08).
  // Chair 12 0.2 m off on z (within the gate); chair 13 far away; a "tv" 14 with no gt.
  const std::vector<io::MappedObject> map = {
      mapped(10, "cup", {0.06, 0, 0}, h), mapped(11, "cup", {0, 0.08, 0}, h),
      mapped(12, "chair", {1, 1, 0.2}, h), mapped(13, "chair", {3, 3, 3}, h),
      mapped(14, "tv", {0, 0, 1}, h)};
  const ObjectEvalResult r = evaluate_objects(map, gt, ObjectEvalOptions{});

  // Table 3: book 1 vs 0, chair 1 vs 2, cup 2 vs 2, tv 0 vs 1; overall 4 vs 5.
  ASSERT_EQ(r.counts.size(), 5u);
  EXPECT_EQ(r.counts[0].class_name, "book");
  EXPECT_EQ(r.counts[0].mapped, 0u);
  EXPECT_DOUBLE_EQ(*r.counts[0].error, 1.0);
  EXPECT_EQ(r.counts[1].class_name, "chair");
  EXPECT_EQ(r.counts[1].mapped, 2u);
  EXPECT_DOUBLE_EQ(*r.counts[1].error, 1.0);
  EXPECT_EQ(r.counts[2].class_name, "cup");
  EXPECT_DOUBLE_EQ(*r.counts[2].error, 0.0);
  EXPECT_EQ(r.counts[3].class_name, "tv monitor");  // "tv", canonical
  EXPECT_FALSE(r.counts[3].error.has_value());
  EXPECT_EQ(r.counts[4].class_name, "overall");
  EXPECT_EQ(r.counts[4].reference, 4u);
  EXPECT_EQ(r.counts[4].mapped, 5u);
  EXPECT_DOUBLE_EQ(*r.counts[4].error, 0.25);

  // Matches (sorted by reference id): 11–1, 10–2, 12–3.
  ASSERT_EQ(r.matches.size(), 3u);
  EXPECT_EQ(r.matches[0].map_id, 11);
  EXPECT_EQ(r.matches[0].reference_id, 1);
  EXPECT_NEAR(r.matches[0].distance_m, 0.08, 1e-12);
  EXPECT_EQ(r.matches[1].map_id, 10);
  EXPECT_EQ(r.matches[1].reference_id, 2);
  EXPECT_NEAR(r.matches[1].distance_m, 0.14, 1e-12);
  EXPECT_TRUE(r.matches[1].error_xyz_m.isApprox(Vec3(-0.14, 0, 0)));
  EXPECT_EQ(r.matches[2].map_id, 12);
  EXPECT_NEAR(r.matches[2].distance_m, 0.2, 1e-12);
  // IoU of two 10 cm cubes 0.08 apart on y: intersection 0.02·0.1·0.1, union 2·0.1³ − that:
  // (0.1 − 0.08) / (0.1 + 0.08) = 1/9.
  EXPECT_NEAR(r.matches[0].iou, 1.0 / 9.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.matches[2].iou, 0.0);  // 0.2 m apart, 0.1 m cubes
  EXPECT_EQ(r.unmatched_map_ids, (std::vector<int>{13, 14}));
  EXPECT_EQ(r.unmatched_reference_ids, (std::vector<int>{4}));

  // Tables 4–5: cup mean (0.08 + 0.14) / 2 = 0.11; chair 0.2; overall (0.08 + 0.14 + 0.2) / 3.
  ASSERT_EQ(r.errors.size(), 5u);
  EXPECT_EQ(r.errors[2].class_name, "cup");
  EXPECT_EQ(r.errors[2].matched, 2u);
  EXPECT_NEAR(r.errors[2].distance_m.mean, 0.11, 1e-12);
  EXPECT_NEAR(r.errors[2].distance_m.max, 0.14, 1e-12);
  EXPECT_TRUE(r.errors[2].mean_abs_xyz_m.isApprox(Vec3(0.07, 0.04, 0)));
  EXPECT_EQ(r.errors[1].class_name, "chair");
  EXPECT_NEAR(r.errors[1].distance_m.mean, 0.2, 1e-12);
  EXPECT_EQ(r.errors[0].matched, 0u);
  EXPECT_EQ(r.errors[4].class_name, "overall");
  EXPECT_EQ(r.errors[4].matched, 3u);
  EXPECT_NEAR(r.errors[4].distance_m.mean, 0.14, 1e-12);
  EXPECT_NEAR(r.errors[4].distance_m.median, 0.14, 1e-12);

  // Precision / recall: within 0.10 m only one cup pair can match (both map cups are within
  // 0.10 of gt 1 only) → 1; within 0.25 m: both cups and the chair → 3. 5 mapped, 4 true.
  ASSERT_EQ(r.precision_recall.size(), 2u);
  EXPECT_EQ(r.precision_recall[0].matched, 1u);
  EXPECT_DOUBLE_EQ(r.precision_recall[0].precision, 0.2);
  EXPECT_DOUBLE_EQ(r.precision_recall[0].recall, 0.25);
  EXPECT_EQ(r.precision_recall[1].matched, 3u);
  EXPECT_DOUBLE_EQ(r.precision_recall[1].precision, 0.6);
  EXPECT_DOUBLE_EQ(r.precision_recall[1].recall, 0.75);

  // A smaller gate drops the chair pair.
  ObjectEvalOptions tight;
  tight.gate_m = 0.15;
  EXPECT_EQ(evaluate_objects(map, gt, tight).matches.size(), 2u);
  tight.gate_m = 0;
  EXPECT_THROW(evaluate_objects(map, gt, tight), InputError);
}

TEST(EvaluateObjects, EveryReferenceObjectIsMatchedBeyondTheGateOrMissed) {
  const Vec3 h(0.05, 0.05, 0.05);
  // Ground truth: cups 1 (0,0,0) and 2 (1,0,0), book 3, chair 4.
  const std::vector<ReferenceObject> gt = {ref(1, "cup", {0, 0, 0}, h), ref(2, "cup", {1, 0, 0}, h),
                                           ref(3, "book", {4, 4, 4}, h),
                                           ref(4, "chair", {0, 3, 0}, h)};
  // Map: cup 10 0.05 from gt 1; cup 11 0.5 from gt 2 (beyond the 0.3 m gate); chair 12 0.1 from
  // gt 4; couch 13 with no true couch. No book: gt 3 is missed.
  const std::vector<io::MappedObject> map = {
      mapped(10, "cup", {0.05, 0, 0}, h), mapped(11, "cup", {1.5, 0, 0}, h),
      mapped(12, "chair", {0, 3, 0.1}, h), mapped(13, "couch", {9, 9, 9}, h)};
  const ObjectEvalResult r = evaluate_objects(map, gt, ObjectEvalOptions{});
  ASSERT_EQ(r.matches.size(), 2u);
  ASSERT_EQ(r.beyond_gate.size(), 1u);
  EXPECT_EQ(r.beyond_gate[0].map_id, 11);
  EXPECT_EQ(r.beyond_gate[0].reference_id, 2);
  EXPECT_NEAR(r.beyond_gate[0].distance_m, 0.5, 1e-12);
  EXPECT_EQ(r.unmatched_map_ids, (std::vector<int>{11, 13}));  // the false positives
  EXPECT_EQ(r.unmatched_reference_ids, (std::vector<int>{2, 3}));
  EXPECT_EQ(r.missed_reference_ids, (std::vector<int>{3}));
  ASSERT_EQ(r.reference_objects.size(), 4u);
  const std::vector<std::string> status = {"matched", "beyond_gate", "missed", "matched"};
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(r.reference_objects[k].reference_id, static_cast<int>(k) + 1);
    EXPECT_EQ(r.reference_objects[k].status, status[k]) << k;
  }
  EXPECT_EQ(r.reference_objects[1].match->map_id, 11);
  EXPECT_NEAR(r.reference_objects[1].match->distance_m, 0.5, 1e-12);
  EXPECT_FALSE(r.reference_objects[2].match.has_value());
  EXPECT_EQ(r.reference_objects[2].class_name, "book");

  // Rows: book, chair, couch, cup, overall.
  ASSERT_EQ(r.errors.size(), 5u);
  const ErrorRow& cup = r.errors[3];
  EXPECT_EQ(cup.class_name, "cup");
  EXPECT_EQ(cup.matched, 1u);
  EXPECT_EQ(cup.beyond_gate, 1u);
  EXPECT_EQ(cup.missed, 0u);
  EXPECT_EQ(cup.false_positives, 1u);
  EXPECT_NEAR(cup.distance_m.mean, 0.05, 1e-12);
  EXPECT_NEAR(cup.distance_all_m.mean, (0.05 + 0.5) / 2, 1e-12);
  EXPECT_EQ(r.errors[0].missed, 1u);
  EXPECT_NEAR(r.errors[0].distance_all_m.mean, 0.3, 1e-12);  // a miss counts at the gate
  EXPECT_EQ(r.errors[2].false_positives, 1u);                // the couch
  EXPECT_EQ(r.errors[2].distance_all_m.count, 0u);           // no true couch
  const ErrorRow& all = r.errors[4];
  EXPECT_EQ(all.matched, 2u);
  EXPECT_EQ(all.beyond_gate, 1u);
  EXPECT_EQ(all.missed, 1u);
  EXPECT_EQ(all.false_positives, 2u);
  EXPECT_NEAR(all.distance_m.mean, (0.05 + 0.1) / 2, 1e-12);
  EXPECT_EQ(all.distance_all_m.count, 4u);
  EXPECT_NEAR(all.distance_all_m.mean, (0.05 + 0.5 + 0.3 + 0.1) / 4, 1e-12);
  EXPECT_NEAR(all.distance_all_m.max, 0.5, 1e-12);
  EXPECT_EQ(all.iou_all.count, 4u);
  EXPECT_NEAR(all.iou_all.mean, (r.matches[0].iou + r.matches[1].iou) / 4, 1e-12);

  // A gate of 0.6 m takes the second cup in: nothing beyond any more.
  ObjectEvalOptions wide;
  wide.gate_m = 0.6;
  const ObjectEvalResult w = evaluate_objects(map, gt, wide);
  EXPECT_EQ(w.matches.size(), 3u);
  EXPECT_TRUE(w.beyond_gate.empty());
  EXPECT_EQ(w.reference_objects[1].status, "matched");
}

TEST(EvaluateObjects, ClassNamesAreComparedCanonically) {
  const Vec3 h(0.05, 0.05, 0.05);
  const std::vector<ReferenceObject> gt = {ref(1, "tvmonitor", {0, 0, 0}, h),
                                           ref(2, "Potted_Plant", {1, 0, 0}, h),
                                           ref(3, "diningtable", {2, 0, 0}, h)};
  const std::vector<io::MappedObject> map = {mapped(7, "tv monitor", {0, 0, 0.02}, h),
                                             mapped(8, "potted plant", {1, 0, 0.02}, h),
                                             mapped(9, "dining_table", {2, 0, 0.02}, h)};
  const ObjectEvalResult r = evaluate_objects(map, gt, ObjectEvalOptions{});
  ASSERT_EQ(r.matches.size(), 3u);
  EXPECT_TRUE(r.unmatched_map_ids.empty());
  ASSERT_EQ(r.counts.size(), 4u);  // one row per class, not one per spelling
  EXPECT_EQ(r.counts[0].class_name, "dining table");
  EXPECT_EQ(r.counts[1].class_name, "potted plant");
  EXPECT_EQ(r.counts[2].class_name, "tv monitor");
  EXPECT_EQ(r.matches[0].class_name, "tv monitor");
  EXPECT_DOUBLE_EQ(*r.counts[3].error, 0.0);
  EXPECT_EQ(match_by_class(map, gt, 0.3).size(), 3u);
}

TEST(EvaluateObjects, ReferenceObjectsSharingAnIdAreEachListed) {
  // A position list ("id class x y z") does not check its ids: two lines with id 5.
  const Vec3 h(0.05, 0.05, 0.05);
  const std::vector<ReferenceObject> gt = {ref(5, "cup", {0, 0, 0}, h),
                                           ref(5, "book", {1, 0, 0}, h)};
  const std::vector<io::MappedObject> map = {mapped(1, "book", {1, 0, 0.01}, h)};
  const ObjectEvalResult r = evaluate_objects(map, gt, ObjectEvalOptions{});
  ASSERT_EQ(r.reference_objects.size(), 2u);
  EXPECT_EQ(r.reference_objects[0].class_name, "cup");
  EXPECT_EQ(r.reference_objects[0].status, "missed");
  EXPECT_EQ(r.reference_objects[1].class_name, "book");
  EXPECT_EQ(r.reference_objects[1].status, "matched");
}

// A scene of 8 objects (3 cups, 2 books) and a map of it: the same objects a few cm off, one true
// object missing and one extra map object.
struct AlignScene {
  std::vector<ReferenceObject> gt;
  std::vector<io::MappedObject> map;
};

AlignScene align_scene() {
  const Vec3 h(0.05, 0.05, 0.05);
  AlignScene s;
  const std::vector<std::pair<std::string, Vec3>> objects = {
      {"cup", {0.1, 0.2, 0.8}},   {"cup", {0.5, -0.3, 0.8}},    {"cup", {-0.4, 0.1, 0.8}},
      {"book", {0.3, 0.4, 0.78}}, {"book", {-0.2, -0.35, 0.8}}, {"chair", {1.0, 0.0, 0.45}},
      {"tv", {0.0, 0.45, 1.0}},   {"bottle", {-0.6, 0.4, 0.85}}};
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const int id = static_cast<int>(k) + 1;
    s.gt.push_back(ref(id, objects[k].first, objects[k].second, h));
    if (k == 7) continue;  // the bottle is missed
    const Vec3 off(noise(rng), noise(rng), noise(rng));
    s.map.push_back(mapped(10 + id, objects[k].first, objects[k].second + off, h));
  }
  s.map.push_back(mapped(30, "cup", {2.0, 2.0, 0.8}, h));  // a false positive
  return s;
}

Similarity known_transform() {
  Similarity t;
  t.rotation = (Eigen::AngleAxisd(1.1, Vec3::UnitZ()) * Eigen::AngleAxisd(0.3, Vec3::UnitX()))
                   .toRotationMatrix();
  t.translation = Vec3(2.5, -1.0, 0.4);
  return t;
}

Similarity inverse(const Similarity& t) {
  Similarity inv;
  inv.rotation = t.rotation.transpose();
  inv.translation = -(inv.rotation * t.translation);
  return inv;
}

void expect_same_evaluation(const ObjectEvalResult& a, const ObjectEvalResult& b) {
  ASSERT_EQ(a.matches.size(), b.matches.size());
  for (std::size_t k = 0; k < a.matches.size(); ++k) {
    EXPECT_EQ(a.matches[k].map_id, b.matches[k].map_id);
    EXPECT_EQ(a.matches[k].reference_id, b.matches[k].reference_id);
    EXPECT_NEAR(a.matches[k].distance_m, b.matches[k].distance_m, 1e-9);
    EXPECT_NEAR(a.matches[k].iou, b.matches[k].iou, 1e-6);
  }
  EXPECT_EQ(a.unmatched_map_ids, b.unmatched_map_ids);
  EXPECT_EQ(a.missed_reference_ids, b.missed_reference_ids);
  EXPECT_NEAR(a.errors.back().distance_all_m.mean, b.errors.back().distance_all_m.mean, 1e-9);
}

TEST(AlignObjects, RecoversAKnownRigidTransform) {
  const AlignScene s = align_scene();
  // The map in a frame turned by 63° about z and 17° about x and moved by 2.7 m: no object is
  // within the gate of its true position before the alignment.
  const Similarity map_from_truth = known_transform();
  const std::vector<io::MappedObject> moved = transform_objects(s.map, map_from_truth);
  EXPECT_TRUE(evaluate_objects(moved, s.gt, ObjectEvalOptions{}).matches.empty());
  const ObjectAlignment a = align_by_objects(moved, s.gt, 0.3);
  EXPECT_EQ(a.method, "objects");
  EXPECT_EQ(a.pairs, 7u);  // every mapped true object; not the bottle, not the extra cup
  const Similarity expected = inverse(map_from_truth);
  EXPECT_LT(
      Eigen::AngleAxisd(a.reference_from_map.rotation.transpose() * expected.rotation).angle(),
      0.05);
  // The translation is the inverse's −Rᵀt: its error grows with the 2.7 m of the move, so check
  // what it does to the objects instead: back within the noise of where they were.
  const std::vector<io::MappedObject> back = transform_objects(moved, a.reference_from_map);
  double worst = 0.0;
  for (std::size_t k = 0; k + 1 < back.size(); ++k)  // the true objects, not the extra cup
    worst = std::max(worst, (back[k].centroid - s.map[k].centroid).norm());
  EXPECT_LT(worst, 0.04) << worst;
  EXPECT_GT(a.rmse_m, 0.005);  // the 2 cm noise stays
  EXPECT_LT(a.rmse_m, 0.05);
  // The moved map, aligned, evaluates as the original map aligned the same way: the result does
  // not depend on the frame the map came in.
  const ObjectAlignment direct = align_by_objects(s.map, s.gt, 0.3);
  EXPECT_TRUE((a.reference_from_map.rotation * map_from_truth.rotation)
                  .isApprox(direct.reference_from_map.rotation, 1e-9));
  EXPECT_LT(
      (a.reference_from_map * map_from_truth.translation - direct.reference_from_map.translation)
          .norm(),
      1e-9);
  expect_same_evaluation(
      evaluate_objects(transform_objects(moved, a.reference_from_map), s.gt, ObjectEvalOptions{}),
      evaluate_objects(transform_objects(s.map, direct.reference_from_map), s.gt,
                       ObjectEvalOptions{}));
}

TEST(AlignObjects, FewerThanThreeMatchesIsAnError) {
  const Vec3 h(0.05, 0.05, 0.05);
  const std::vector<ReferenceObject> gt = {ref(1, "cup", {0, 0, 0}, h),
                                           ref(2, "book", {1, 0, 0}, h)};
  const std::vector<io::MappedObject> map = {mapped(1, "cup", {5, 0, 0}, h),
                                             mapped(2, "book", {6, 0, 0}, h)};
  try {
    align_by_objects(map, gt, 0.3);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_TRUE(mentions(e.what(), "--align objects")) << e.what();
    EXPECT_TRUE(mentions(e.what(), "only 0 objects")) << e.what();
    EXPECT_TRUE(mentions(e.what(), "expected at least 3")) << e.what();
  }
}

TEST(AlignObjects, TransformMovesCentroidsAndBoxes) {
  io::MappedObject o = mapped(1, "cup", {1, 0, 0}, {0.1, 0.2, 0.3});
  o.aabb = {Vec3(0.9, -0.2, -0.3), Vec3(1.1, 0.2, 0.3)};
  Similarity quarter;  // 90° about z, then 1 m up
  quarter.rotation = Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ()).toRotationMatrix();
  quarter.translation = Vec3(0, 0, 1);
  const io::MappedObject m = transform_objects({o}, quarter)[0];
  EXPECT_TRUE(m.centroid.isApprox(Vec3(0, 1, 1), 1e-12));
  EXPECT_TRUE(m.position.isApprox(Vec3(0, 1, 1), 1e-12));
  EXPECT_TRUE(m.obb.center.isApprox(Vec3(0, 1, 1), 1e-12));
  EXPECT_TRUE(m.obb.rotation.isApprox(quarter.rotation, 1e-12));
  EXPECT_TRUE(m.aabb.min.isApprox(Vec3(-0.2, 0.9, 0.7), 1e-12));
  EXPECT_TRUE(m.aabb.max.isApprox(Vec3(0.2, 1.1, 1.3), 1e-12));
  EXPECT_NEAR(obb_iou(m.obb, transform_objects({o}, quarter)[0].obb), 1.0, 1e-9);
}

TEST(EvaluateObjects, EmptyInputsGiveZeros) {
  const ObjectEvalResult r = evaluate_objects({}, {}, ObjectEvalOptions{});
  ASSERT_EQ(r.counts.size(), 1u);
  EXPECT_FALSE(r.counts[0].error.has_value());
  EXPECT_EQ(r.errors[0].matched, 0u);
  EXPECT_DOUBLE_EQ(r.precision_recall[0].recall, 0.0);
}

// ---- files and the CLI
// ---------------------------------------------------------------------------

// An objects.json of objmap fuse with the fields the reader needs.
std::string objects_json(const std::vector<io::MappedObject>& objects) {
  nlohmann::json doc;
  doc["schema_version"] = 1;
  doc["objects"] = nlohmann::json::array();
  for (const auto& o : objects) {
    nlohmann::json j;
    j["id"] = o.id;
    j["class"] = o.class_name;
    j["score"] = 0.9;
    j["centroid"] = {o.centroid.x(), o.centroid.y(), o.centroid.z()};
    j["aabb"] = {{"min", {0, 0, 0}}, {"max", {0, 0, 0}}};
    j["obb"] = {
        {"center", {o.obb.center.x(), o.obb.center.y(), o.obb.center.z()}},
        {"rotation", {1, 0, 0, 0, 1, 0, 0, 0, 1}},
        {"half_extent", {o.obb.half_extent.x(), o.obb.half_extent.y(), o.obb.half_extent.z()}}};
    j["points"] = {{"raw", 100}, {"voxel_filtered", 50}, {"outlier_filtered", 40}};
    j["observation_count"] = 3;
    j["ply"] = "objects/x.ply";
    doc["objects"].push_back(j);
  }
  return doc.dump();
}

const char* kRunJson = R"({"points":{"dense_back_projected":1000,"dense_map":400,"objects_raw":300,
  "objects_voxel_filtered":120,"objects_outlier_filtered":100,"semantic_map":400,"objects_map":100}})";

TEST(EvalObjectsCli, HandMadeFilesGiveTheExactNumbers) {
  TempDir tmp;
  const Vec3 h(0.05, 0.05, 0.05);
  fs::create_directories(tmp / "est");
  fs::create_directories(tmp / "gt");
  write_text(tmp / "est/objects.json",
             objects_json({mapped(1, "cup", {0.03, 0, 0}, h), mapped(2, "cup", {1, 0, 0}, h),
                           mapped(3, "teddy bear", {0, 2, 0.09}, h)}));
  write_text(tmp / "est/run.json", kRunJson);
  write_text(
      tmp / "gt/objects.json",
      objects_json({mapped(5, "cup", {0, 0, 0}, h), mapped(6, "cup", {1, 0.04, 0}, h),
                    mapped(7, "teddy bear", {0, 2, 0}, h), mapped(8, "book", {4, 4, 4}, h)}));
  const auto r =
      run_objmap({"eval", "objects", "--map", (tmp / "est/objects.json").string(), "--reference",
                  (tmp / "gt/objects.json").string(), "--json", (tmp / "out.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(mentions(r.out, "Table 3")) << r.out;
  EXPECT_TRUE(mentions(r.out, "overall")) << r.out;
  EXPECT_TRUE(mentions(r.out, "25.0%")) << r.out;  // 3 mapped vs 4
  EXPECT_TRUE(mentions(r.out, "75.0%")) << r.out;  // Table 6: 1 − 100/400
  const auto json = nlohmann::json::parse(read_text(tmp / "out.json"));
  EXPECT_TRUE(
      objmap::test::validate_json(json, objmap::test::load_schema("eval_objects.schema.json"))
          .empty());
  EXPECT_EQ(json.at("mode"), "reference");
  const auto& overall = json.at("centroid_error").back();
  EXPECT_EQ(overall.at("class"), "overall");
  EXPECT_EQ(overall.at("matched"), 3);
  EXPECT_NEAR(overall.at("distance_m").at("mean").get<double>(), (0.03 + 0.04 + 0.09) / 3, 1e-12);
  // objects.json without `position`: the centroid stands in on both sides.
  EXPECT_NEAR(overall.at("position_distance_m").at("mean").get<double>(), (0.03 + 0.04 + 0.09) / 3,
              1e-12);
  EXPECT_NEAR(json.at("counts").back().at("error").get<double>(), 0.25, 1e-12);
  EXPECT_TRUE(json.at("counts").front().at("error").is_number());  // book: 0 vs 1 → 100%
  EXPECT_EQ(json.at("points").at("dense_map"), 400);
  EXPECT_NEAR(json.at("points").at("reduction").get<double>(), 0.75, 1e-12);
  EXPECT_EQ(json.at("unmatched_reference_ids"), nlohmann::json::array({8}));
  // Precision at 0.10 m: the three pairs are within 0.1 → 3/3, recall 3/4.
  EXPECT_DOUBLE_EQ(json.at("precision_recall")[0].at("precision").get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(json.at("precision_recall")[0].at("recall").get<double>(), 0.75);
}

TEST(EvalObjectsCli, BadInputIsExitTwoWithOneLine) {
  TempDir tmp;
  write_text(tmp / "objects.json", objects_json({}));
  write_text(tmp / "bad.json", "{\"objects\": [");
  const std::string map = (tmp / "objects.json").string();
  const auto one_line = [](const std::string& err) {
    return std::count(err.begin(), err.end(), '\n') == 1;
  };
  auto r = run_objmap({"eval", "objects", "--map", map});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err)) << r.err;
  EXPECT_TRUE(mentions(r.err, "--gt-objects")) << r.err;
  r = run_objmap({"eval", "objects", "--map", (tmp / "missing.json").string(), "--reference", map});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "missing.json: cannot open")) << r.err;
  r = run_objmap({"eval", "objects", "--map", map, "--reference", (tmp / "bad.json").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "bad.json: malformed JSON")) << r.err;
  r = run_objmap({"eval", "objects", "--map", map, "--gt-objects", (tmp / "bad.json").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "bad.json: malformed JSON")) << r.err;
  r = run_objmap(
      {"eval", "objects", "--map", map, "--reference", map, "--run", (tmp / "norun").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "run.json: cannot open")) << r.err;
  r = run_objmap({"eval", "objects", "--map", map, "--reference", map, "--gate", "-1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "gate")) << r.err;
}

// objmap synth (20 frames) → fuse with the true and the drifting trajectory → eval objects, both
// protocols. Structure and sanity only: the association is being tuned.
TEST(EvalObjectsCli, SynthFuseEvalEndToEnd) {
  objmap::test::RunResult failure;
  const fs::path scene = objmap::test::cached_output(
      "evalobj_synth20", {"synth", "--out", "{OUT}", "--frames", "20"}, &failure);
  ASSERT_FALSE(scene.empty()) << failure.err;
  const auto fuse = [&](const std::string& key, const std::string& trajectory) {
    const fs::path run = objmap::test::cached_output(
        key,
        {"fuse", "--dataset", scene.string(), "--trajectory", (scene / trajectory).string(),
         "--segmentation", (scene / "segmentation").string(), "--out", "{OUT}"},
        &failure);
    EXPECT_FALSE(run.empty()) << failure.err;
    return run;
  };
  const fs::path run_gt = fuse("evalobj_fuse_gt", "groundtruth.txt");
  const fs::path run_est = fuse("evalobj_fuse_est", "estimated.txt");
  ASSERT_FALSE(run_gt.empty() || run_est.empty());
  TempDir tmp;
  const nlohmann::json schema = objmap::test::load_schema("eval_objects.schema.json");
  for (const bool with_gt : {false, true}) {
    const auto r = run_objmap(
        {"eval", "objects", "--map", (run_est / "objects.json").string(),
         with_gt ? "--gt-objects" : "--reference",
         with_gt ? (scene / "objects_gt.json").string() : (run_gt / "objects.json").string(),
         "--json", (tmp / "e.json").string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(mentions(r.out, "Table 6")) << r.out;
    const auto json = nlohmann::json::parse(read_text(tmp / "e.json"));
    const auto problems = objmap::test::validate_json(json, schema);
    EXPECT_TRUE(problems.empty()) << problems.front();
    EXPECT_EQ(json.at("mode"), with_gt ? "ground_truth" : "reference");
    EXPECT_GT(json.at("precision_recall")[1].at("recall").get<double>(), 0.0);
    const auto& overall = json.at("centroid_error").back();
    EXPECT_GT(overall.at("matched").get<int>(), 0);
    const double mean = overall.at("distance_m").at("mean").get<double>();
    EXPECT_TRUE(std::isfinite(mean) && mean >= 0 && mean <= 0.3) << mean;
    for (const auto& m : json.at("matches")) {
      EXPECT_LE(m.at("distance_m").get<double>(), 0.3);
      EXPECT_GE(m.at("iou").get<double>(), 0.0);
      EXPECT_LE(m.at("iou").get<double>(), 1.0);
    }
    EXPECT_GT(json.at("points").at("reduction").get<double>(), 0.0);
    // Table 6 as the paper defines it (objects-only map vs dense map) and eq 18's own reduction
    // (outlier- vs voxel-filtered object points): the same figures in run.json and eval objects.
    const auto run = nlohmann::json::parse(read_text(run_est / "run.json")).at("points");
    const auto& points = json.at("points");
    EXPECT_DOUBLE_EQ(points.at("reduction").get<double>(),
                     run.at("reduction_objects_vs_dense").get<double>());
    EXPECT_DOUBLE_EQ(points.at("reduction_eq18").get<double>(),
                     run.at("reduction_eq18").get<double>());
    EXPECT_DOUBLE_EQ(points.at("reduction_eq18").get<double>(),
                     1.0 - run.at("objects_outlier_filtered").get<double>() /
                               run.at("objects_voxel_filtered").get<double>());
    EXPECT_LT(points.at("reduction_eq18").get<double>(), points.at("reduction").get<double>());
    if (with_gt) {
      EXPECT_EQ(json.at("counts").back().at("reference"), 12);  // tabletop: 12 objects
    }
  }
}

// ---- --align on a fused synthetic run
// -------------------------------------------------------------

// The run's objects.json with every centroid, position and box moved by `t`.
nlohmann::json moved_objects_json(const fs::path& file, const Similarity& t) {
  nlohmann::json doc = nlohmann::json::parse(read_text(file));
  const auto point = [&](nlohmann::json& j) {
    const Vec3 p = t * Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
    j = {p.x(), p.y(), p.z()};
  };
  for (auto& o : doc.at("objects")) {
    point(o.at("centroid"));
    if (o.contains("position")) point(o.at("position"));
    point(o.at("obb").at("center"));
    Eigen::Matrix3d r;
    for (int k = 0; k < 9; ++k) r(k / 3, k % 3) = o.at("obb").at("rotation")[k].get<double>();
    r = t.rotation * r;
    for (int k = 0; k < 9; ++k) o["obb"]["rotation"][k] = r(k / 3, k % 3);
    io::MappedObject box;  // the AABB around the moved one
    for (int k = 0; k < 3; ++k) {
      box.aabb.min[k] = o.at("aabb").at("min")[k].get<double>();
      box.aabb.max[k] = o.at("aabb").at("max")[k].get<double>();
    }
    box = transform_objects({box}, t)[0];
    o["aabb"] = {{"min", {box.aabb.min.x(), box.aabb.min.y(), box.aabb.min.z()}},
                 {"max", {box.aabb.max.x(), box.aabb.max.y(), box.aabb.max.z()}}};
  }
  return doc;
}

// The two evaluations list the same objects with the same statuses, pairs and errors.
void expect_same_eval_json(const nlohmann::json& a, const nlohmann::json& b) {
  EXPECT_EQ(a.at("counts"), b.at("counts"));
  EXPECT_EQ(a.at("unmatched_map_ids"), b.at("unmatched_map_ids"));
  EXPECT_EQ(a.at("missed_reference_ids"), b.at("missed_reference_ids"));
  ASSERT_EQ(a.at("reference_objects").size(), b.at("reference_objects").size());
  for (std::size_t k = 0; k < a.at("reference_objects").size(); ++k) {
    const auto &x = a.at("reference_objects")[k], &y = b.at("reference_objects")[k];
    EXPECT_EQ(x.at("status"), y.at("status")) << k;
    EXPECT_EQ(x.at("map_id"), y.at("map_id")) << k;
    if (x.at("distance_m").is_number()) {
      EXPECT_NEAR(x.at("distance_m").get<double>(), y.at("distance_m").get<double>(), 1e-9) << k;
    }
    if (x.at("iou").is_number()) {
      EXPECT_NEAR(x.at("iou").get<double>(), y.at("iou").get<double>(), 1e-6) << k;
    }
  }
  const auto &ra = a.at("centroid_error").back(), &rb = b.at("centroid_error").back();
  for (const char* key : {"distance_m", "distance_all_m"})
    for (const char* stat : {"mean", "rmse", "max"})
      EXPECT_NEAR(ra.at(key).at(stat).get<double>(), rb.at(key).at(stat).get<double>(), 1e-9)
          << key << "." << stat;
}

TEST(EvalObjectsCli, AlignBringsAMovedMapBack) {
  objmap::test::RunResult failure;
  const fs::path scene = objmap::test::cached_output(
      "evalobj_synth20", {"synth", "--out", "{OUT}", "--frames", "20"}, &failure);
  ASSERT_FALSE(scene.empty()) << failure.err;
  const fs::path run = objmap::test::cached_output(
      "evalobj_fuse_gt",
      {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
       "--segmentation", (scene / "segmentation").string(), "--out", "{OUT}"},
      &failure);
  ASSERT_FALSE(run.empty()) << failure.err;
  // The map and the trajectory it was fused with, in a frame turned by 63° about z and 17° about
  // x and moved by 2.7 m (a SLAM run's own frame).
  TempDir tmp;
  const Similarity t = known_transform();
  fs::create_directories(tmp / "moved");
  write_text(tmp / "moved/objects.json", moved_objects_json(run / "objects.json", t).dump());
  Trajectory moved = io::read_trajectory(scene / "groundtruth.txt");
  for (StampedPose& p : moved.poses) p.world_from_cam = t.apply(p.world_from_cam);
  io::write_trajectory(tmp / "moved.txt", moved);

  const auto eval = [&](const fs::path& map, const std::vector<std::string>& extra) {
    std::vector<std::string> args{"eval",         "objects",
                                  "--map",        map.string(),
                                  "--gt-objects", (scene / "objects_gt.json").string(),
                                  "--json",       (tmp / "e.json").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_objmap(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const auto json = nlohmann::json::parse(read_text(tmp / "e.json"));
    const auto problems =
        objmap::test::validate_json(json, objmap::test::load_schema("eval_objects.schema.json"));
    EXPECT_TRUE(problems.empty()) << problems.front();
    return std::make_pair(json, r.out);
  };
  const auto [plain, plain_text] = eval(run / "objects.json", {});
  EXPECT_EQ(plain.at("alignment").at("method"), "none");
  EXPECT_TRUE(mentions(plain_text, "alignment: none")) << plain_text;
  const int matched = plain.at("centroid_error").back().at("matched").get<int>();
  ASSERT_GE(matched, 10);
  // Without --align, the moved map matches nothing.
  const auto [lost, lost_text] = eval(tmp / "moved/objects.json", {});
  EXPECT_EQ(lost.at("centroid_error").back().at("matched"), 0) << lost_text;

  // --align trajectory: eval ate's SE(3) undoes the move exactly.
  const auto [by_trajectory, text] =
      eval(tmp / "moved/objects.json",
           {"--align", "trajectory", "--gt-trajectory", (scene / "groundtruth.txt").string(),
            "--trajectory", (tmp / "moved.txt").string()});
  expect_same_eval_json(plain, by_trajectory);
  const auto& a = by_trajectory.at("alignment");
  EXPECT_EQ(a.at("method"), "trajectory");
  EXPECT_EQ(a.at("pairs"), 20);
  EXPECT_LT(a.at("rmse_m").get<double>(), 1e-9);
  EXPECT_TRUE(mentions(text, "alignment: SE(3) from the trajectories")) << text;

  // --align objects: the same map in either frame gives the same evaluation, with all pairs kept,
  // and the fitted transform cannot leave the matched pairs' RMS error worse than none.
  const auto [objects_moved, objects_text] =
      eval(tmp / "moved/objects.json", {"--align", "objects"});
  const nlohmann::json objects_plain = eval(run / "objects.json", {"--align", "objects"}).first;
  expect_same_eval_json(objects_plain, objects_moved);
  EXPECT_EQ(objects_moved.at("alignment").at("method"), "objects");
  EXPECT_EQ(objects_moved.at("alignment").at("pairs").get<int>(), matched);
  EXPECT_EQ(objects_moved.at("centroid_error").back().at("matched").get<int>(), matched);
  EXPECT_LE(objects_moved.at("centroid_error").back().at("distance_m").at("rmse").get<double>(),
            plain.at("centroid_error").back().at("distance_m").at("rmse").get<double>() + 1e-9);
  EXPECT_TRUE(mentions(objects_text, "alignment: SE(3) from the objects")) << objects_text;
}

TEST(EvalObjectsCli, AlignFlagsAreChecked) {
  TempDir tmp;
  write_text(tmp / "objects.json", objects_json({}));
  const std::string map = (tmp / "objects.json").string();
  const auto one_line = [](const std::string& err) {
    return std::count(err.begin(), err.end(), '\n') == 1;
  };
  auto r =
      run_objmap({"eval", "objects", "--map", map, "--reference", map, "--align", "trajectory"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "--align trajectory") &&
              mentions(r.err, "--gt-trajectory"))
      << r.err;
  r = run_objmap({"eval", "objects", "--map", map, "--reference", map, "--trajectory", map});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "only with --align trajectory")) << r.err;
  r = run_objmap({"eval", "objects", "--map", map, "--reference", map, "--align", "icp"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "--align")) << r.err;
  r = run_objmap({"eval", "objects", "--map", map, "--reference", map, "--align", "objects"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "--align objects: only 0 objects")) << r.err;
  r = run_objmap({"eval", "objects", "--map", map, "--reference", map, "--align", "trajectory",
                  "--gt-trajectory", (tmp / "none.txt").string(), "--trajectory",
                  (tmp / "none.txt").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(one_line(r.err) && mentions(r.err, "none.txt")) << r.err;
}

}  // namespace
}  // namespace objmap::eval

#include "objmap/fusion/split.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "fusion_test_util.h"
#include "objmap/core/error.h"
#include "objmap/fusion/object_map.h"

// Splitting an object whose surface forms clusters that its observations see apart
// (ObjectMapOptions::split_clusters, fusion/split.h).
namespace objmap::fusion {
namespace {

using test::box;
using test::instance;

PointCloud joined_clouds(PointCloud a, const PointCloud& b) {
  for (std::size_t i = 0; i < b.size(); ++i) a.push_back(b.points[i], b.colors[i]);
  return a;
}

// A chair: a 41 × 41 cm seat at height 0.455 over a frame of legs (four 2 × 2 cm legs from the
// floor to 0.355 joined by bars at 0.055): the legs are 10 cm below the seat, a cluster apart.
PointCloud split_test_chair(const Vec3& at) {
  PointCloud c;
  const auto add = [&](int i, int j, int k) {
    c.push_back((at + 0.01 * Vec3(i, j, k) + Vec3::Constant(0.005)).cast<float>(), Rgb{90, 60, 30});
  };
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j) add(i, j, 45);
  for (int li : {-20, 18})
    for (int lj : {-20, 18})
      for (int k = 0; k <= 35; ++k)
        for (int di = 0; di < 2; ++di)
          for (int dj = 0; dj < 2; ++dj) add(li + di, lj + dj, k);
  for (int t = -20; t <= 19; ++t)
    for (int d = 0; d < 2; ++d)
      for (int k = 5; k < 7; ++k) {
        add(t, -20 + d, k);
        add(t, 18 + d, k);
        add(-20 + d, t, k);
        add(18 + d, t, k);
      }
  return c;
}

double split_test_width_x(const ObjectRecord& r) { return r.aabb.max.x() - r.aabb.min.x(); }

TEST(SplitCells, CellsAreConnectedInTheirNeighbourhoodAndApartBeyondIt) {
  using geometry::pack_voxel;
  EXPECT_EQ(coarse_cell(pack_voxel(7, -1, -4), 4), pack_voxel(1, -1, -1));
  EXPECT_EQ(coarse_cell(pack_voxel(-5, 3, 4), 4), pack_voxel(-2, 0, 1));
  EXPECT_EQ(coarse_cells({pack_voxel(0, 0, 0), pack_voxel(3, 3, 3), pack_voxel(4, 0, 0)}, 4),
            (std::vector<VoxelKey>{pack_voxel(0, 0, 0), pack_voxel(1, 0, 0)}));
  // (0,0,0)-(1,1,1) touch diagonally; (3,1,1) is a cell apart from them; (-1,0,0) touches (0,0,0).
  std::vector<VoxelKey> cells{pack_voxel(0, 0, 0), pack_voxel(1, 1, 1), pack_voxel(3, 1, 1),
                              pack_voxel(-1, 0, 0)};
  std::sort(cells.begin(), cells.end());
  const std::vector<int> labels = connected_cells(cells);
  ASSERT_EQ(labels.size(), 4u);
  EXPECT_EQ(labels, (std::vector<int>{0, 0, 0, 1}));  // sorted: (-1,0,0) (0,0,0) (1,1,1) (3,1,1)
}

TEST(SplitCells, AVoxelMapSubsetKeepsTheChosenVoxelsWithTheirSums) {
  VoxelMap map;
  PointCloud points;
  for (float x : {0.001f, 0.002f, 0.003f, 0.051f, 0.052f}) points.push_back(Vec3f(x, 0.f, 0.f));
  map.insert(points);
  const VoxelKey far_key = map.key_of(Vec3f(0.051f, 0.f, 0.f));
  const VoxelMap part = map.subset([&](VoxelKey key) { return key == far_key; });
  ASSERT_EQ(part.size(), 1u);
  EXPECT_EQ(part.points_inserted(), 2u);
  ASSERT_NE(part.find(far_key), nullptr);
  EXPECT_EQ(part.find(far_key)->count, 2u);
  EXPECT_NEAR(part.mean_position(far_key, *part.find(far_key)).x(), 0.0515, 1e-6);
  EXPECT_EQ(map.size(), 2u);  // the map itself is left as it was
}

TEST(SplitCells, TwoClustersSeenApartAreTwoPartsSeenTogetherOne) {
  using geometry::pack_voxel;
  const std::vector<VoxelKey> cells{pack_voxel(0, 0, 0), pack_voxel(0, 0, 1), pack_voxel(5, 0, 0),
                                    pack_voxel(5, 0, 1), pack_voxel(9, 0, 0)};
  const std::vector<std::size_t> weight{10, 10, 10, 10, 1};  // (9,0,0): a small cluster
  const std::vector<VoxelKey> left{pack_voxel(0, 0, 0), pack_voxel(0, 0, 1)};
  const std::vector<VoxelKey> right{pack_voxel(5, 0, 0), pack_voxel(5, 0, 1)};
  const std::vector<VoxelKey> both{pack_voxel(0, 0, 0), pack_voxel(5, 0, 0)};
  const std::vector<VoxelKey> off{pack_voxel(40, 0, 0)};
  const SplitPlan apart = plan_split(cells, weight, {&left, &right, &left, &right, &off}, {});
  EXPECT_EQ(apart.large_clusters, 2u);
  ASSERT_EQ(apart.groups, 2);
  EXPECT_EQ(apart.cell_group, (std::vector<int>{0, 0, 1, 1, 1}));  // the small one to the nearest
  EXPECT_EQ(apart.observation_group, (std::vector<int>{0, 1, 0, 1, -1}));
  // One observation covering both of the six covering each is at most max_joint (0.2) of them;
  // two are more.
  std::vector<const std::vector<VoxelKey>*> once{&both};
  for (int i = 0; i < 5; ++i) once.insert(once.end(), {&left, &right});
  EXPECT_EQ(plan_split(cells, weight, once, {}).groups, 2);
  once.push_back(&both);
  EXPECT_EQ(plan_split(cells, weight, once, {}).groups, 0);
  const SplitPlan together = plan_split(cells, weight, {&both, &both, &left, &right}, {});
  EXPECT_EQ(together.groups, 0);
  EXPECT_TRUE(together.cell_group.empty());
}

// Two chairs 0.5 m apart on the floor, one track ID for both: the first mask covered both (the
// chairs' masks touched), then the ID swaps between them from keyframe to keyframe. Every
// observation joins the one object; the split makes it two, each box one chair.
TEST(ObjectMap, SplitsAnObjectWhoseClustersItsObservationsSeeApart) {
  const Vec3 a(0.505, 0.105, 1.005), b(1.005, 0.105, 1.005);
  const PointCloud chair_a = box(a, 20), chair_b = box(b, 20);
  const auto run = [&](const ObjectMapOptions& options, std::vector<SplitLink>* splits) {
    ObjectMap map(options);
    EXPECT_EQ(
        map.add_frame({instance(0, 1, "chair", joined_clouds(chair_a, chair_b))}).front().object_id,
        0);
    for (int f = 1; f <= 16; ++f) {
      const AddResult r =
          map.add_frame({instance(f, 1, "chair", f % 2 ? chair_a : chair_b)}).front();
      EXPECT_EQ(r.object_id, 0);  // one object for both chairs
    }
    map.merge_pass();
    const std::vector<SplitLink> made = map.split_pass();
    if (splits) *splits = made;
    // Where each keyframe's observation ended up (the object models' views follow it).
    EXPECT_EQ(map.resolve(0, 1.0), map.resolve(0, 3.0));
    if (!made.empty()) {
      EXPECT_NE(map.resolve(0, 1.0), map.resolve(0, 2.0));
    }
    EXPECT_EQ(map.split_pass().size(), 0u);  // nothing new the second time
    return map.records(RecordOptions{});
  };
  ObjectMapOptions off;
  off.split_clusters = false;
  const auto joined = run(off, nullptr);
  ASSERT_EQ(joined.size(), 1u);
  EXPECT_GT(split_test_width_x(joined[0]), 0.85);  // a box over both chairs
  std::vector<SplitLink> splits;
  const auto apart = run(ObjectMapOptions{}, &splits);
  ASSERT_EQ(splits.size(), 1u);
  EXPECT_EQ(splits[0].from, 0);
  EXPECT_EQ(splits[0].parts, std::vector<int>{1});
  EXPECT_EQ(splits[0].large_clusters, 2u);
  ASSERT_EQ(apart.size(), 2u);
  int seen_a = 0, seen_b = 0;
  for (const ObjectRecord& r : apart) {
    const Vec3& chair = (r.position - a).norm() < (r.position - b).norm() ? a : b;
    EXPECT_LT((r.position - chair).norm(), 0.02) << r.id;
    EXPECT_LT(split_test_width_x(r), 0.45) << r.id;  // one chair (0.41 m)
    EXPECT_EQ(r.class_name, "chair");
    EXPECT_EQ(r.track_ids, std::vector<int>{1});
    (&chair == &a ? seen_a : seen_b) += r.observations;
    for (const ObservationLink& l : r.provenance) {  // each keyframe's chair is this one's
      if (l.timestamp > 0) {
        EXPECT_EQ(static_cast<int>(l.timestamp) % 2 == 1, &chair == &a);
      }
    }
  }
  EXPECT_EQ(seen_a + seen_b, 17);  // the mask over both goes with one of them
  EXPECT_GE(std::min(seen_a, seen_b), 8);
}

// A chair whose legs are a cluster apart from its seat (10 cm below it), seen whole in every
// observation: one object, its box from the floor to the seat.
TEST(ObjectMap, KeepsAnObjectWhoseClustersEveryObservationSeesTogether) {
  const Vec3 at(2.0, 0.0, 0.0);
  const PointCloud chair = split_test_chair(at);
  ObjectMap map;
  for (int f = 0; f < 12; ++f) map.add_frame({instance(f, 3, "chair", chair)});
  map.merge_pass();
  EXPECT_TRUE(map.split_pass().empty());
  const auto records = map.records(RecordOptions{});
  ASSERT_EQ(records.size(), 1u);
  EXPECT_LT(records[0].aabb.min.z(), 0.05);          // the legs (their thin feet may go in eq 18)
  EXPECT_NEAR(records[0].aabb.max.z(), 0.46, 0.02);  // the seat
  // The same chair seen by halves (seat alone, legs alone) would be two objects by the rule: the
  // legs are a large cluster of their own.
  PointCloud seat, legs;
  for (std::size_t i = 0; i < chair.size(); ++i)
    (chair.points[i].z() > 0.4f ? seat : legs).push_back(chair.points[i], chair.colors[i]);
  ObjectMap by_halves;
  by_halves.add_frame({instance(0, 3, "chair", chair)});
  for (int f = 1; f <= 10; ++f) by_halves.add_frame({instance(f, 3, "chair", f % 2 ? seat : legs)});
  by_halves.merge_pass();
  EXPECT_EQ(by_halves.split_pass().size(), 1u);
}

TEST(ObjectMap, SplitOptionsAreChecked) {
  ObjectMapOptions o;
  o.split_cell_voxels = 0;
  EXPECT_THROW(o.check(), InputError);
  o = ObjectMapOptions{};
  o.split_max_joint = 1.5;
  try {
    o.check();
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("split_max_joint"), std::string::npos) << e.what();
  }
  ObjectMapOptions paper;
  set_paper_rules(paper);
  EXPECT_FALSE(paper.split_clusters);
  EXPECT_TRUE(ObjectMapOptions{}.split_clusters);
}

}  // namespace
}  // namespace objmap::fusion

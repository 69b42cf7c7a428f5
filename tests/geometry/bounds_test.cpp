#include "objmap/geometry/bounds.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "objmap/core/error.h"

namespace objmap::geometry {
namespace {

TEST(Bounds, AabbCentroidAndObbOfARotatedBox) {
  // A 0.4 × 0.2 × 0.1 box surface sampled on a grid, rotated 30° about z and moved.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 6, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 t(1.0, 2.0, 0.5);
  PointCloud cloud;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 20; ++j)
      for (int k = 0; k <= 10; ++k) {
        if (i != 0 && i != 40 && j != 0 && j != 20 && k != 0 && k != 10) continue;  // surface only
        const Vec3 local(-0.2 + 0.01 * i, -0.1 + 0.01 * j, -0.05 + 0.01 * k);
        cloud.push_back((R * local + t).cast<float>());
      }
  EXPECT_LT((centroid(cloud) - t).norm(), 1e-5);
  const Obb obb = compute_obb(cloud);
  EXPECT_LT((obb.center - t).norm(), 1e-5);
  EXPECT_NEAR(obb.half_extent.x(), 0.2, 1e-5);
  EXPECT_NEAR(obb.half_extent.y(), 0.1, 1e-5);
  EXPECT_NEAR(obb.half_extent.z(), 0.05, 1e-5);
  EXPECT_NEAR(std::abs(obb.rotation.col(0).dot(R.col(0))), 1.0, 1e-6);
  EXPECT_NEAR(obb.rotation.determinant(), 1.0, 1e-9);
  for (const Vec3f& p : cloud.points) EXPECT_TRUE(obb.contains(p.cast<double>(), 1e-5));
  const Aabb aabb = compute_aabb(cloud);
  EXPECT_LE(aabb.min.x(), t.x() - 0.2);
  EXPECT_GE(aabb.max.x(), t.x() + 0.2);
  EXPECT_EQ(compute_aabb(PointCloud{}).min, Vec3::Zero());
}

// Points on the rectangle spanned by `u` and `v` from `corner`, every `step` metres (both ends).
void add_strip_test_rect(PointCloud& cloud, const Vec3& corner, const Vec3& u, const Vec3& v,
                         double step = 0.005) {
  const int nu = static_cast<int>(std::lround(u.norm() / step));
  const int nv = static_cast<int>(std::lround(v.norm() / step));
  for (int i = 0; i <= nu; ++i)
    for (int j = 0; j <= nv; ++j)
      cloud.push_back((corner + u * (double(i) / nu) + v * (double(j) / nv)).cast<float>());
}

// A 16 × 6 × 21 cm box standing on a table at z = 0 (its centre at the origin's x, y), seen from
// the front (-y): its front face and top; its mask bled onto the table behind it, a strip
// `strip_depth` deep (from 5 cm behind the box) and as wide as the box plus 4 cm each side.
PointCloud box_seen_from_the_front(double strip_depth) {
  PointCloud cloud;
  add_strip_test_rect(cloud, Vec3(-0.08, -0.03, 0.0), Vec3(0.16, 0, 0), Vec3(0, 0, 0.21));
  add_strip_test_rect(cloud, Vec3(-0.08, -0.03, 0.21), Vec3(0.16, 0, 0), Vec3(0, 0.06, 0));
  if (strip_depth > 0)
    add_strip_test_rect(cloud, Vec3(-0.12, 0.08, 0.0), Vec3(0.24, 0, 0), Vec3(0, strip_depth, 0));
  return cloud;
}

// The table of the strip tests: 1 m² at height 0; a floor of 20 m² under a 75 cm table of 1 m².
const std::vector<SupportPlane> kStripTestTable{{0.0, 1.0}};
const std::vector<SupportPlane> kStripTestFloorAndTable{{0.0, 20.0}, {0.75, 1.0}};

std::size_t count_marked(const std::vector<bool>& marks) {
  return static_cast<std::size_t>(std::count(marks.begin(), marks.end(), true));
}

TEST(SupportStrip, TheTableBehindABoxSeenFromOneSideIsLeftOutOfItsPosition) {
  const PointCloud box = box_seen_from_the_front(0.0);
  const PointCloud cloud = box_seen_from_the_front(0.10);
  const std::size_t strip_points = cloud.size() - box.size();
  ASSERT_LT(strip_points, cloud.size() / 2);  // a minority of the object's points
  const Vec3 true_centre(0.0, 0.0, 0.105);
  // The strip pulls the box of the points 6.5 cm back; without it the box is the seen part's.
  const Vec3 with_strip = percentile_box_centre(cloud, 0.01);
  EXPECT_GT((with_strip - true_centre).norm(), 0.04);
  const std::vector<bool> strip =
      support_strip(cloud, Eigen::Matrix3d::Identity(), kStripTestTable);
  EXPECT_EQ(count_marked(strip), strip_points);
  for (std::size_t i = 0; i < box.size(); ++i) EXPECT_FALSE(strip[i]) << "box point " << i;
  const Vec3 centre = percentile_box_centre(without(cloud, strip), 0.01);
  EXPECT_LT((centre - true_centre).norm(), 0.005);
  // Without a strip nothing is marked: the bottom edge of the face lies under the face.
  EXPECT_EQ(count_marked(support_strip(box, Eigen::Matrix3d::Identity(), kStripTestTable)), 0u);
  // Nor without a plane of the map to rest on.
  EXPECT_EQ(count_marked(support_strip(cloud, Eigen::Matrix3d::Identity(), {})), 0u);
}

TEST(SupportStrip, TheSameInAWorldFrameThatIsNotZUp) {
  const PointCloud cloud = box_seen_from_the_front(0.10);
  const Eigen::Matrix3d world_from_gravity =
      (Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()) * Eigen::AngleAxisd(1.2, Vec3::UnitX()))
          .toRotationMatrix();
  PointCloud turned;
  for (const Vec3f& p : cloud.points)
    turned.push_back((world_from_gravity * p.cast<double>() + Vec3(2, -1, 0.5)).cast<float>());
  const double table_height = (world_from_gravity.transpose() * Vec3(2, -1, 0.5)).z();
  const std::vector<bool> strip =
      support_strip(cloud, Eigen::Matrix3d::Identity(), kStripTestTable);
  EXPECT_GT(count_marked(strip), 0u);
  EXPECT_EQ(support_strip(turned, world_from_gravity.transpose(), {{table_height, 1.0}}), strip);
}

TEST(SupportStrip, AChairsFeetStayAndTheFloorAroundThemGoes) {
  // A seat 44 × 44 cm at 45 cm on four 3.6 cm legs, seen all round; its masks bled onto two strips
  // of the floor 10 cm wide, 6 cm beyond the seat's edges.
  PointCloud chair;
  add_strip_test_rect(chair, Vec3(-0.22, -0.22, 0.45), Vec3(0.44, 0, 0), Vec3(0, 0.44, 0));
  for (double sx : {-0.19, 0.19})
    for (double sy : {-0.19, 0.19})
      for (const Vec3& side : {Vec3(0.036, 0, 0), Vec3(0, 0.036, 0)}) {
        const Vec3 corner(sx - 0.018, sy - 0.018, 0.0);
        add_strip_test_rect(chair, corner, side, Vec3(0, 0, 0.43));
        add_strip_test_rect(chair, corner + Vec3(0.036, 0.036, 0) - side, side, Vec3(0, 0, 0.43));
      }
  PointCloud cloud = chair;
  add_strip_test_rect(cloud, Vec3(-0.38, -0.38, 0.0), Vec3(0.76, 0, 0), Vec3(0, 0.10, 0));
  add_strip_test_rect(cloud, Vec3(-0.38, 0.28, 0.0), Vec3(0.76, 0, 0), Vec3(0, 0.10, 0));
  const std::vector<bool> strip =
      support_strip(cloud, Eigen::Matrix3d::Identity(), kStripTestFloorAndTable);
  for (std::size_t i = 0; i < chair.size(); ++i) ASSERT_FALSE(strip[i]) << "chair point " << i;
  EXPECT_EQ(count_marked(strip), cloud.size() - chair.size());
}

TEST(SupportStrip, AChairsSeatSeenOverATableIsNoSupport) {
  // Seen over a table, a chair shows its seat's front (45 cm up) and its back above: the lowest
  // layer is the seat, outside the footprint of the back, but no plane of the map is there.
  PointCloud chair;
  add_strip_test_rect(chair, Vec3(-0.02, -0.22, 0.45), Vec3(0.24, 0, 0), Vec3(0, 0.44, 0));
  add_strip_test_rect(chair, Vec3(-0.22, -0.22, 0.475), Vec3(0, 0.44, 0), Vec3(0, 0, 0.44));
  EXPECT_EQ(
      count_marked(support_strip(chair, Eigen::Matrix3d::Identity(), kStripTestFloorAndTable)), 0u);
  // The seat found as a surface of the map is the chair's own top, no larger than its footprint.
  EXPECT_EQ(count_marked(support_strip(chair, Eigen::Matrix3d::Identity(), {{0.45, 0.19}})), 0u);
  // A plane of its height larger than twice its footprint would be one (the rule bites).
  EXPECT_GT(count_marked(support_strip(chair, Eigen::Matrix3d::Identity(), {{0.45, 2.0}})), 0u);
}

TEST(SupportStrip, AFlatObjectKeepsItselfAndAThinOneIsLeftAlone) {
  // A book's top 3 cm above the table, the table around it: the table goes, the book stays.
  PointCloud book;
  add_strip_test_rect(book, Vec3(-0.12, -0.085, 0.03), Vec3(0.24, 0, 0), Vec3(0, 0.17, 0));
  PointCloud cloud = book;
  add_strip_test_rect(cloud, Vec3(-0.12, 0.13, 0.0), Vec3(0.24, 0, 0), Vec3(0, 0.06, 0));
  const std::vector<bool> strip =
      support_strip(cloud, Eigen::Matrix3d::Identity(), kStripTestTable);
  EXPECT_EQ(count_marked(strip), cloud.size() - book.size());
  // A sheet 5 mm thick: most of its points are in the lowest layer, so no strip is judged.
  PointCloud sheet;
  add_strip_test_rect(sheet, Vec3(-0.1, -0.1, 0.0), Vec3(0.2, 0, 0), Vec3(0, 0.2, 0));
  add_strip_test_rect(sheet, Vec3(-0.1, -0.1, 0.005), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0));
  EXPECT_EQ(count_marked(support_strip(sheet, Eigen::Matrix3d::Identity(), kStripTestTable)), 0u);
}

TEST(SupportStrip, AHandfulOfPointsIsLeftToThePercentileBox) {
  // The strip behind the box, 1 cm deep and 4 cm wide: under 2 % of the points.
  PointCloud cloud = box_seen_from_the_front(0.0);
  const std::size_t box_points = cloud.size();
  add_strip_test_rect(cloud, Vec3(-0.02, 0.08, 0.0), Vec3(0.04, 0, 0), Vec3(0, 0.01, 0));
  ASSERT_LT(cloud.size() - box_points, box_points / 50);
  EXPECT_EQ(count_marked(support_strip(cloud, Eigen::Matrix3d::Identity(), kStripTestTable)), 0u);
  SupportStripOptions every_strip;
  every_strip.min_strip_share = 0.0;
  EXPECT_EQ(
      count_marked(support_strip(cloud, Eigen::Matrix3d::Identity(), kStripTestTable, every_strip)),
      cloud.size() - box_points);
}

TEST(SupportStrip, OptionsOutOfRangeAreNamed) {
  SupportStripOptions o;
  EXPECT_NO_THROW(o.check());
  o.band_m = 0.0;
  try {
    o.check();
    FAIL() << "band_m 0 accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "SupportStripOptions.band_m");
  }
  o = SupportStripOptions{};
  o.min_body_share = 1.5;
  EXPECT_THROW(o.check(), InputError);
  o = SupportStripOptions{};
  o.area_factor = -1.0;
  EXPECT_THROW(o.check(), InputError);
}

}  // namespace
}  // namespace objmap::geometry

#include "objmap/segmentation/box_mask.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/core/error.h"

namespace objmap::segmentation {
namespace {

// A tiny ray caster: axis-aligned boxes in a world frame with y pointing DOWN (like the camera), so
// "up" is −y. Each pixel gets the depth (camera z) of the nearest box hit and that box's label.
struct Aabb {
  Eigen::Vector3d lo, hi;
  int label;
};

struct Rendered {
  cv::Mat depth;           // CV_16UC1, raw
  std::vector<int> label;  // per pixel, -1 = nothing hit
  int width = 0, height = 0;
  Mask mask_of(int wanted) const {
    Mask m;
    m.width = width;
    m.height = height;
    m.data.assign(label.size(), 0);
    for (std::size_t i = 0; i < label.size(); ++i) m.data[i] = label[i] == wanted;
    return m;
  }
};

// Camera at `position`, looking along +z tilted down by `pitch_rad` (towards +y).
Rendered render(const std::vector<Aabb>& scene, const Camera& cam, const Eigen::Vector3d& position,
                double pitch_rad, double noise_per_m2 = 0.0) {
  const double s = std::sin(pitch_rad), c = std::cos(pitch_rad);
  Eigen::Matrix3d world_from_cam;
  world_from_cam.col(0) = Eigen::Vector3d(1, 0, 0);   // right
  world_from_cam.col(1) = Eigen::Vector3d(0, c, -s);  // down
  world_from_cam.col(2) = Eigen::Vector3d(0, s, c);   // forward
  Rendered r;
  r.width = cam.width;
  r.height = cam.height;
  r.depth = cv::Mat(cam.height, cam.width, CV_16UC1, cv::Scalar(0));
  r.label.assign(static_cast<std::size_t>(cam.width) * cam.height, -1);
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      // Direction with camera z = 1, so the ray parameter t is the depth.
      const Eigen::Vector3d dir =
          world_from_cam * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      double best = std::numeric_limits<double>::infinity();
      int best_label = -1;
      for (const auto& b : scene) {
        double t0 = 0, t1 = best;
        bool hit = true;
        for (int a = 0; a < 3 && hit; ++a) {
          if (std::abs(dir[a]) < 1e-12) {
            hit = position[a] >= b.lo[a] && position[a] <= b.hi[a];
            continue;
          }
          double ta = (b.lo[a] - position[a]) / dir[a], tb = (b.hi[a] - position[a]) / dir[a];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
          hit = t0 <= t1;
        }
        if (hit && t0 > 0 && t0 < best) {
          best = t0;
          best_label = b.label;
        }
      }
      if (best_label < 0) continue;
      double z = best;
      if (noise_per_m2 > 0) z += noise_per_m2 * z * z * gauss(rng);
      r.depth.at<std::uint16_t>(v, u) =
          static_cast<std::uint16_t>(std::lround(z * cam.depth_factor));
      r.label[static_cast<std::size_t>(v) * cam.width + u] = best_label;
    }
  }
  return r;
}

double iou(const Mask& a, const Mask& b) {
  std::size_t inter = 0, uni = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    inter += a.data[i] && b.data[i];
    uni += a.data[i] || b.data[i];
  }
  return uni ? static_cast<double>(inter) / static_cast<double>(uni) : 0.0;
}

std::size_t count(const Mask& m) {
  return static_cast<std::size_t>(std::count(m.data.begin(), m.data.end(), 1));
}

// The bounding box of a mask, grown by `margin` of its size on each side (a loose detection).
Box box_of(const Mask& m, double margin) {
  int u0 = m.width, v0 = m.height, u1 = -1, v1 = -1;
  for (int v = 0; v < m.height; ++v) {
    for (int u = 0; u < m.width; ++u) {
      if (!m.at(u, v)) continue;
      u0 = std::min(u0, u);
      v0 = std::min(v0, v);
      u1 = std::max(u1, u);
      v1 = std::max(v1, v);
    }
  }
  const double w = u1 - u0 + 1, h = v1 - v0 + 1;
  return {u0 - margin * w, v0 - margin * h, w * (1 + 2 * margin), h * (1 + 2 * margin)};
}

enum Label { kTable = 1, kWall = 2, kFloor = 3, kObject = 4 };

// A cuboid (20 × 15 × 12 cm) on a table in front of a wall, seen from 60 cm above the table.
std::vector<Aabb> tabletop_scene() {
  return {
      {{-1.0, 0.0, 0.0}, {1.0, 0.04, 1.6}, kTable},     // table top at y = 0
      {{-3.0, -3.0, 1.6}, {3.0, 3.0, 1.7}, kWall},      // wall behind the table
      {{-3.0, 0.75, -3.0}, {3.0, 0.8, 3.0}, kFloor},    // floor
      {{-0.1, -0.15, 0.8}, {0.1, 0.0, 0.92}, kObject},  // the object, standing on the table
  };
}

const Eigen::Vector3d kTableCamera(0.05, -0.6, 0.0);
constexpr double kTablePitch = 0.55;  // ~31° down

TEST(BoxMask, CuboidOnTableInFrontOfWall) {
  const Camera cam = camera_preset("fr3");
  const Rendered r = render(tabletop_scene(), cam, kTableCamera, kTablePitch);
  const Mask truth = r.mask_of(kObject);
  ASSERT_GT(count(truth), 2000u);
  const Box box = box_of(truth, 0.15);  // the box holds table below/in front and wall behind
  const BoxMaskResult result = mask_from_box(box, r.depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kOk);
  EXPECT_TRUE(result.support_plane_removed);
  EXPECT_EQ(result.pixels, count(result.mask));
  EXPECT_GT(iou(result.mask, truth), 0.9);
  // Without the plane removal the region grows into the table: the plane is what makes it work.
  BoxMaskOptions no_plane;
  no_plane.remove_support_plane = false;
  const BoxMaskResult leaky = mask_from_box(box, r.depth, cam, no_plane);
  EXPECT_FALSE(leaky.support_plane_removed);
  EXPECT_LT(iou(leaky.mask, truth), iou(result.mask, truth));
}

TEST(BoxMask, CuboidWithKinectLikeNoise) {
  const Camera cam = camera_preset("fr3");
  // σ = 2.5 mm · z² (Kinect-like), deterministic seed.
  const Rendered r = render(tabletop_scene(), cam, kTableCamera, kTablePitch, 0.0025);
  const Mask truth = r.mask_of(kObject);
  const BoxMaskResult result = mask_from_box(box_of(truth, 0.15), r.depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kOk);
  EXPECT_GT(iou(result.mask, truth), 0.85);
}

TEST(BoxMask, ModeDepthIsTheObjectsFrontNotTheWall) {
  const Camera cam = camera_preset("fr3");
  const Rendered r = render(tabletop_scene(), cam, kTableCamera, kTablePitch);
  const Mask truth = r.mask_of(kObject);
  const BoxMaskResult result = mask_from_box(box_of(truth, 0.15), r.depth, cam, {});
  // The object spans z ∈ [0.8, 0.92] m in the world; at this pitch its surface is ~0.8–1.1 m deep.
  EXPECT_GT(result.mode_depth_m, 0.75);
  EXPECT_LT(result.mode_depth_m, 1.15);
}

// A chair-like object: a back panel on two legs standing on the floor, the wall far behind, floor
// and wall visible between the legs.
TEST(BoxMask, ThinChairLikeObjectKeepsTheGapsOut) {
  const Camera cam = camera_preset("fr3");
  const std::vector<Aabb> scene = {
      {{-4.0, 0.0, -4.0}, {4.0, 0.05, 6.0}, kFloor},        // floor at y = 0
      {{-4.0, -4.0, 3.5}, {4.0, 0.0, 3.6}, kWall},          // wall 3.5 m ahead
      {{-0.22, -0.95, 2.0}, {0.22, -0.45, 2.04}, kObject},  // back panel
      {{-0.22, -0.45, 2.0}, {-0.18, 0.0, 2.04}, kObject},   // left leg
      {{0.18, -0.45, 2.0}, {0.22, 0.0, 2.04}, kObject},     // right leg
  };
  const Rendered r = render(scene, cam, Eigen::Vector3d(0.1, -0.9, 0.0), 0.2);
  const Mask truth = r.mask_of(kObject);
  ASSERT_GT(count(truth), 1500u);
  const Box box = box_of(truth, 0.08);
  const BoxMaskResult result = mask_from_box(box, r.depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kOk);
  EXPECT_NEAR(result.mode_depth_m, 2.0, 0.15);
  EXPECT_GT(iou(result.mask, truth), 0.85);
  // Of the background between the legs (wall and floor inside the box), at most 2 % is taken.
  std::size_t gap = 0, gap_taken = 0;
  for (int v = static_cast<int>(box.y); v < static_cast<int>(box.y + box.h); ++v) {
    for (int u = static_cast<int>(box.x); u < static_cast<int>(box.x + box.w); ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * r.width + u;
      if (r.label[i] == kObject) continue;
      ++gap;
      gap_taken += result.mask.data[i];
    }
  }
  ASSERT_GT(gap, 1000u);
  EXPECT_LT(static_cast<double>(gap_taken), 0.02 * gap);
}

TEST(BoxMask, ObjectHangingOnAWallWithoutSupport) {
  // A picture frame 5 cm in front of a wall: the "plane" below the box is the wall, which is
  // removed (it is behind the object), and the frame is kept.
  const Camera cam = camera_preset("fr3");
  const std::vector<Aabb> scene = {
      {{-4.0, -4.0, 2.0}, {4.0, 4.0, 2.1}, kWall},
      {{-0.3, -0.2, 1.95}, {0.3, 0.2, 2.0}, kObject},
  };
  const Rendered r = render(scene, cam, Eigen::Vector3d(0, 0, 0), 0.0);
  const Mask truth = r.mask_of(kObject);
  const BoxMaskResult result = mask_from_box(box_of(truth, 0.1), r.depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kOk);
  EXPECT_GT(iou(result.mask, truth), 0.95);
}

TEST(BoxMask, FrontFaceIsNotMistakenForTheSupport) {
  // A large cuboid seen head-on and filling the bottom of the box (no table visible): the bottom
  // rows are the object's own front face; it must not be removed as a "support plane".
  const Camera cam = camera_preset("fr3");
  const std::vector<Aabb> scene = {
      {{-4.0, -4.0, 3.0}, {4.0, 4.0, 3.1}, kWall},
      {{-0.4, -0.3, 1.5}, {0.4, 0.3, 1.9}, kObject},
  };
  const Rendered r = render(scene, cam, Eigen::Vector3d(0, 0, 0), 0.0);
  const Mask truth = r.mask_of(kObject);
  const BoxMaskResult result = mask_from_box(box_of(truth, 0.05), r.depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kOk);
  EXPECT_GT(iou(result.mask, truth), 0.95);
}

TEST(BoxMask, OccluderInFrontOfTheBoxCentreIsNotTaken) {
  // A 16 cm pole 50 cm in front of a cuboid crosses the whole image vertically, right through the
  // box centre: it is the nearest surface in the centre, but it runs on beyond the box, so the
  // cuboid behind it is taken — both halves, left and right of the pole.
  const Camera cam = camera_preset("fr3");
  constexpr int kPole = 5;
  const std::vector<Aabb> scene = {
      {{-4.0, -4.0, 3.0}, {4.0, 4.0, 3.1}, kWall},
      {{-0.3, -0.25, 1.8}, {0.3, 0.25, 2.1}, kObject},
      {{-0.08, -3.0, 1.3}, {0.08, 3.0, 1.36}, kPole},
  };
  const Rendered r = render(scene, cam, Eigen::Vector3d(0, 0, 0), 0.0);
  const Mask truth = r.mask_of(kObject);
  const BoxMaskResult result = mask_from_box(box_of(truth, 0.0), r.depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kOk);
  EXPECT_NEAR(result.mode_depth_m, 1.8, 0.05);
  EXPECT_GT(iou(result.mask, truth), 0.95);
  EXPECT_LT(result.border_leak, 0.5);
  std::size_t left = 0, right = 0;
  for (int v = 0; v < r.height; ++v) {
    for (int u = 0; u < r.width; ++u) (u < 320 ? left : right) += result.mask.at(u, v);
  }
  EXPECT_GT(left, count(truth) / 3);
  EXPECT_GT(right, count(truth) / 3);
  // With a single candidate depth the pole is what comes out.
  BoxMaskOptions nearest_only;
  nearest_only.depth_candidates = 1;
  const BoxMaskResult pole = mask_from_box(box_of(truth, 0.0), r.depth, cam, nearest_only);
  EXPECT_LT(iou(pole.mask, truth), 0.1);
  EXPECT_GT(pole.border_leak, 0.5);
}

TEST(BoxMask, NoValidDepthGivesAnEmptyMask) {
  const Camera cam = camera_preset("fr3");
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(0));
  depth(cv::Rect(0, 0, 100, 100)).setTo(5000);  // depth elsewhere, none in the box
  const BoxMaskResult result = mask_from_box({200, 150, 120, 90}, depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kNoValidDepth);
  EXPECT_EQ(result.pixels, 0u);
  EXPECT_EQ(result.valid_pixels, 0u);
  EXPECT_EQ(result.mask.width, 640);
  EXPECT_EQ(result.mask.height, 480);
  EXPECT_EQ(count(result.mask), 0u);
  // Depths outside [min_depth_m, max_depth_m] are not valid either.
  depth.setTo(65535);  // 13.1 m
  EXPECT_EQ(mask_from_box({200, 150, 120, 90}, depth, cam, {}).status,
            BoxMaskStatus::kNoValidDepth);
}

TEST(BoxMask, BoxPartlyOutsideTheImageIsClipped) {
  const Camera cam = camera_preset("fr3");
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(3.0 * 5000));  // wall at 3 m
  depth(cv::Rect(560, 400, 80, 80)).setTo(1.0 * 5000);        // an object in the corner at 1 m
  const BoxMaskResult result = mask_from_box({540, 380, 200, 200}, depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kOk);
  EXPECT_EQ(result.u0, 540);
  EXPECT_EQ(result.v0, 380);
  EXPECT_EQ(result.u1, 640);
  EXPECT_EQ(result.v1, 480);
  EXPECT_EQ(result.pixels, 80u * 80u);
  EXPECT_EQ(result.bounds, cv::Rect(560, 400, 80, 80));
  for (int v = 400; v < 480; ++v) {
    for (int u = 560; u < 640; ++u) ASSERT_EQ(result.mask.at(u, v), 1) << u << "," << v;
  }
  EXPECT_NEAR(result.mode_depth_m, 1.0, 1e-6);
  // Entirely outside: empty, no throw.
  const BoxMaskResult outside = mask_from_box({700, -300, 50, 50}, depth, cam, {});
  EXPECT_EQ(outside.status, BoxMaskStatus::kOutsideImage);
  EXPECT_EQ(count(outside.mask), 0u);
  const BoxMaskResult nan_box = mask_from_box({std::nan(""), 10, 20, 20}, depth, cam, {});
  EXPECT_NE(nan_box.status, BoxMaskStatus::kOk);
}

TEST(BoxMask, TinyRegionIsEmpty) {
  const Camera cam = camera_preset("fr3");
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(0));
  depth(cv::Rect(300, 200, 3, 3)).setTo(5000);  // 9 pixels in a 100 × 100 box
  const BoxMaskResult result = mask_from_box({250, 150, 100, 100}, depth, cam, {});
  EXPECT_EQ(result.status, BoxMaskStatus::kTooSmall);
  EXPECT_EQ(count(result.mask), 0u);
  EXPECT_TRUE(result.bounds.empty());
  BoxMaskOptions small;
  small.min_pixels = 5;
  small.min_box_fraction = 0;
  EXPECT_EQ(mask_from_box({250, 150, 100, 100}, depth, cam, small).pixels, 9u);
}

TEST(BoxMask, IsDeterministic) {
  const Camera cam = camera_preset("fr3");
  const Rendered r = render(tabletop_scene(), cam, kTableCamera, kTablePitch, 0.0025);
  const Box box = box_of(r.mask_of(kObject), 0.15);
  const BoxMaskResult a = mask_from_box(box, r.depth, cam, {});
  const BoxMaskResult b = mask_from_box(box, r.depth, cam, {});
  EXPECT_EQ(a.mask.data, b.mask.data);
  EXPECT_EQ(a.support_plane_in_cam, b.support_plane_in_cam);
}

TEST(BoxMask, BadInputsThrow) {
  const Camera cam = camera_preset("fr3");
  cv::Mat wrong(480, 640, CV_32FC1, cv::Scalar(1.0));
  try {
    mask_from_box({0, 0, 10, 10}, wrong, cam, {});
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "mask_from_box: depth");
    EXPECT_NE(e.reason().find("CV_16UC1"), std::string::npos);
  }
  Camera bad = cam;
  bad.depth_factor = 0;
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(5000));
  EXPECT_THROW(mask_from_box({0, 0, 10, 10}, depth, bad, {}), InputError);
}

void expect_bad_field(const BoxMaskOptions& options, const std::string& field) {
  try {
    options.check();
    FAIL() << "check() accepted a bad " << field;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "BoxMaskOptions." + field) << e.what();
  }
}

TEST(BoxMask, OptionsCheckNamesTheBadField) {
  EXPECT_NO_THROW(BoxMaskOptions{}.check());
  BoxMaskOptions o;
  o.bin_m = 0;
  expect_bad_field(o, "bin_m");
  o = {};
  o.max_depth_m = 0.05;
  expect_bad_field(o, "max_depth_m");
  o = {};
  o.connectivity = 6;
  expect_bad_field(o, "connectivity");
  o = {};
  o.near_mode_min_share = 1.5;
  expect_bad_field(o, "near_mode_min_share");
  o = {};
  o.support_inlier_m = -0.01;
  expect_bad_field(o, "support_inlier_m");
  o = {};
  o.band_max_m = 0.01;
  expect_bad_field(o, "band_max_m");
  o = {};
  o.support_ransac_iterations = 0;
  expect_bad_field(o, "support_ransac_iterations");
  o = {};
  o.close_radius_px = -1;
  expect_bad_field(o, "close_radius_px");
  o = {};
  o.depth_candidates = 0;
  expect_bad_field(o, "depth_candidates");
  o = {};
  o.support_max_beyond_share = 2;
  expect_bad_field(o, "support_max_beyond_share");
  o = {};
  o.seed_center_fraction = std::nan("");
  expect_bad_field(o, "seed_center_fraction");
  try {
    o = {};
    o.connectivity = 6;
    o.check();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("got 6"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace objmap::segmentation

#include "objmap/segmentation/depth_gate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "mask_test_util.h"
#include "objmap/core/error.h"
#include "objmap/segmentation/mask_refine.h"

namespace objmap::segmentation {
namespace {

using test_masks::camera;
using test_masks::count;
using test_masks::mask_of;

constexpr double kFactor = 5000.0;

std::uint16_t raw(double z_m) { return static_cast<std::uint16_t>(z_m * kFactor + 0.5); }

cv::Mat flat_at(double z_m) { return cv::Mat(480, 640, CV_16UC1, cv::Scalar(raw(z_m))); }

TEST(DepthGate, BleedJoinedByARampIsRemovedWhereRefineKeepsIt) {
  // A can-sized object (60 × 80 px at 0.8 m: 9 × 12 cm) and a mask that bleeds 4 px over its top
  // edge onto a background that recedes smoothly (a table seen at a grazing angle, or the ramp of
  // mixed pixels a sensor draws along an occlusion edge): 1 cm deeper per row, so the bleed is
  // one smooth part with the object and refine_mask keeps it.
  cv::Mat depth = flat_at(2.0);
  const cv::Rect object(300, 200, 60, 80);
  depth(object).setTo(cv::Scalar(raw(0.8)));
  const cv::Rect bleed(300, 150, 60, 50);  // rows 150..199, the bleed
  for (int v = bleed.y; v < bleed.y + bleed.height; ++v)
    depth.row(v)
        .colRange(bleed.x, bleed.x + bleed.width)
        .setTo(cv::Scalar(raw(0.8 + 0.010 * (object.y - v))));
  const cv::Rect mask_rect(300, 196, 60, 84);  // 4 bleed rows: 0.81..0.84 m
  cv::Rect long_rect(300, 150, 60, 130);       // the whole ramp: up to 1.3 m
  const MaskRefineResult refined = refine_mask(mask_of(long_rect), long_rect, depth, camera());
  EXPECT_EQ(refined.removed_pixels, 0u) << "the ramp is one smooth part with the object";

  // Near bleed (4 rows, up to 4 cm behind): inside the band, kept.
  const DepthGateResult near = gate_mask_depth(mask_of(mask_rect), mask_rect, depth, camera());
  EXPECT_EQ(near.removed_pixels, 0u);
  EXPECT_TRUE(near.mask.empty()) << "nothing removed: no copy";
  EXPECT_EQ(near.pixels, 60u * 84u);
  EXPECT_NEAR(near.median_depth_m, 0.8, 1e-3);

  // The whole ramp: S = sqrt(60 · 130) px · z_med / f; pixels more than S (+ noise) behind z_med
  // go.
  const DepthGateResult far = gate_mask_depth(mask_of(long_rect), long_rect, depth, camera());
  EXPECT_NEAR(far.median_depth_m, 0.8, 1e-3);
  EXPECT_NEAR(far.size_m, std::sqrt(60.0 * 130.0) / 525.0 * 0.8, 1e-3);
  EXPECT_NEAR(far.band_m, far.size_m + 0.005 * 0.64, 1e-6);
  std::size_t expected = 0;
  for (int v = long_rect.y; v < object.y; ++v)
    expected += (depth.at<std::uint16_t>(v, 300) > raw(0.8 + far.band_m)) ? 60 : 0;
  EXPECT_GT(expected, 0u);
  EXPECT_EQ(far.removed_pixels, expected);
  EXPECT_EQ(count(far.mask), 60u * 130u - expected);
  EXPECT_EQ(far.bounds.y + far.bounds.height, object.y + object.height);
  EXPECT_GT(far.bounds.y, long_rect.y);
}

TEST(DepthGate, FarBleedAndAnOccluderInFrontGo) {
  // A box at 1.5 m (S = 29 cm); 3 % of its mask sees the floor 1 m behind, a hand-sized patch 1 m
  // in front.
  cv::Mat depth = flat_at(1.5);
  const cv::Rect mask_rect(100, 100, 100, 100);
  depth(cv::Rect(100, 197, 100, 3)).setTo(cv::Scalar(raw(2.5)));  // 300 px far
  depth(cv::Rect(100, 100, 10, 10)).setTo(cv::Scalar(raw(0.5)));  // 100 px in front
  depth(cv::Rect(150, 150, 5, 5)).setTo(cv::Scalar(0));           // 25 px without depth
  const DepthGateResult r = gate_mask_depth(mask_of(mask_rect), mask_rect, depth, camera());
  EXPECT_EQ(r.pixels, 10000u - 25u);
  EXPECT_EQ(r.removed_pixels, 400u);
  EXPECT_EQ(count(r.mask), 10000u - 400u) << "pixels without depth stay";
  EXPECT_EQ(r.bounds, cv::Rect(100, 100, 100, 97));
}

TEST(DepthGate, ASlantedLargeObjectKeepsItsWholeDepthRange) {
  // A table top seen at a grazing angle: 400 × 150 px, depth 1.0 m at the bottom row to 2.0 m at
  // the top: S ≈ sqrt(400 · 150) / 525 × 1.5 m = 0.7 m > its 0.5 m half-range.
  cv::Mat depth = flat_at(3.5);
  const cv::Rect top(100, 200, 400, 150);
  for (int v = top.y; v < top.y + top.height; ++v)
    depth.row(v)
        .colRange(top.x, top.x + top.width)
        .setTo(cv::Scalar(raw(2.0 - (v - top.y) / 149.0)));
  const DepthGateResult r = gate_mask_depth(mask_of(top), top, depth, camera());
  EXPECT_EQ(r.removed_pixels, 0u);
  EXPECT_GT(r.band_m, 0.5);
}

TEST(DepthGate, SmallObjectsHaveTheMinimumBand) {
  // 10 × 10 px at 1 m: S = 1.9 cm, the band is min_band_m (5 cm) + noise (0.5 cm).
  cv::Mat depth = flat_at(1.0);
  const cv::Rect r(10, 10, 10, 10);
  depth(cv::Rect(10, 10, 10, 1)).setTo(cv::Scalar(raw(1.05)));  // 5 cm behind: kept
  depth(cv::Rect(10, 11, 10, 1)).setTo(cv::Scalar(raw(1.06)));  // 6 cm behind: removed
  const DepthGateResult g = gate_mask_depth(mask_of(r), r, depth, camera());
  EXPECT_NEAR(g.band_m, 0.055, 1e-9);
  EXPECT_EQ(g.removed_pixels, 10u);
}

TEST(DepthGate, BadInputIsNamed) {
  const cv::Rect r(10, 10, 10, 10);
  const cv::Mat wrong(480, 640, CV_32FC1, cv::Scalar(1.0));
  try {
    gate_mask_depth(mask_of(r), r, wrong, camera());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gate_mask_depth: depth"), std::string::npos) << e.what();
  }
  DepthGateOptions o;
  o.size_factor = 0;
  try {
    o.check();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("DepthGateOptions.size_factor"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace objmap::segmentation

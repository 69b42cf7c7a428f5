#include "objmap/segmentation/mask_refine.h"

#include <gtest/gtest.h>

#include <string>

#include "mask_test_util.h"
#include "objmap/core/error.h"

namespace objmap::segmentation {
namespace {

using test_masks::add;
using test_masks::camera;
using test_masks::count;
using test_masks::fill;
using test_masks::flat;
using test_masks::mask_of;

TEST(MaskRefine, SpillOntoTheBackgroundIsRemoved) {
  // An object at 1 m in front of a wall at 2 m; its mask spills 2 px over the outline.
  cv::Mat depth = flat(2.0);
  const cv::Rect object(200, 150, 60, 40);
  fill(depth, object, 1.0);
  const cv::Rect spilled(198, 148, 64, 44);
  const Mask mask = mask_of(spilled);
  const MaskRefineResult r = refine_mask(mask, spilled, depth, camera());
  EXPECT_EQ(r.parts, 2u);
  EXPECT_EQ(r.removed_parts, 1u);
  EXPECT_EQ(r.removed_pixels, 64u * 44u - 60u * 40u);
  EXPECT_EQ(r.mask.data, mask_of(object).data);
  EXPECT_EQ(r.bounds, object);
}

TEST(MaskRefine, PartsDeeperThanTheRimOrLargeEnoughStay) {
  cv::Mat depth = flat(3.0);
  const cv::Rect body(200, 150, 60, 40);  // 2400 px at 1 m
  const cv::Rect leg(300, 150, 10, 30);   // 300 px at 1.3 m: its own part, but not a rim
  const cv::Rect strip(400, 150, 2, 80);  // 160 px, 2 px wide: rim, small -> spill
  fill(depth, body, 1.0);
  fill(depth, leg, 1.3);
  fill(depth, strip, 1.6);
  Mask mask = mask_of(body);
  add(mask, leg);
  add(mask, strip);
  const cv::Rect bounds(200, 150, 202, 80);
  MaskRefineResult r = refine_mask(mask, bounds, depth, camera());
  EXPECT_EQ(r.parts, 3u);
  EXPECT_EQ(r.removed_parts, 1u);
  EXPECT_EQ(r.removed_pixels, 160u);
  EXPECT_EQ(count(r.mask), 2400u + 300u);
  EXPECT_EQ(r.bounds, cv::Rect(200, 150, 110, 40));

  // A thin part with at least min_part_share of the largest part's pixels stays.
  MaskRefineOptions options;
  options.min_part_share = 160.0 / 2400.0;
  r = refine_mask(mask, bounds, depth, camera(), options);
  EXPECT_EQ(r.removed_parts, 0u);
  EXPECT_EQ(r.mask.data, mask.data);
  EXPECT_EQ(r.bounds, bounds);
}

TEST(MaskRefine, SmoothSlantedSurfacesAndPixelsWithoutDepthStay) {
  // A floor seen at a grazing angle: depth grows by 1.5 cm per row from 1.5 m (a 75° slant, below
  // the 80° of the step); some pixels have no depth.
  cv::Mat depth = flat(0.0);
  for (int v = 200; v < 300; ++v)
    depth.row(v).setTo(cv::Scalar(static_cast<int>((1.5 + 0.015 * (v - 200)) * 5000.0)));
  for (int u = 250; u < 260; ++u) depth.at<std::uint16_t>(240, u) = 0;
  const cv::Rect r(220, 200, 80, 100);
  const Mask mask = mask_of(r);
  const MaskRefineResult out = refine_mask(mask, r, depth, camera());
  EXPECT_EQ(out.parts, 1u);
  EXPECT_EQ(out.removed_pixels, 0u);
  EXPECT_EQ(out.mask.data, mask.data);
}

TEST(MaskRefine, BadInputNamesTheField) {
  const cv::Mat depth = flat(1.0);
  const Mask mask = mask_of(cv::Rect(10, 10, 5, 5));
  MaskRefineOptions options;
  options.rim_px = -1;
  try {
    refine_mask(mask, cv::Rect(10, 10, 5, 5), depth, camera(), options);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("MaskRefineOptions.rim_px"), std::string::npos)
        << e.what();
  }
  options = MaskRefineOptions{};
  options.min_part_share = 1.5;
  EXPECT_THROW(refine_mask(mask, cv::Rect(10, 10, 5, 5), depth, camera(), options), InputError);
  const cv::Mat small(240, 320, CV_16UC1, cv::Scalar(5000));
  try {
    refine_mask(mask, cv::Rect(10, 10, 5, 5), small, camera());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("refine_mask: depth"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("640x480"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace objmap::segmentation

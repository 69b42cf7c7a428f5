#include "objmap/segmentation/instance_masks.h"

#include <gtest/gtest.h>

#include <string>

#include "mask_test_util.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

using test::error_of;
using test_masks::camera;
using test_masks::count;
using test_masks::fill;
using test_masks::flat;
using test_masks::mask_of;

Instance instance(const std::string& cls, double score, const cv::Rect& box, bool with_mask) {
  Instance i;
  i.class_name = cls;
  i.score = score;
  i.bbox = {double(box.x), double(box.y), double(box.width), double(box.height)};
  if (with_mask) i.mask = mask_of(box);
  return i;
}

// An object at 1 m in front of a wall at 2 m, its given mask spilling 2 px over the outline onto
// the wall, and a second object whose mask is exact.
struct SpillScene {
  cv::Mat depth = flat(2.0);
  cv::Rect object{200, 150, 60, 40};
  cv::Rect spilled{198, 148, 64, 44};
  cv::Rect other{400, 300, 50, 50};
  FrameSegmentation seg;
  SpillScene() {
    fill(depth, object, 1.0);
    fill(depth, other, 1.2);
    seg.source = "frame.json";
    seg.instances = {instance("cup", 0.9, spilled, true), instance("book", 0.8, other, true)};
  }
};

TEST(InstanceMasks, SpillOfAGivenMaskIsRemovedByEitherCleanUpAndAnExactMaskIsUsedAsGiven) {
  SpillScene s;
  const std::size_t spill = 64u * 44u - 60u * 40u;
  for (const bool refine : {true, false}) {
    InstanceMaskOptions o;
    o.refine.enabled = refine;  // without refine_mask the depth gate removes the spill
    InstanceMaskCounts n;
    const auto masks = make_instance_masks(s.seg, s.depth, camera(), o, n);
    ASSERT_EQ(masks.size(), 2u);
    EXPECT_EQ(masks[0].instance, &s.seg.instances[0]);
    EXPECT_EQ(masks[0].given, nullptr) << "a cleaned mask is owned";
    EXPECT_EQ(masks[0].mask().data, mask_of(s.object).data) << "refine " << refine;
    EXPECT_EQ(masks[0].bounds, s.object);
    EXPECT_EQ(masks[0].cls, "cup");
    EXPECT_EQ(masks[1].given, &*s.seg.instances[1].mask) << "nothing removed: no copy";
    EXPECT_EQ(masks[1].bounds, s.other);
    EXPECT_EQ(n.instances, 2u);
    EXPECT_EQ(n.refined, refine ? 1u : 0u);
    EXPECT_EQ(n.refine_pixels_removed, refine ? spill : 0u);
    EXPECT_EQ(n.depth_gated, refine ? 0u : 1u);
    EXPECT_EQ(n.gate_pixels_removed, refine ? 0u : spill);
    EXPECT_EQ(n.empty + n.below_score + n.from_box + n.duplicates, 0u);
  }
  // Both clean-ups off (the paper): the masks as given.
  InstanceMaskOptions off;
  off.refine.enabled = false;
  off.gate.enabled = false;
  InstanceMaskCounts n;
  const auto masks = make_instance_masks(s.seg, s.depth, camera(), off, n);
  ASSERT_EQ(masks.size(), 2u);
  EXPECT_EQ(masks[0].given, &*s.seg.instances[0].mask);
  EXPECT_EQ(masks[0].bounds, s.spilled);
}

TEST(InstanceMasks, BoxesGetAMaskFromTheDepthAndInstancesBelowTheScoreOrWithoutPixelsAreLeftOut) {
  SpillScene s;
  const cv::Rect no_depth(20, 20, 40, 40);
  fill(s.depth, no_depth, 0.0);
  Instance empty_mask = instance("cup", 0.9, no_depth, true);
  empty_mask.mask->data.assign(empty_mask.mask->data.size(), 0);
  s.seg.instances = {instance("bottle", 0.3, s.other, true),            // below the score
                     instance("cup", 0.9, no_depth, false),             // box without depth
                     instance("book", 0.7, {190, 140, 80, 60}, false),  // box around the object
                     empty_mask, instance("book", 0.8, s.other, true)};
  InstanceMaskOptions o;
  o.min_score = 0.5;
  InstanceMaskCounts n;
  const auto masks = make_instance_masks(s.seg, s.depth, camera(), o, n);
  ASSERT_EQ(masks.size(), 2u);
  EXPECT_EQ(masks[0].instance, &s.seg.instances[2]);
  EXPECT_EQ(masks[1].instance, &s.seg.instances[4]);
  // The box mask is the object in front of the wall, its pixels counted.
  EXPECT_EQ(masks[0].given, nullptr);
  EXPECT_EQ(masks[0].bounds, s.object);
  EXPECT_EQ(masks[0].pixels, count(masks[0].mask()));
  EXPECT_EQ(masks[0].pixels, 60u * 40u);
  EXPECT_EQ(n.instances, 5u);
  EXPECT_EQ(n.below_score, 1u);
  EXPECT_EQ(n.from_box, 2u);
  EXPECT_EQ(n.empty, 2u);
}

// Two instances of one class: a keyboard, and the keyboard with the desk around it.
struct TwoBoxes {
  cv::Rect inner{100, 100, 100, 50};
  cv::Rect outer{90, 90, 140, 80};
  FrameSegmentation seg;
  std::vector<InstanceMask> masks(double inner_score, double outer_score) {
    seg.instances = {instance("keyboard", outer_score, outer, true),
                     instance("keyboard", inner_score, inner, true)};
    InstanceMaskOptions o;
    o.refine.enabled = false;
    o.gate.enabled = false;
    InstanceMaskCounts n;
    return make_instance_masks(seg, flat(1.0), camera(), o, n);
  }
};

TEST(DropDuplicates, TheLowerScoredBoxOfOneObjectIsDroppedAndTheOrderKept) {
  TwoBoxes t;
  std::vector<InstanceMask> masks = t.masks(0.9, 0.6);
  InstanceMaskCounts n;
  drop_duplicates(masks, 0.5, n);
  ASSERT_EQ(masks.size(), 1u);
  EXPECT_EQ(masks[0].instance, &t.seg.instances[1]) << "the higher score stays";
  EXPECT_EQ(masks[0].mask().data, mask_of(t.inner).data);
  EXPECT_EQ(n.duplicates, 1u);

  // Equal scores: the one listed first stays.
  masks = t.masks(0.7, 0.7);
  drop_duplicates(masks, 0.5, n);
  ASSERT_EQ(masks.size(), 1u);
  EXPECT_EQ(masks[0].instance, &t.seg.instances[0]);
  EXPECT_EQ(n.duplicates, 2u);

  // overlap 1 keeps both; so does another class.
  masks = t.masks(0.9, 0.6);
  drop_duplicates(masks, 1.0, n);
  EXPECT_EQ(masks.size(), 2u);
  masks[0].cls = "tv";
  drop_duplicates(masks, 0.5, n);
  EXPECT_EQ(masks.size(), 2u);
  EXPECT_EQ(n.duplicates, 2u);
}

TEST(DropDuplicates, BoxesOrMasksLessInsideThanTheOverlapAreTwoObjects) {
  TwoBoxes t;
  t.inner = {180, 100, 100, 50};  // 50 of its 100 columns inside the outer box: a share of 0.5
  std::vector<InstanceMask> masks = t.masks(0.9, 0.6);
  InstanceMaskCounts n;
  drop_duplicates(masks, 0.6, n);
  EXPECT_EQ(masks.size(), 2u);
  drop_duplicates(masks, 0.5, n);
  EXPECT_EQ(masks.size(), 1u);

  // The boxes nest, but the masks do not: two objects.
  t.inner = {100, 100, 100, 50};
  masks = t.masks(0.9, 0.6);
  masks[1].owned = mask_of({240, 300, 10, 10});  // the inner instance's mask elsewhere
  masks[1].given = nullptr;
  masks[1].pixels = InstanceMask::kPixelsUnknown;
  masks[1].bounds = {240, 300, 10, 10};
  drop_duplicates(masks, 0.5, n);
  EXPECT_EQ(masks.size(), 2u);
  // clean_instance_masks applies the rule with options.duplicate_overlap.
  InstanceMaskOptions o;
  o.duplicate_overlap = 0.5;
  InstanceMaskCounts counts;
  EXPECT_EQ(clean_instance_masks(t.seg, flat(1.0), camera(), o, counts).size(), 1u);
  EXPECT_EQ(counts.duplicates, 1u);
  EXPECT_EQ(counts.instances, 2u);
}

TEST(InstanceMasks, BadOptionsAndInputsNameTheField) {
  SpillScene s;
  InstanceMaskCounts n;
  const auto error = [&](const InstanceMaskOptions& o, const cv::Mat& depth) {
    return error_of([&] { make_instance_masks(s.seg, depth, camera(), o, n); });
  };
  InstanceMaskOptions o;
  o.min_score = 1.5;
  EXPECT_NE(error(o, s.depth).find("InstanceMaskOptions.min_score"), std::string::npos);
  o = {};
  o.duplicate_overlap = 0;
  EXPECT_NE(error(o, s.depth).find("InstanceMaskOptions.duplicate_overlap"), std::string::npos);
  o = {};
  o.gate.size_factor = -1;
  EXPECT_NE(error(o, s.depth).find("DepthGateOptions.size_factor"), std::string::npos);
  o = {};
  EXPECT_NE(error(o, cv::Mat(480, 640, CV_8UC1, cv::Scalar(1))).find("make_instance_masks: depth"),
            std::string::npos);
  s.seg.instances[1].mask->width = 320;
  s.seg.instances[1].mask->height = 240;
  EXPECT_EQ(
      error(o, s.depth),
      "make_instance_masks: frame.json: instances[1].mask: mask is 320x240 with 307200 values; "
      "expected 640x480 like the depth image");
  std::vector<InstanceMask> none;
  EXPECT_NE(error_of([&] { drop_duplicates(none, 1.5, n); }).find("drop_duplicates: overlap"),
            std::string::npos);
}

}  // namespace
}  // namespace objmap::segmentation

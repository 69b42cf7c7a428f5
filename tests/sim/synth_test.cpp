#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "objmap/core/error.h"
#include "objmap/sim/synth.h"
#include "objmap/sim/writer.h"

namespace objmap::sim {
namespace {

SynthOptions small(std::uint64_t seed, int threads) {
  SynthOptions o;
  o.seed = seed;
  o.frames = 4;
  o.resolution_scale = 0.25;
  o.threads = threads;
  return o;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

bool same(const segmentation::FrameSegmentation& a, const segmentation::FrameSegmentation& b) {
  if (a.instances.size() != b.instances.size() || a.timestamp != b.timestamp) return false;
  for (std::size_t i = 0; i < a.instances.size(); ++i) {
    const auto &x = a.instances[i], &y = b.instances[i];
    if (x.class_name != y.class_name || x.score != y.score || x.track_id != y.track_id ||
        x.mask->data != y.mask->data)
      return false;
  }
  return true;
}

TEST(Synth, SameSeedSameSequenceWhateverTheThreads) {
  const SynthSequence a = synthesize(small(7, 1));
  const SynthSequence b = synthesize(small(7, 2));
  ASSERT_EQ(a.frames.size(), 4u);
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_TRUE(same(a.frames[i].rgb, b.frames[i].rgb));
    EXPECT_TRUE(same(a.frames[i].depth, b.frames[i].depth));
    EXPECT_TRUE(same(a.frames[i].labels, b.frames[i].labels));
    EXPECT_TRUE(same(a.frames[i].segmentation, b.frames[i].segmentation));
    EXPECT_TRUE(same(a.frames[i].segmentation_gt, b.frames[i].segmentation_gt));
    EXPECT_TRUE(
        a.groundtruth.poses[i].world_from_cam.isApprox(b.groundtruth.poses[i].world_from_cam, 0));
    EXPECT_TRUE(
        a.estimated.poses[i].world_from_cam.isApprox(b.estimated.poses[i].world_from_cam, 0));
  }
  EXPECT_EQ(objects_gt_json(a.scene), objects_gt_json(b.scene));
}

TEST(Synth, DifferentSeedDifferentSequence) {
  const SynthSequence a = synthesize(small(7, 0));
  const SynthSequence c = synthesize(small(8, 0));
  EXPECT_FALSE(same(a.frames[0].rgb, c.frames[0].rgb));
  EXPECT_FALSE(same(a.frames[0].depth, c.frames[0].depth));
  EXPECT_NE(objects_gt_json(a.scene), objects_gt_json(c.scene));
}

TEST(Synth, TimestampsSurviveSixDecimalsAndDepthIsOffset) {
  SynthOptions o = small(1, 0);
  o.frames = 40;
  o.resolution_scale = 0.1;
  const SynthSequence s = synthesize(o);
  for (const auto& f : s.frames) {
    EXPECT_EQ(std::strtod(timestamp_name(f.timestamp).c_str(), nullptr), f.timestamp);
    EXPECT_EQ(std::strtod(timestamp_name(f.depth_timestamp).c_str(), nullptr), f.depth_timestamp);
    EXPECT_NEAR(f.depth_timestamp - f.timestamp, 0.005, 1.5e-6);
    EXPECT_EQ(f.timestamp, s.groundtruth.poses[f.index].timestamp);
  }
  EXPECT_NEAR(s.frames[30].timestamp - s.frames[0].timestamp, 1.0, 1e-6);  // 30 Hz
}

TEST(Synth, EstimateDriftsByTheConfiguredFractionOfThePath) {
  SynthOptions o = small(3, 0);
  o.frames = 90;
  o.resolution_scale = 0.05;
  for (double fraction : {0.01, 0.03}) {
    o.drift.translation_fraction = fraction;
    const SynthSequence s = synthesize(o);
    const double length = path_length_m(s.groundtruth);
    EXPECT_GT(length, 1.5);  // the default orbit: 80 degrees at 1.6 m
    const double end = (s.estimated.poses.back().world_from_cam.translation() -
                        s.groundtruth.poses.back().world_from_cam.translation())
                           .norm();
    EXPECT_NEAR(end / length, fraction, 0.004) << fraction;
    // Starts on the ground truth.
    EXPECT_TRUE(
        s.estimated.poses[0].world_from_cam.isApprox(s.groundtruth.poses[0].world_from_cam));
  }
}

TEST(Synth, CameraKeepsTheTableInView) {
  SynthOptions o = small(2, 0);
  o.frames = 30;
  o.resolution_scale = 0.25;
  o.seg_noise.min_area_px = 4;
  for (const std::string preset : {"tabletop", "office"}) {
    o.preset = preset;
    const SynthSequence s = synthesize(o);
    for (const auto& f : s.frames) {
      // Most of the ground-truth objects are seen in every frame.
      EXPECT_GE(f.segmentation_gt.instances.size() + 0.0, 0.5 * s.scene.objects.size())
          << preset << " frame " << f.index;
    }
  }
}

TEST(Synth, BadOptionsNameTheOption) {
  SynthOptions o;
  o.frames = 0;
  try {
    synthesize(o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--frames");
    EXPECT_EQ(std::string(e.what()), "--frames: must be in [1, 100000], got 0");
  }
  o.frames = 3;
  o.preset = "garden";
  EXPECT_THROW(synthesize(o), InputError);
}

}  // namespace
}  // namespace objmap::sim

#include <gtest/gtest.h>
#include <algorithm>
#include <nlohmann/json.hpp>
#include <set>

#include <cstdio>
#include <cstdlib>

#include <opencv2/imgcodecs.hpp>

#include "objmap/core/error.h"
#include "objmap/sim/camera_path.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/synth.h"
#include "objmap/sim/writer.h"
#include "support/test_support.h"

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

// Expects every file under `a` to have an identical twin under `b`; returns how many were compared.
int expect_same_files(const test::fs::path& a, const test::fs::path& b) {
  int compared = 0;
  for (const auto& e : test::fs::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    const auto rel = test::fs::relative(e.path(), a);
    EXPECT_EQ(test::read_text(e.path()), test::read_text(b / rel)) << rel;
    ++compared;
  }
  return compared;
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
    o.seed += 1;
    const SynthSequence s = synthesize(o);
    const double length = path_length_m(s.groundtruth);
    EXPECT_GT(length, 1.5);  // the default orbit: 3 s at 20 deg/s and 1.6 m
    const double end = (s.estimated.poses.back().world_from_cam.translation() -
                        s.groundtruth.poses.back().world_from_cam.translation())
                           .norm();
    EXPECT_NEAR(end / length, fraction, 0.002) << fraction;  // 1 mm white noise / 1.7 m
    // Starts on the ground truth.
    EXPECT_TRUE(
        s.estimated.poses[0].world_from_cam.isApprox(s.groundtruth.poses[0].world_from_cam));
  }
}

TEST(Synth, DriftFractionHoldsForEverySeedYawIncluded) {
  std::vector<double> timestamps;
  for (int i = 0; i < 90; ++i) timestamps.push_back(frame_timestamp(0.0, 30.0, i));
  DriftOptions o;
  o.white_noise_m = 0.0;
  o.yaw_deg_per_m = 3.0;  // large: the cap on the yaw's share must keep the end error exact
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Trajectory gt = make_camera_path(CameraPathOptions{}, timestamps, seed);
    const double length = path_length_m(gt);
    for (double fraction : {0.01, 0.02, 0.03}) {
      o.translation_fraction = fraction;
      const Trajectory est = add_drift(gt, o, seed);
      const double end = (est.poses.back().world_from_cam.translation() -
                          gt.poses.back().world_from_cam.translation())
                             .norm();
      EXPECT_NEAR(end / length, fraction, 1e-9) << "seed " << seed;
    }
  }
}

TEST(Synth, CameraKeepsTheTableInView) {
  SynthOptions o = small(2, 0);
  o.frames = 30;
  o.resolution_scale = 0.25;
  o.seg_noise.min_area_px = 4;
  for (const std::string preset : {"tabletop", "office", "edge"}) {
    o.preset = preset;
    const SynthSequence s = synthesize(o);
    for (const auto& f : s.frames) {
      // Most of the ground-truth objects are seen in every frame.
      EXPECT_GE(f.segmentation_gt.instances.size() + 0.0, 0.5 * s.scene.objects.size())
          << preset << " frame " << f.index;
    }
  }
}

TEST(Synth, StreamingWriterWritesTheSameFilesAsTheInMemoryOne) {
  SynthOptions o = small(4, 2);
  o.frames =
      11;  // on 2 threads: frames finish out of order, the noise must still see them in order
  o.resolution_scale = 0.15;
  o.seg_noise.min_area_px = 5;
  o.seg_noise.id_switch_prob = 0.2;  // track IDs must carry over from frame to frame identically
  test::TempDir tmp;
  const SynthSequence memory = synthesize(o);
  write_sequence(tmp / "memory", memory, 1);
  const SynthSequence streamed = write_synthetic_sequence(tmp / "streamed", o);
  EXPECT_TRUE(streamed.frames.empty());
  EXPECT_GT(streamed.seg_stats.id_switches, 0);
  const int compared = expect_same_files(tmp / "memory", tmp / "streamed");
  EXPECT_EQ(compared, 11 * 4 + 8);  // rgb, depth, 2 segmentations per frame + 8 files
  // The PNGs (io/png_encode.h's encoder) read back as the images in memory.
  for (const auto& f : memory.frames) {
    const cv::Mat rgb =
        cv::imread((tmp / "streamed" / "rgb" / (timestamp_name(f.timestamp) + ".png")).string(),
                   cv::IMREAD_UNCHANGED);
    const cv::Mat depth = cv::imread(
        (tmp / "streamed" / "depth" / (timestamp_name(f.depth_timestamp) + ".png")).string(),
        cv::IMREAD_UNCHANGED);
    ASSERT_EQ(rgb.type(), CV_8UC3);
    ASSERT_EQ(depth.type(), CV_16UC1);
    EXPECT_EQ(cv::norm(rgb, f.rgb, cv::NORM_INF), 0.0) << f.index;
    EXPECT_EQ(cv::norm(depth, f.depth, cv::NORM_INF), 0.0) << f.index;
  }
}

// A sparse export (--keep-every): frames 0, K, 2K written, each instance its own track id, alike
// from both writers.
TEST(Synth, KeepEveryWritesOneFrameInKEachInstanceWithATrackIdOfItsOwn) {
  SynthOptions o = small(4, 2);
  o.frames = 7;
  o.keep_every = 3;
  o.resolution_scale = 0.15;
  o.seg_noise.min_area_px = 5;
  test::TempDir tmp;
  write_sequence(tmp / "memory", synthesize(o), 1);
  write_synthetic_sequence(tmp / "streamed", o);
  EXPECT_EQ(expect_same_files(tmp / "memory", tmp / "streamed"), 3 * 4 + 8);  // frames 0, 3, 6
  const std::string rgb = test::read_text(tmp / "streamed" / "rgb.txt");
  EXPECT_EQ(std::count(rgb.begin(), rgb.end(), '\n'), 3 + 3);  // 3 comment lines
  std::set<int> ids;
  int instances = 0;
  for (const auto& e : test::fs::directory_iterator(tmp / "streamed" / "segmentation")) {
    const nlohmann::json frame = nlohmann::json::parse(test::read_text(e.path()));
    for (const auto& i : frame.at("instances")) {
      ++instances;
      ids.insert(i.at("track_id").get<int>());
    }
  }
  EXPECT_GT(instances, 10);
  EXPECT_EQ(static_cast<int>(ids.size()), instances);
  o.keep_every = 0;
  EXPECT_THROW(o.check(), InputError);
}

TEST(Synth, StreamingWriterBleedsTheMasksAsTheInMemoryOne) {
  // The streaming writer keeps each frame's exact depth for the bleed until its turn in the chain.
  SynthOptions o = small(5, 2);
  o.preset = "edge";
  o.frames = 7;
  o.seg_noise.bleed_px = 2;
  test::TempDir tmp;
  const SynthSequence memory = synthesize(o);
  write_sequence(tmp / "memory", memory, 1);
  const SynthSequence streamed = write_synthetic_sequence(tmp / "streamed", o);
  EXPECT_GT(streamed.seg_stats.bleed_pixels, 0);
  EXPECT_EQ(streamed.seg_stats.bleed_pixels, memory.seg_stats.bleed_pixels);
  const int compared = expect_same_files(tmp / "memory", tmp / "streamed");
  EXPECT_EQ(compared, 7 * 4 + 8);
}

TEST(Synth, BleedIsRecordedInSynthJsonOnlyWhenOn) {
  // Without the bleed, synth.json is as it was before the option existed.
  SynthOptions o = small(5, 0);
  o.frames = 2;
  const std::string off = synth_json(synthesize(o));
  EXPECT_EQ(off.find("bleed"), std::string::npos);
  o.seg_noise.bleed_px = 2;
  const std::string on = synth_json(synthesize(o));
  EXPECT_NE(on.find("\"bleed_px\": 2"), std::string::npos) << on;
  EXPECT_NE(on.find("\"bleed_pixels\": "), std::string::npos) << on;
}

TEST(Synth, WalkReturnsToEachPlaceOncePerLoop) {
  // The walkthrough preset's path without jitter: after one loop (its length / the walking speed)
  // the camera is where it was, and between two loops it has been metres away.
  CameraPathOptions path = preset_camera_path("walkthrough");
  path.jitter_translation_m = 0.0;
  path.jitter_rotation_deg = 0.0;
  double loop = 0.0;
  for (std::size_t i = 0; i < path.waypoints.size(); ++i)
    loop +=
        (path.waypoints[(i + 1) % path.waypoints.size()].eye_world - path.waypoints[i].eye_world)
            .norm();
  const double period = loop / path.walk_speed_m_per_s;
  std::vector<double> stamps;
  for (int i = 0; i <= 100; ++i) stamps.push_back(2.0 + period * i / 50.0);  // two loops
  const Trajectory t = make_camera_path(path, stamps, 7);
  const Pose& first = t.poses.front().world_from_cam;
  EXPECT_LT((t.poses[50].world_from_cam.matrix() - first.matrix()).norm(), 1e-6);
  EXPECT_LT((t.poses[100].world_from_cam.matrix() - first.matrix()).norm(), 1e-6);
  double farthest = 0.0;
  for (const auto& p : t.poses)
    farthest = std::max(farthest, (p.world_from_cam.translation() - first.translation()).norm());
  EXPECT_GT(farthest, 3.0);
  EXPECT_NEAR(path_length_m(t), 2.0 * loop, 0.05 * loop);
  // The first pose is at the first waypoint, looking at its target.
  EXPECT_LT((first.translation() - path.waypoints[0].eye_world).norm(), 1e-9);
  const Vec3 forward = first.linear().col(2);
  EXPECT_GT(
      forward.dot((path.waypoints[0].target_world - path.waypoints[0].eye_world).normalized()),
      0.999999);
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

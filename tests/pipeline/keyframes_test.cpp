#include "objmap/pipeline/keyframes.h"

#include <gtest/gtest.h>

namespace objmap::pipeline {
namespace {

// `n` frames at 30 Hz and a pose for each, the camera moving `step_m` along x per frame.
std::pair<io::Dataset, Trajectory> clip(int n, double step_m) {
  io::Dataset dataset;
  Trajectory trajectory;
  for (int i = 0; i < n; ++i) {
    const double t = 100.0 + i / 30.0;
    dataset.frames.push_back({t, t, "", ""});
    Pose pose = Pose::Identity();
    pose.translate(Vec3(step_m * i, 0, 0));
    trajectory.poses.push_back({t, pose});
  }
  return {dataset, trajectory};
}

TEST(Keyframes, MotionKeepsAFrameEveryFiveCentimetres) {
  const auto [dataset, trajectory] = clip(30, 0.01);  // 29 cm in all
  KeyframeOptions options;
  options.mode = "motion";
  options.min_keyframes = 3;
  const KeyframeSelection s = select_keyframes(dataset, trajectory, options);
  ASSERT_EQ(s.keyframes.size(), 6u);  // frames 0, 5, 10, ..., 25
  EXPECT_EQ(s.keyframes[1].frame, 5u);
  EXPECT_FALSE(s.still_camera);
}

TEST(Keyframes, AStillCameraIsSaidWhateverTheMode) {
  // 10 frames over 9 mm (ycbv_0000_10f moves about 1 cm): motion keeps one keyframe.
  const auto [dataset, trajectory] = clip(10, 0.001);
  KeyframeOptions options;
  options.min_keyframes = 3;
  for (const char* mode : {"auto", "all", "motion", "stride"}) {
    options.mode = mode;
    const KeyframeSelection s = select_keyframes(dataset, trajectory, options);
    EXPECT_TRUE(s.still_camera) << mode;
    EXPECT_EQ(s.keyframes.size(), std::string(mode) == "motion" ? 1u : 10u) << mode;
  }
  options.mode = "auto";
  EXPECT_EQ(select_keyframes(dataset, trajectory, options).mode, "all");
  // A moving camera is not still in any mode, "all" included.
  const auto [moving, path] = clip(10, 0.05);
  options.mode = "all";
  EXPECT_FALSE(select_keyframes(moving, path, options).still_camera);
}

}  // namespace
}  // namespace objmap::pipeline

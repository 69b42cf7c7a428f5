// THE key property of the generator: rendered depth, intrinsics, masks and ground-truth poses
// agree.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "objmap/core/error.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/render.h"
#include "objmap/sim/synth.h"

namespace objmap::sim {
namespace {

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

bool touches_border(const segmentation::Box& b, int width, int height) {
  return b.x <= 0 || b.y <= 0 || b.x + b.w >= width || b.y + b.h >= height;
}

TEST(Render, BackProjectedMasksLieOnTheGroundTruthSurfaces) {
  SynthOptions options;
  options.frames = 4;
  options.frame_rate_hz = 2.0;  // spread the 4 frames over the whole orbit
  options.depth_time_offset_s = 0.0;
  options.resolution_scale = 0.5;
  options.set_noise_free();
  const SynthSequence seq = synthesize(options);
  const Camera& cam = seq.camera;

  std::set<std::string> classes_checked;
  int instances_checked = 0;
  double worst_median = 0.0;
  for (const auto& frame : seq.frames) {
    const Pose& world_from_cam = seq.groundtruth.poses[frame.index].world_from_cam;
    for (const auto& instance : frame.segmentation_gt.instances) {
      if (touches_border(instance.bbox, cam.width, cam.height)) continue;  // not fully seen
      const SceneObject* object = seq.scene.find(*instance.track_id);
      ASSERT_NE(object, nullptr);
      EXPECT_EQ(object->class_name, instance.class_name);
      std::vector<double> distances;
      Vec3 sum = Vec3::Zero();
      for (int v = 0; v < cam.height; ++v)
        for (int u = 0; u < cam.width; ++u) {
          if (!instance.mask->at(u, v)) continue;
          const std::uint16_t raw = frame.depth.at<std::uint16_t>(v, u);
          ASSERT_GT(raw, 0);  // noise-free: every object pixel has depth
          const Vec3 point_in_cam = cam.unproject(u, v, raw / cam.depth_factor);
          const Vec3 point_in_world = world_from_cam * point_in_cam;
          distances.push_back(distance_to_surface(*object, point_in_world));
          sum += point_in_world;
        }
      if (distances.size() < 30) continue;
      const double med = median(distances);
      EXPECT_LT(med, 0.002) << object->class_name << " id " << object->id << " frame "
                            << frame.index;
      const Vec3 centroid = sum / static_cast<double>(distances.size());
      EXPECT_TRUE(object->obb.contains(centroid)) << object->class_name << " id " << object->id;
      worst_median = std::max(worst_median, med);
      classes_checked.insert(object->class_name);
      ++instances_checked;
    }
  }
  RecordProperty("worst_median_distance_um", std::to_string(worst_median * 1e6));
  RecordProperty("instances_checked", instances_checked);
  EXPECT_GE(classes_checked.size(), 8u);
  EXPECT_GE(instances_checked, 30);
  // The 16-bit depth (0.2 mm steps) is the only error: the median is far below the 2 mm bound.
  EXPECT_LT(worst_median, 0.0005);
}

TEST(Render, ObjectCentroidsProjectOntoTheirMasks) {
  // Pose convention check independent of depth: project the GT centroid of compact objects with
  // cam_from_world = inverse(world_from_cam); it must fall inside (or next to) the object's box.
  SynthOptions options;
  options.frames = 2;
  options.resolution_scale = 0.5;
  options.set_noise_free();
  const SynthSequence seq = synthesize(options);
  int checked = 0;
  for (const auto& frame : seq.frames) {
    const Pose cam_from_world = seq.groundtruth.poses[frame.index].world_from_cam.inverse();
    for (const auto& instance : frame.segmentation_gt.instances) {
      const SceneObject* object = seq.scene.find(*instance.track_id);
      if (object->class_name != "cup" && object->class_name != "bottle" &&
          object->class_name != "keyboard")
        continue;
      const Eigen::Vector2d px = seq.camera.project(cam_from_world * object->centroid);
      const auto& b = instance.bbox;
      EXPECT_GE(px.x(), b.x - 2);
      EXPECT_LE(px.x(), b.x + b.w + 2);
      EXPECT_GE(px.y(), b.y - 2);
      EXPECT_LE(px.y(), b.y + b.h + 2);
      ++checked;
    }
  }
  EXPECT_GE(checked, 4);
}

TEST(Render, ResultDoesNotDependOnTheThreadCount) {
  const Scene scene = make_scene("tabletop", 5);
  const Camera cam = synthetic_camera(0.25);
  SynthOptions options;
  const Pose pose = look_at(Vec3(0.2, -1.5, 1.4), Vec3(0, 0, 0.8));
  const RenderedFrame a = render_frame(scene, cam, pose, 1);
  const RenderedFrame b = render_frame(scene, cam, pose, 2);
  EXPECT_EQ(cv::norm(a.rgb, b.rgb, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.depth_m, b.depth_m, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.labels, b.labels, cv::NORM_INF), 0.0);
  // Something was seen, including objects.
  EXPECT_GT(cv::countNonZero(a.labels), 100);
  EXPECT_EQ(cv::countNonZero(a.depth_m), cam.width * cam.height);  // inside the room
}

TEST(Render, DistortedCameraIsRefused) {
  const Scene scene = make_scene("tabletop", 1);
  Camera cam = camera_preset("fr1");
  EXPECT_THROW(render_frame(scene, cam, Pose::Identity()), InputError);
}

}  // namespace
}  // namespace objmap::sim

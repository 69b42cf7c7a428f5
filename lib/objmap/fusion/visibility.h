#pragma once
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/core/types.h"

// Where an object's place was in view: the keyframes whose camera saw it, not occluded, judged with
// their depth images. Confirmation by the detected share (ObjectMapOptions::min_detected_share)
// compares the keyframes in which the object was detected with those in which it could have been:
// a detector's false positive seen in a few of many frames stays a small share however dense the
// frames are, where a count of views grows with them.
//
// A keyframe has the object in view when at least min_visible_fraction of a sample of its points
// (its supported voxels, evenly spaced) project into the image onto a pixel with a depth that does
// not lie more than the occlusion tolerance in front of the point (the point is on or behind that
// surface: seen, or the ray passed through its place), and the camera is no farther from the
// object's centroid than range_factor × the farthest distance at which the object was detected (a
// detector finds an object within a range of apparent sizes). A pixel without depth says nothing.
// Self-occlusion hides an object's far side from any one view, so the fraction is well below 1/2.
namespace objmap::fusion {

struct VisibilityOptions {
  int sample_points = 64;               // points of the object projected into each keyframe
  double min_visible_fraction = 0.25;   // of them visible: the keyframe has the object in view
  double occlusion_tolerance_m = 0.05;  // a depth this much (+ per metre below) in front: occluded
  double occlusion_tolerance_per_m = 0.02;  // ... + this × the point's depth (noise grows with z)
  double range_factor = 1.25;  // in view only within this × the farthest detection's distance
  void check() const;          // throws InputError naming the bad field
};

// Every keyframe's depth image (every kStep-th pixel of every kStep-th row: 38 KB for 640×480) and
// pose, to judge afterwards where an object's place was in view.
class ViewLog {
 public:
  static constexpr int kStep = 4;
  explicit ViewLog(const Camera& camera);
  // The thinned copy of a raw depth image (CV_16UC1 of the camera's size and depth factor) that
  // add() keeps (CV_16UC1, the raw values): a worker can make it.
  cv::Mat thin(const cv::Mat& depth) const;
  // A keyframe: its timestamp, thin(depth) and pose. Keyframes are added in time order.
  void add(double timestamp, cv::Mat thinned, const Pose& world_from_cam);
  std::size_t size() const { return views_.size(); }
  std::size_t bytes() const;

  // The timestamps (ascending) of the keyframes that had `sample` (points of one object, in the
  // world) in view by the rule above; max_distance_m <= 0: no range limit.
  std::vector<double> frames_in_view(const std::vector<Vec3>& sample, const Vec3& centroid,
                                     double max_distance_m, const VisibilityOptions& options) const;

 private:
  struct View {
    double timestamp = 0.0;
    cv::Mat depth;  // CV_16UC1, raw values (camera's depth factor), 0 = no depth
    Eigen::Matrix3d cam_from_world_r;
    Vec3 cam_from_world_t;
    Vec3 centre_in_world;
  };
  bool visible(const View& view, const Vec3& point, const VisibilityOptions& options) const;
  Camera camera_;
  std::vector<View> views_;
};

}  // namespace objmap::fusion

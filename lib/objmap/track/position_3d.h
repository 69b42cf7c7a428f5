#pragma once
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/core/camera.h"
#include "objmap/core/trajectory.h"
#include "objmap/core/types.h"
#include "objmap/geometry/backproject.h"
#include "objmap/io/dataset.h"
#include "objmap/segmentation/box_mask.h"
#include "objmap/segmentation/types.h"

// The 3D position of a detection for the tracker's 3D gate (TrackerOptions::use_gate_3d): the
// instance's robust centroid in the world frame, from the frame's depth image and pose.
namespace objmap::track {

struct Position3dOptions {
  // Valid depth range, metres (as fuse's back-projection: Kinect depth is poor beyond ~4 m).
  double min_depth_m = 0.1;
  double max_depth_m = 4.0;
  // Masks for instances that have only a box (detector boxes): the object's pixels inside the box
  // on its depth surface, as fuse makes them (segmentation/box_mask.h).
  segmentation::BoxMaskOptions box_mask;
  int min_pixels = 20;  // fewer valid depth pixels in the mask: no position (gate off for it)
  double pose_max_diff_s = 0.02;  // a frame has a pose when one is within this many seconds
  void check() const;             // throws InputError naming the bad field
};

// Why an instance has no position (or kOk).
enum class PositionStatus { kOk, kNoMaskFromBox, kTooFewDepthPixels };

struct InstancePosition {
  std::optional<Vec3> point_in_world;  // set when status is kOk
  PositionStatus status = PositionStatus::kOk;
  bool mask_from_box = false;  // the instance had only a box; box_mask.h made its mask
  std::size_t pixels = 0;      // valid depth pixels used
};

// The robust centroid of one instance: the per-axis median of its back-projected valid depth pixels
// (inside its mask, or inside the mask made from its box and the depth when it has only a box),
// in the world frame (world_from_cam x point_in_cam, paper eqs 11-15). The median ignores the
// mask's bleed onto the background and flying pixels at depth edges, which pull a mean far behind
// the object. `rays` is make_ray_table(camera). Throws InputError for a depth image or mask of
// another size than the camera's.
InstancePosition instance_position(const segmentation::Instance& instance, const cv::Mat& depth,
                                   const Camera& camera, const geometry::RayTable& rays,
                                   const Pose& world_from_cam, const Position3dOptions& options);

// The positions of one frame's instances.
struct FramePositions {
  bool has_pose = false;  // false: no pose within pose_max_diff_s, or no depth image: gate off
  std::vector<InstancePosition> instances;  // one per instance of the frame, when has_pose
};

// Positions of the instances of `frame`, frame `index` of a segmentation (called once per frame,
// in order).
using FramePositionsFn =
    std::function<FramePositions(std::size_t index, const segmentation::FrameSegmentation& frame)>;

// Positions for the segmentation frames at `timestamps` (sorted) from a recording (its frames as
// fuse reads them) and a trajectory (world_from_cam, looked up at each frame's timestamp): the
// returned function reads the frame's depth image and computes instance_position for each instance.
// A frame whose timestamp is not an rgb frame of the dataset (within 1e-4 s) or that has no pose
// gets has_pose = false. `dataset` must outlive the returned function. Throws InputError for bad
// options; the function throws for an unreadable depth image.
FramePositionsFn depth_positions(const io::Dataset& dataset, const std::vector<double>& timestamps,
                                 const Trajectory& trajectory, const Camera& camera,
                                 const Position3dOptions& options);

}  // namespace objmap::track

#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/core/camera.h"
#include "objmap/core/types.h"
#include "objmap/segmentation/types.h"

// `objmap eval masks`: how well each object's own masks agree with the object, without ground
// truth. Each object of a fuse run is projected into every keyframe where it took an observation;
// of its points that the keyframe sees (in the image, and not behind the depth image's surface),
// the share inside the mask of that observation's instance. A mask that spills over the outline or
// misses part of the object, or an object that fused another object's points, lowers it: it
// measures the front end (box masks against network masks, docs/benchmarks.md) on real data.
namespace objmap::pipeline {

struct MaskCheckOptions {
  // A projected point is seen by the keyframe when the depth image has a value within
  // depth_tolerance_m + depth_tolerance_per_m · z of its depth, or no depth there (a hole: not
  // counted either way).
  double depth_tolerance_m = 0.03;
  double depth_tolerance_per_m = 0.02;
  void check() const;  // throws InputError naming the bad field
};

// One object in one keyframe: its points that the keyframe sees and those inside the mask.
struct MaskViewCount {
  std::size_t visible = 0;
  std::size_t inside = 0;
};

// Projects `points_in_world` with `world_from_cam` and `camera` into a CV_16UC1 depth image of the
// camera's size (read with camera.depth_factor) and counts the seen points and those on a non-zero
// pixel of `mask` (the same size).
MaskViewCount count_inside_mask(const PointCloud& points_in_world, const Pose& world_from_cam,
                                const Camera& camera, const cv::Mat& depth,
                                const segmentation::Mask& mask,
                                const MaskCheckOptions& options = {});

struct ObjectMaskCheck {
  int id = -1;
  std::string class_name;
  std::size_t keyframes = 0;  // keyframes with an observation whose instance was found
  std::size_t visible = 0, inside = 0;
  double share = 0.0;  // inside / visible (0 when nothing is seen)
};

struct MaskCheckResult {
  std::vector<ObjectMaskCheck> objects;  // as objects.json lists them
  std::size_t visible = 0, inside = 0;
  double share = 0.0;                      // over all objects' points (inside / visible)
  std::size_t unmatched_observations = 0;  // observations whose instance was not found again
};

// Reads RUN/run.json (the dataset, trajectory, segmentation and camera fuse used), RUN/objects.json
// and each object's PLY, and checks every observation's mask: given masks as the segmentation has
// them, box-only instances with the mask fuse makes from the box and the depth. An observation's
// instance is the one of its keyframe with the same class, score and track id. Throws InputError
// for a run folder that is not a fuse run or whose inputs are gone.
MaskCheckResult check_run_masks(const std::filesystem::path& run,
                                const MaskCheckOptions& options = {});

}  // namespace objmap::pipeline

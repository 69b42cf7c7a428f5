#pragma once
#include <optional>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/core/types.h"

// The partial-view bias of an observed centroid. A camera sees one side of an object, so the
// centroid of an observation's points lies off the object's centroid, toward the camera, by an
// amount that turns with the viewpoint. Rendering the fused object models (their filtered point
// clouds) from a keyframe's pose with a z-buffer gives the part of each model that this keyframe
// can see; the centroid of that part is what the keyframe's observation should measure.
namespace objmap::pose {

struct VisibilityOptions {
  int downsample = 2;               // z-buffer at 1/downsample of the image resolution
  double point_size_m = 0.01;       // splat size of one model point (the fuse voxel, 1 cm)
  double depth_tolerance_m = 0.02;  // a point within this of the nearest surface is visible
  int min_visible_points = 10;      // fewer visible points: no visible centroid
  void check() const;               // throws InputError naming the bad field
};

// For each model (points in the world frame), the centroid (world frame) of its points that are
// visible from `world_from_cam`: inside the image, in front of the camera and not hidden by a
// nearer point of any model. nullopt when fewer than min_visible_points are visible.
std::vector<std::optional<Vec3>> visible_centroids(const std::vector<const PointCloud*>& models,
                                                   const Pose& world_from_cam, const Camera& camera,
                                                   const VisibilityOptions& options);

}  // namespace objmap::pose

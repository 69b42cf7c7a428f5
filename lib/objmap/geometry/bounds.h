#pragma once
#include "objmap/core/types.h"

// Boxes and centroids of point sets (an object's position and extent in objects.json).
namespace objmap::geometry {

// Mean of the points (0 for an empty cloud), accumulated in double.
Vec3 centroid(const PointCloud& cloud);

// Smallest axis-aligned box holding every point (zero box for an empty cloud).
Aabb compute_aabb(const PointCloud& cloud);

// Oriented box from PCA: axes = eigenvectors of the points' covariance (largest variance first,
// right-handed, each axis signed so that its largest component is positive, for a deterministic
// result), extent = the points' min/max along each axis, centre = the middle of that range.
Obb compute_obb(const PointCloud& cloud);

// Oriented box standing on the up axis (unit `up`): its third axis is `up`, its first the largest
// horizontal variance (PCA of the points projected on the plane normal to `up`, signed so that its
// largest component is positive), its second `up` × first. The box of an object as it stands:
// height along up, turned only about up.
Obb compute_upright_obb(const PointCloud& cloud, const Vec3& up);

// Centre of the box spanned by the q- and (1 − q)-quantiles of the points along each axis of the
// frame `frame_from_world` (a rotation; identity: the world axes), in world coordinates (0 when
// empty).
Vec3 percentile_box_centre(const PointCloud& cloud, double q,
                           const Eigen::Matrix3d& frame_from_world = Eigen::Matrix3d::Identity());

}  // namespace objmap::geometry

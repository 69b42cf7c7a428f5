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

}  // namespace objmap::geometry

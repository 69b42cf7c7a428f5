#pragma once
// Private to lib/objmap/scene: `near` as a person means it (docs/scene.md, "Relations").
#include <opencv2/core/types.hpp>
#include <vector>

#include "objmap/scene/footprint.h"
#include "objmap/scene/scene.h"

namespace objmap::scene::detail {

// The smallest distance between two convex outlines seen from above, 0 when they touch or overlap
// (one inside the other too); an outline of 1 or 2 corners is a point or a segment. Infinity when
// either is empty.
double hull_gap(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b);

// The largest distance between two corners of an outline: its largest horizontal extent.
double hull_extent(const std::vector<cv::Point2f>& hull);

// The clearance between two objects in the gravity frame: the gap between their footprints seen
// from above and the gap between their height ranges [bottom, top] (each 0 when they overlap),
// combined as the two sides of a right angle. Without a footprint (no points): the distance
// between the centres seen from above, with the heights' gap.
double clearance(const Footprint& a, const Footprint& b);

// How close is near for two things of these largest horizontal extents: clamp(near_scale × the
// smaller, near_min_m, near_max_m).
double near_reach(double extent_a, double extent_b, const RelationOptions& o);

// Relations::near (objects) and near_surfaces of every object, nearest first: those whose
// clearance is within near_reach (RelationOptions::near_by_centres: box centres within
// near_radius_m, and surfaces whose outline is within it of the object's centre seen from above).
void near_relations(const std::vector<SceneObject>& objects, const std::vector<Footprint>& feet,
                    const std::vector<Surface>& surfaces, const Eigen::Matrix3d& gravity,
                    const RelationOptions& o, std::vector<Relations>& relations);

}  // namespace objmap::scene::detail

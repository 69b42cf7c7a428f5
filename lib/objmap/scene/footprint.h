#pragma once
// Private to lib/objmap/scene: points seen from above (the gravity frame: z along up).
#include <opencv2/core/types.hpp>
#include <vector>

#include "objmap/core/types.h"

namespace objmap::scene::detail {

// A set of points seen from above: its outline (convex hull of the points' (x, y) in the gravity
// frame), its centre there, and its extent along up.
struct Footprint {
  std::vector<cv::Point2f> hull;
  cv::Point2f centre;
  // 0.5th and 98th percentiles of the heights (an object): few points of a chair or a table are
  // on its legs, so a higher bottom percentile would stand it in the air.
  double bottom = 0.0, top = 0.0;
  double mean_height = 0.0;
  // The outline of the points within the top band below `top` (what stands on the object stands
  // on these): a table's top, a book's cover, a chair's backrest (not its seat or legs).
  std::vector<cv::Point2f> top_hull;
};

// `gravity_from_world` rotates world points into the gravity frame. For an object, `centre_world`
// is its position (box centre); empty points give an empty hull.
Footprint footprint(const std::vector<Vec3f>& points, const Eigen::Matrix3d& gravity_from_world,
                    const Vec3& centre_world, double top_band_m = 0.05);

// Signed distance of `p` to the hull's boundary: > 0 inside, < 0 outside (metres).
double inside_distance(const std::vector<cv::Point2f>& hull, const cv::Point2f& p);

}  // namespace objmap::scene::detail

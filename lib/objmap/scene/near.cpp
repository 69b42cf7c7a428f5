// `near` as a person means it: the clearance between two objects against a reach scaled to the
// smaller one (docs/scene.md, "Relations").
#include "objmap/scene/near.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace objmap::scene::detail {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

double cross(const cv::Point2f& o, const cv::Point2f& a, const cv::Point2f& b) {
  return (static_cast<double>(a.x) - o.x) * (static_cast<double>(b.y) - o.y) -
         (static_cast<double>(a.y) - o.y) * (static_cast<double>(b.x) - o.x);
}

double point_to_segment(const cv::Point2f& p, const cv::Point2f& a, const cv::Point2f& b) {
  const double dx = static_cast<double>(b.x) - a.x, dy = static_cast<double>(b.y) - a.y;
  const double px = static_cast<double>(p.x) - a.x, py = static_cast<double>(p.y) - a.y;
  const double length2 = dx * dx + dy * dy;
  const double t = length2 > 0.0 ? std::clamp((px * dx + py * dy) / length2, 0.0, 1.0) : 0.0;
  return std::hypot(px - t * dx, py - t * dy);
}

// Segments ab and cd cross or touch (collinear ones are left to the distances).
bool segments_cross(const cv::Point2f& a, const cv::Point2f& b, const cv::Point2f& c,
                    const cv::Point2f& d) {
  const double d1 = cross(a, b, c), d2 = cross(a, b, d), d3 = cross(c, d, a), d4 = cross(c, d, b);
  if (d1 == 0.0 && d2 == 0.0) return false;
  return d1 * d2 <= 0.0 && d3 * d4 <= 0.0;
}

// The edges of an outline: n for a polygon, one for a segment, a zero-length one for a point.
std::size_t edge_count(const std::vector<cv::Point2f>& hull) {
  return hull.size() >= 3 ? hull.size() : 1;
}
cv::Point2f edge_end(const std::vector<cv::Point2f>& hull, std::size_t k) {
  return hull[(k + 1) % hull.size()];
}

std::vector<cv::Point2f> outline_in_gravity(const Surface& s, const Eigen::Matrix3d& gravity) {
  std::vector<cv::Point2f> hull;
  for (const Vec3& q : s.outline) {
    const Vec3 g = gravity * q;
    hull.emplace_back(static_cast<float>(g.x()), static_cast<float>(g.y()));
  }
  return hull;
}

void sort_nearest_first(std::vector<Neighbour>& list) {
  std::stable_sort(list.begin(), list.end(), [](const Neighbour& a, const Neighbour& b) {
    return a.distance_m < b.distance_m;
  });
}

// The old rule (near_by_centres): box centres within near_radius_m; a surface whose outline lies
// within it of the object's centre seen from above.
void near_by_centres(const std::vector<SceneObject>& objects, const std::vector<Footprint>& feet,
                     const std::vector<Surface>& surfaces, const Eigen::Matrix3d& gravity,
                     const RelationOptions& o, std::vector<Relations>& relations) {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    for (std::size_t j = 0; j < objects.size(); ++j) {
      const double d = (objects[i].position - objects[j].position).norm();
      if (i != j && d <= o.near_radius_m) relations[i].near.push_back({objects[j].id, d});
    }
    for (const Surface& s : surfaces) {
      const double d = hull_gap(outline_in_gravity(s, gravity), {feet[i].centre});
      if (d <= o.near_radius_m) relations[i].near_surfaces.push_back({s.id, d});
    }
  }
}

}  // namespace

double hull_gap(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
  if (a.empty() || b.empty()) return kInfinity;
  if (a.size() >= 3 && cv::pointPolygonTest(a, b[0], false) >= 0) return 0.0;
  if (b.size() >= 3 && cv::pointPolygonTest(b, a[0], false) >= 0) return 0.0;
  double best = kInfinity;
  for (std::size_t i = 0; i < edge_count(a); ++i) {
    const cv::Point2f &a0 = a[i], a1 = edge_end(a, i);
    for (std::size_t j = 0; j < edge_count(b); ++j) {
      const cv::Point2f &b0 = b[j], b1 = edge_end(b, j);
      if (segments_cross(a0, a1, b0, b1)) return 0.0;
      best = std::min({best, point_to_segment(a0, b0, b1), point_to_segment(a1, b0, b1),
                       point_to_segment(b0, a0, a1), point_to_segment(b1, a0, a1)});
    }
  }
  return best;
}

double hull_extent(const std::vector<cv::Point2f>& hull) {
  double extent = 0.0;
  for (std::size_t i = 0; i < hull.size(); ++i)
    for (std::size_t j = i + 1; j < hull.size(); ++j)
      extent = std::max(extent, std::hypot(static_cast<double>(hull[i].x) - hull[j].x,
                                           static_cast<double>(hull[i].y) - hull[j].y));
  return extent;
}

double clearance(const Footprint& a, const Footprint& b) {
  const double across = a.hull.empty() || b.hull.empty()
                            ? std::hypot(static_cast<double>(a.centre.x) - b.centre.x,
                                         static_cast<double>(a.centre.y) - b.centre.y)
                            : hull_gap(a.hull, b.hull);
  const double along = std::max({0.0, a.bottom - b.top, b.bottom - a.top});
  return std::hypot(across, along);
}

double near_reach(double extent_a, double extent_b, const RelationOptions& o) {
  return std::clamp(o.near_scale * std::min(extent_a, extent_b), o.near_min_m, o.near_max_m);
}

void near_relations(const std::vector<SceneObject>& objects, const std::vector<Footprint>& feet,
                    const std::vector<Surface>& surfaces, const Eigen::Matrix3d& gravity,
                    const RelationOptions& o, std::vector<Relations>& relations) {
  if (o.near_by_centres) {
    near_by_centres(objects, feet, surfaces, gravity, o, relations);
  } else {
    std::vector<double> extent;
    for (const Footprint& f : feet) extent.push_back(hull_extent(f.hull));
    for (std::size_t i = 0; i < objects.size(); ++i)
      for (std::size_t j = i + 1; j < objects.size(); ++j) {
        const double gap = clearance(feet[i], feet[j]);
        if (gap > near_reach(extent[i], extent[j], o)) continue;
        relations[i].near.push_back({objects[j].id, gap});
        relations[j].near.push_back({objects[i].id, gap});
      }
    // A surface: the gap between the footprint and its outline, and the footprint's heights to its
    // height; its extent is that of its outline (the object's is smaller but for a small shelf).
    for (const Surface& s : surfaces) {
      const std::vector<cv::Point2f> outline = outline_in_gravity(s, gravity);
      const double reach_of_surface = hull_extent(outline);
      for (std::size_t i = 0; i < objects.size(); ++i) {
        const Footprint& f = feet[i];
        if (f.hull.empty()) continue;
        const double along = std::max({0.0, f.bottom - s.height_m, s.height_m - f.top});
        const double gap = std::hypot(hull_gap(f.hull, outline), along);
        if (gap <= near_reach(extent[i], reach_of_surface, o))
          relations[i].near_surfaces.push_back({s.id, gap});
      }
    }
  }
  for (Relations& r : relations) {
    sort_nearest_first(r.near);
    sort_nearest_first(r.near_surfaces);
  }
}

}  // namespace objmap::scene::detail

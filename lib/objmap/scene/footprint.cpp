#include "objmap/scene/footprint.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace objmap::scene::detail {

Footprint footprint(const std::vector<Vec3f>& points, const Eigen::Matrix3d& gravity_from_world,
                    const Vec3& centre_world, double top_band_m) {
  Footprint f;
  const Vec3 c = gravity_from_world * centre_world;
  f.centre = cv::Point2f(static_cast<float>(c.x()), static_cast<float>(c.y()));
  if (points.empty()) return f;
  const Eigen::Matrix3f r = gravity_from_world.cast<float>();
  std::vector<cv::Point2f> xy(points.size());
  std::vector<float> z(points.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f g = r * points[i];
    xy[i] = cv::Point2f(g.x(), g.y());
    z[i] = g.z();
    sum += g.z();
  }
  f.mean_height = sum / static_cast<double>(points.size());
  cv::convexHull(xy, f.hull, /*clockwise=*/false);
  std::vector<float> ordered = z;
  const auto quantile = [&](double q) {
    const std::size_t k =
        static_cast<std::size_t>(std::llround(q * static_cast<double>(ordered.size() - 1)));
    std::nth_element(ordered.begin(), ordered.begin() + k, ordered.end());
    return static_cast<double>(ordered[k]);
  };
  f.bottom = quantile(0.005);
  f.top = quantile(0.98);
  std::vector<cv::Point2f> top_xy;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (z[i] >= f.top - top_band_m) top_xy.push_back(xy[i]);
  if (!top_xy.empty()) cv::convexHull(top_xy, f.top_hull, /*clockwise=*/false);
  return f;
}

double inside_distance(const std::vector<cv::Point2f>& hull, const cv::Point2f& p) {
  if (hull.size() < 3) return -std::numeric_limits<double>::infinity();
  return cv::pointPolygonTest(hull, p, /*measureDist=*/true);
}

}  // namespace objmap::scene::detail

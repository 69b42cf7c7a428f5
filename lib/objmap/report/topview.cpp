#include "objmap/report/topview.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "objmap/core/error.h"

namespace objmap::report {

void TopViewOptions::check() const {
  require(up_axis >= 0 && up_axis <= 2, "TopViewOptions.up_axis", "must be 0, 1 or 2 (x, y, z)");
  require(std::isfinite(pixel_m) && pixel_m > 0, "TopViewOptions.pixel_m", "must be > 0");
  require(max_size_px >= 64 && max_size_px <= 20000, "TopViewOptions.max_size_px",
          "must be in [64, 20000]");
  require(margin_px >= 0 && margin_px <= 1000, "TopViewOptions.margin_px", "must be in [0, 1000]");
  require(clip_percent >= 0 && clip_percent < 50, "TopViewOptions.clip_percent",
          "must be in [0, 50)");
}

namespace {

// The two horizontal axes for an up axis, so that the view is right-handed seen from above.
void horizontal_axes(int up, int& a, int& b) {
  a = (up + 1) % 3;
  b = (up + 2) % 3;
}

double percentile(std::vector<float>& v, double p) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

TopView render_top_view(const PointCloud& cloud, const std::vector<TopViewObject>& objects,
                        const TopViewOptions& options) {
  options.check();
  int a = 0, b = 1;
  horizontal_axes(options.up_axis, a, b);
  const int up = options.up_axis;

  // 1. Extent of the map on the two horizontal axes (stray points clipped).
  std::vector<float> va, vb;
  va.reserve(cloud.size());
  vb.reserve(cloud.size());
  for (const auto& p : cloud.points) {
    va.push_back(p[a]);
    vb.push_back(p[b]);
  }
  double a0 = percentile(va, options.clip_percent), a1 = percentile(va, 100 - options.clip_percent);
  double b0 = percentile(vb, options.clip_percent), b1 = percentile(vb, 100 - options.clip_percent);
  for (const auto& o : objects) {  // objects always in view
    a0 = std::min(a0, o.obb.center[a] - 0.2);
    a1 = std::max(a1, o.obb.center[a] + 0.2);
    b0 = std::min(b0, o.obb.center[b] - 0.2);
    b1 = std::max(b1, o.obb.center[b] + 0.2);
  }
  if (a1 - a0 < 0.1) a1 = a0 + 0.1;
  if (b1 - b0 < 0.1) b1 = b0 + 0.1;
  const double extent = std::max(a1 - a0, b1 - b0);
  const double pixel_m = std::max(options.pixel_m, extent / options.max_size_px);
  const int width = static_cast<int>(std::ceil((a1 - a0) / pixel_m)) + 2 * options.margin_px;
  const int height = static_cast<int>(std::ceil((b1 - b0) / pixel_m)) + 2 * options.margin_px;

  TopView view;
  view.pixel_m = pixel_m;
  view.origin_a = a0 - options.margin_px * pixel_m;
  view.origin_b = b1 + options.margin_px * pixel_m;  // image rows go toward -b (b up in the image)
  view.image = cv::Mat(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  auto to_pixel = [&](double pa, double pb) {
    return cv::Point2d((pa - view.origin_a) / pixel_m, (view.origin_b - pb) / pixel_m);
  };

  // 2. Z-buffer: the highest point of each pixel.
  cv::Mat top(height, width, CV_32F, cv::Scalar(-std::numeric_limits<float>::infinity()));
  const bool colors = cloud.has_colors();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud.points[i];
    const cv::Point2d px = to_pixel(p[a], p[b]);
    const int u = static_cast<int>(px.x), v = static_cast<int>(px.y);
    if (u < 0 || v < 0 || u >= width || v >= height) continue;
    float& z = top.at<float>(v, u);
    if (p[up] <= z) continue;
    z = p[up];
    const Rgb c = colors ? cloud.colors[i] : Rgb{90, 90, 90};
    view.image.at<cv::Vec3b>(v, u) = cv::Vec3b(c.b, c.g, c.r);
  }

  // 3. Objects: the outline of each oriented box seen from above, and its label.
  if (options.draw_objects) {
    for (const auto& o : objects) {
      std::vector<cv::Point2f> corners;
      for (int i = 0; i < 8; ++i) {
        const Vec3 local((i & 1 ? 1 : -1) * o.obb.half_extent.x(),
                         (i & 2 ? 1 : -1) * o.obb.half_extent.y(),
                         (i & 4 ? 1 : -1) * o.obb.half_extent.z());
        const Vec3 w = o.obb.center + o.obb.rotation * local;
        corners.push_back(to_pixel(w[a], w[b]));
      }
      std::vector<cv::Point2f> hull;
      cv::convexHull(corners, hull);
      std::vector<cv::Point> poly(hull.begin(), hull.end());
      const cv::Scalar color(o.color.b, o.color.g, o.color.r);
      cv::polylines(view.image, poly, true, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
      cv::polylines(view.image, poly, true, color, 1, cv::LINE_AA);
      const cv::Point2d c = to_pixel(o.obb.center[a], o.obb.center[b]);
      const cv::Point org(static_cast<int>(c.x) + 4, static_cast<int>(c.y) - 4);
      cv::putText(view.image, o.label, org, cv::FONT_HERSHEY_SIMPLEX, 0.45,
                  cv::Scalar(255, 255, 255), 3, cv::LINE_AA);
      cv::putText(view.image, o.label, org, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
                  cv::LINE_AA);
    }
  }
  // A 1 m scale bar in the bottom-left corner.
  const int bar = static_cast<int>(1.0 / pixel_m);
  const cv::Point s0(options.margin_px / 2 + 4, height - 8);
  cv::line(view.image, s0, s0 + cv::Point(bar, 0), cv::Scalar(0, 0, 0), 2);
  cv::putText(view.image, "1 m", s0 + cv::Point(4, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return view;
}

}  // namespace objmap::report

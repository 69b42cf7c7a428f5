#include "objmap/report/thumbnail.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "objmap/core/error.h"

namespace objmap::report {

void ThumbnailOptions::check() const {
  require(size_px >= 32 && size_px <= 4096, "ThumbnailOptions.size_px", "must be in [32, 4096]");
  require(up_axis >= 0 && up_axis <= 2, "ThumbnailOptions.up_axis", "must be 0, 1 or 2 (x, y, z)");
  require(std::isfinite(azimuth_deg), "ThumbnailOptions.azimuth_deg", "must be finite");
  require(std::isfinite(elevation_deg) && std::abs(elevation_deg) < 90,
          "ThumbnailOptions.elevation_deg", "must be in (-90, 90)");
  require(std::isfinite(point_size_m) && point_size_m >= 0, "ThumbnailOptions.point_size_m",
          "must be >= 0");
  require(clip_percent >= 0 && clip_percent < 50, "ThumbnailOptions.clip_percent",
          "must be in [0, 50)");
  require(margin_px >= 0 && 2 * margin_px < size_px - 8, "ThumbnailOptions.margin_px",
          "must be >= 0 and leave room for the object");
}

namespace {

double percentile(std::vector<double> v, double p) {
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

void label_image(cv::Mat& image, const std::string& label) {
  if (label.empty()) return;
  const cv::Point org(5, 14);
  cv::putText(image, label, org, cv::FONT_HERSHEY_SIMPLEX, 0.42, cv::Scalar(255, 255, 255), 3,
              cv::LINE_AA);
  cv::putText(image, label, org, cv::FONT_HERSHEY_SIMPLEX, 0.42, cv::Scalar(20, 20, 20), 1,
              cv::LINE_AA);
}

}  // namespace

cv::Mat render_thumbnail(const PointCloud& cloud, const std::string& label,
                         const ThumbnailOptions& options) {
  options.check();
  const int n = options.size_px;
  cv::Mat image(n, n, CV_8UC3, cv::Scalar(255, 255, 255));
  if (cloud.empty()) {
    label_image(image, label);
    return image;
  }

  // 1. The view: a right-handed frame with coordinates (a, b, up), the viewer at azimuth/elevation;
  //    `right` and `screen_up` span the image plane, `forward` points away from the viewer.
  const int up = options.up_axis, ax = (up + 1) % 3, bx = (up + 2) % 3;
  const double az = options.azimuth_deg * M_PI / 180, el = options.elevation_deg * M_PI / 180;
  const Vec3 to_viewer(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const Vec3 forward = -to_viewer;
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 screen_up = right.cross(forward);

  // 2. Project every point: image-plane coordinates and depth.
  std::vector<double> sx(cloud.size()), sy(cloud.size()), depth(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vec3f& p = cloud.points[i];
    const Vec3 q(p[ax], p[bx], p[up]);
    sx[i] = q.dot(right);
    sy[i] = q.dot(screen_up);
    depth[i] = q.dot(forward);
  }
  const double clip = options.clip_percent;
  const double x0 = percentile(sx, clip), x1 = percentile(sx, 100 - clip);
  const double y0 = percentile(sy, clip), y1 = percentile(sy, 100 - clip);
  const double d0 = percentile(depth, clip), d1 = percentile(depth, 100 - clip);
  const double label_band = label.empty() ? 0 : 16;
  const double avail_w = n - 2.0 * options.margin_px;
  const double avail_h = n - 2.0 * options.margin_px - label_band;
  const double scale =
      std::min(avail_w / std::max(x1 - x0, 1e-3), avail_h / std::max(y1 - y0, 1e-3));
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const double u_mid = 0.5 * n, v_mid = options.margin_px + label_band + 0.5 * avail_h;
  const int half =
      std::clamp(static_cast<int>(std::lround(options.point_size_m * scale / 2)), 0, 4);

  // 3. Z-buffer of squares, shaded by depth (nearest full colour, farthest 45% darker).
  cv::Mat zbuf(n, n, CV_64F, cv::Scalar(std::numeric_limits<double>::infinity()));
  const bool colors = cloud.has_colors();
  const double depth_range = std::max(d1 - d0, 1e-6);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int u = static_cast<int>(std::lround(u_mid + (sx[i] - cx) * scale));
    const int v = static_cast<int>(std::lround(v_mid - (sy[i] - cy) * scale));
    if (u + half < 0 || v + half < 0 || u - half >= n || v - half >= n) continue;
    const Rgb c = colors ? cloud.colors[i] : options.default_color;
    const double shade = 1.0 - 0.45 * std::clamp((depth[i] - d0) / depth_range, 0.0, 1.0);
    const cv::Vec3b bgr(static_cast<uchar>(c.b * shade), static_cast<uchar>(c.g * shade),
                        static_cast<uchar>(c.r * shade));
    for (int dv = -half; dv <= half; ++dv)
      for (int du = -half; du <= half; ++du) {
        const int uu = u + du, vv = v + dv;
        if (uu < 0 || vv < 0 || uu >= n || vv >= n) continue;
        double& z = zbuf.at<double>(vv, uu);
        if (depth[i] >= z) continue;
        z = depth[i];
        image.at<cv::Vec3b>(vv, uu) = bgr;
      }
  }
  cv::rectangle(image, cv::Rect(0, 0, n, n), cv::Scalar(210, 210, 210), 1);
  label_image(image, label);
  return image;
}

}  // namespace objmap::report

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

namespace {

// The thumbnail's view of a set of points: the viewer at azimuth/elevation around the up axis, the
// points framed (clip_percent strays ignored) into the square below the label band.
struct ThumbnailView {
  Vec3 right, screen_up, forward;
  int up = 2, ax = 0, bx = 1;
  double scale = 1, cx = 0, cy = 0, u_mid = 0, v_mid = 0, d0 = 0, d1 = 1;

  ThumbnailView(const std::vector<Vec3f>& points, bool labelled, const ThumbnailOptions& o) {
    up = o.up_axis, ax = (up + 1) % 3, bx = (up + 2) % 3;
    const double az = o.azimuth_deg * M_PI / 180, el = o.elevation_deg * M_PI / 180;
    const Vec3 to_viewer(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    forward = -to_viewer;
    right = forward.cross(Vec3::UnitZ()).normalized();
    screen_up = right.cross(forward);
    std::vector<double> sx, sy, depth;
    for (const Vec3f& p : points) {
      const Vec3 s = screen(p);
      sx.push_back(s.x()), sy.push_back(s.y()), depth.push_back(s.z());
    }
    const double clip = o.clip_percent;
    const double x0 = percentile(sx, clip), x1 = percentile(sx, 100 - clip);
    const double y0 = percentile(sy, clip), y1 = percentile(sy, 100 - clip);
    d0 = percentile(depth, clip), d1 = percentile(depth, 100 - clip);
    const int n = o.size_px;
    const double label_band = labelled ? 16 : 0;
    const double avail_w = n - 2.0 * o.margin_px, avail_h = n - 2.0 * o.margin_px - label_band;
    scale = std::min(avail_w / std::max(x1 - x0, 1e-3), avail_h / std::max(y1 - y0, 1e-3));
    cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    u_mid = 0.5 * n, v_mid = o.margin_px + label_band + 0.5 * avail_h;
  }
  // Image-plane coordinates (right, screen up) and depth along `forward` of a world point.
  Vec3 screen(const Vec3f& p) const {
    const Vec3 q(p[ax], p[bx], p[up]);
    return Vec3(q.dot(right), q.dot(screen_up), q.dot(forward));
  }
  // The pixel (u, v, depth) of a world point.
  Vec3 pixel(const Vec3f& p) const {
    const Vec3 s = screen(p);
    return Vec3(u_mid + (s.x() - cx) * scale, v_mid - (s.y() - cy) * scale, s.z());
  }
  // Nearest full colour, farthest 45% darker.
  double depth_shade(double depth) const {
    return 1.0 - 0.45 * std::clamp((depth - d0) / std::max(d1 - d0, 1e-6), 0.0, 1.0);
  }
};

cv::Vec3b bgr_of(const Rgb& c, double shade) {
  return cv::Vec3b(static_cast<uchar>(std::clamp(c.b * shade, 0.0, 255.0)),
                   static_cast<uchar>(std::clamp(c.g * shade, 0.0, 255.0)),
                   static_cast<uchar>(std::clamp(c.r * shade, 0.0, 255.0)));
}

void frame_and_label(cv::Mat& image, const std::string& label) {
  cv::rectangle(image, cv::Rect(0, 0, image.cols, image.rows), cv::Scalar(210, 210, 210), 1);
  label_image(image, label);
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
  const ThumbnailView view(cloud.points, !label.empty(), options);
  const int half =
      std::clamp(static_cast<int>(std::lround(options.point_size_m * view.scale / 2)), 0, 4);
  // A z-buffer of squares, shaded by depth.
  cv::Mat zbuf(n, n, CV_64F, cv::Scalar(std::numeric_limits<double>::infinity()));
  const bool colors = cloud.has_colors();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vec3 px = view.pixel(cloud.points[i]);
    const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
    if (u + half < 0 || v + half < 0 || u - half >= n || v - half >= n) continue;
    const cv::Vec3b bgr =
        bgr_of(colors ? cloud.colors[i] : options.default_color, view.depth_shade(px.z()));
    for (int dv = -half; dv <= half; ++dv)
      for (int du = -half; du <= half; ++du) {
        const int uu = u + du, vv = v + dv;
        if (uu < 0 || vv < 0 || uu >= n || vv >= n) continue;
        double& z = zbuf.at<double>(vv, uu);
        if (px.z() >= z) continue;
        z = px.z();
        image.at<cv::Vec3b>(vv, uu) = bgr;
      }
  }
  frame_and_label(image, label);
  return image;
}

cv::Mat render_mesh_thumbnail(const TriangleMesh& mesh, Rgb color, const std::string& label,
                              const ThumbnailOptions& options) {
  options.check();
  const int n = options.size_px;
  cv::Mat image(n, n, CV_8UC3, cv::Scalar(255, 255, 255));
  if (mesh.empty()) {
    label_image(image, label);
    return image;
  }
  const ThumbnailView view(mesh.vertices, !label.empty(), options);
  std::vector<Vec3> px;
  for (const Vec3f& p : mesh.vertices) px.push_back(view.pixel(p));
  // Lambert shading from a light over the viewer's left shoulder, with some ambient light.
  const Vec3 light = (-view.forward + 0.5 * view.screen_up - 0.4 * view.right).normalized();
  cv::Mat zbuf(n, n, CV_64F, cv::Scalar(std::numeric_limits<double>::infinity()));
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = px[t[0]], &b = px[t[1]], &c = px[t[2]];
    const Vec3f &wa = mesh.vertices[t[0]], &wb = mesh.vertices[t[1]], &wc = mesh.vertices[t[2]];
    Vec3 normal = view.screen(wb) - view.screen(wa);
    normal = normal.cross(view.screen(wc) - view.screen(wa));
    if (normal.norm() < 1e-12) continue;
    normal.normalize();
    // In (right, screen_up, forward) coordinates the light is:
    const Vec3 l(light.dot(view.right), light.dot(view.screen_up), light.dot(view.forward));
    const double shade = 0.35 + 0.65 * std::abs(normal.dot(l));
    const cv::Vec3b bgr = bgr_of(color, shade);
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (std::abs(area) < 1e-12) continue;
    const int u0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()})))),
              u1 = std::min(n - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()})))),
              v0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()})))),
              v1 = std::min(n - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int v = v0; v <= v1; ++v)
      for (int u = u0; u <= u1; ++u) {
        const double x = u, y = v;  // pixel centres at integer coordinates, as the points
        const double w0 = ((b.x() - x) * (c.y() - y) - (c.x() - x) * (b.y() - y)) / area;
        const double w1 = ((c.x() - x) * (a.y() - y) - (a.x() - x) * (c.y() - y)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
        const double z = w0 * a.z() + w1 * b.z() + w2 * c.z();
        double& zb = zbuf.at<double>(v, u);
        if (z >= zb) continue;
        zb = z;
        image.at<cv::Vec3b>(v, u) = bgr;
      }
  }
  frame_and_label(image, label);
  return image;
}

}  // namespace objmap::report

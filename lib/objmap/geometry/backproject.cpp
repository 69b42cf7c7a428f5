#include "objmap/geometry/backproject.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <thread>

#include "objmap/core/error.h"

namespace objmap::geometry {

RayTable make_ray_table(const Camera& camera, int threads) {
  camera.check();
  RayTable rays;
  rays.width = camera.width;
  rays.height = camera.height;
  rays.depth_factor = camera.depth_factor;
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  rays.x_over_z.resize(n);
  rays.y_over_z.resize(n);
  // Rows t, t + threads, ... on thread t; each pixel is computed on its own, so the table does not
  // depend on the thread count.
  const int t_count = std::max(1, std::min(threads, camera.height));
  auto rows = [&](int t) {
    for (int v = t; v < camera.height; v += t_count) {
      for (int u = 0; u < camera.width; ++u) {
        // Eqs 12-13 with the distortion removed: the normalised coordinates of the pixel's ray.
        const Eigen::Vector2d xy = camera.undistort_pixel(u, v);
        const std::size_t i = static_cast<std::size_t>(v) * camera.width + u;
        rays.x_over_z[i] = static_cast<float>(xy.x());
        rays.y_over_z[i] = static_cast<float>(xy.y());
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < t_count; ++t) pool.emplace_back(rows, t);
  rows(0);
  for (auto& th : pool) th.join();
  return rays;
}

void BackprojectOptions::check() const {
  require(std::isfinite(min_depth_m) && min_depth_m >= 0.0, "BackprojectOptions.min_depth_m",
          "must be finite and >= 0, got " + std::to_string(min_depth_m));
  require(std::isfinite(max_depth_m) && max_depth_m > min_depth_m, "BackprojectOptions.max_depth_m",
          "must be finite and > min_depth_m (" + std::to_string(min_depth_m) + "), got " +
              std::to_string(max_depth_m));
  require(stride >= 1, "BackprojectOptions.stride", "must be >= 1, got " + std::to_string(stride));
}

cv::Rect mask_bounds(const Mask& mask) {
  // Rows are tested 8 bytes at a time (most of a box mask's image is zero); the first and last
  // non-zero pixel are then searched from the row's ends.
  int u0 = mask.width, v0 = mask.height, u1 = -1, v1 = -1;
  const std::size_t w = static_cast<std::size_t>(mask.width);
  for (int v = 0; v < mask.height; ++v) {
    const std::uint8_t* row = mask.data.data() + static_cast<std::size_t>(v) * w;
    std::uint64_t any = 0;
    std::size_t u = 0;
    for (; u + 8 <= w; u += 8) {
      std::uint64_t word;
      std::memcpy(&word, row + u, 8);
      any |= word;
    }
    for (; u < w; ++u) any |= row[u];
    if (!any) continue;
    int first = 0, last = mask.width - 1;
    while (!row[first]) ++first;
    while (!row[last]) --last;
    u0 = std::min(u0, first);
    u1 = std::max(u1, last);
    v0 = std::min(v0, v);
    v1 = std::max(v1, v);
  }
  if (u1 < 0) return {};
  return {u0, v0, u1 - u0 + 1, v1 - v0 + 1};
}

namespace {
std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }
}  // namespace

void check_depth_frame(const RayTable& rays, const DepthFrame& frame) {
  require(!rays.empty(), "backproject", "empty ray table; expected make_ray_table(camera)");
  require(frame.depth != nullptr && frame.depth->type() == CV_16UC1, "backproject: depth",
          "expected a 16-bit single-channel (CV_16UC1) depth image");
  const cv::Mat& depth = *frame.depth;
  require(depth.cols == rays.width && depth.rows == rays.height, "backproject: depth",
          "image is " + size_text(depth.cols, depth.rows) + "; expected the camera's " +
              size_text(rays.width, rays.height));
  if (frame.bgr) {
    require(frame.bgr->type() == CV_8UC3, "backproject: rgb",
            "expected an 8-bit 3-channel (CV_8UC3, BGR) image");
    require(frame.bgr->cols == rays.width && frame.bgr->rows == rays.height, "backproject: rgb",
            "image is " + size_text(frame.bgr->cols, frame.bgr->rows) + "; expected " +
                size_text(rays.width, rays.height) + " like the depth image");
  }
  if (frame.mask) {
    require(frame.mask->width == rays.width && frame.mask->height == rays.height &&
                frame.mask->data.size() == static_cast<std::size_t>(rays.width) * rays.height,
            "backproject: mask",
            "mask is " + size_text(frame.mask->width, frame.mask->height) + "; expected " +
                size_text(rays.width, rays.height) + " like the depth image");
  }
}

PixelTransform::PixelTransform(const RayTable& rays, const DepthFrame& frame,
                               const BackprojectOptions& options) {
  // value / factor in [min_depth_m, max_depth_m] (eq 11 and the validity test of §3.2).
  const double f = rays.depth_factor;
  raw_min =
      std::max<std::uint32_t>(1, static_cast<std::uint32_t>(std::ceil(options.min_depth_m * f)));
  const double raw_max_d = std::floor(options.max_depth_m * f);
  raw_max = raw_max_d >= 65535.0 ? 65535u : static_cast<std::uint32_t>(raw_max_d);
  inv_factor = static_cast<float>(1.0 / f);
  const Eigen::Matrix3f R = frame.world_from_cam.linear().cast<float>();
  const Eigen::Vector3f tr = frame.world_from_cam.translation().cast<float>();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r[3 * i + j] = R(i, j);
    t[i] = tr[i];
  }
}

FrameRow::FrameRow(const RayTable& rays, const DepthFrame& frame, int v) {
  const std::size_t row0 = static_cast<std::size_t>(v) * rays.width;
  depth = frame.depth->ptr<std::uint16_t>(v);
  bgr = frame.bgr ? frame.bgr->ptr<cv::Vec3b>(v) : nullptr;
  mask = frame.mask ? frame.mask->data.data() + row0 : nullptr;
  x_over_z = rays.x_over_z.data() + row0;
  y_over_z = rays.y_over_z.data() + row0;
}

BackprojectResult backproject(const RayTable& rays, const DepthFrame& frame,
                              const BackprojectOptions& options) {
  options.check();
  check_depth_frame(rays, frame);

  cv::Rect roi(0, 0, rays.width, rays.height);
  if (!frame.roi.empty()) roi &= frame.roi;

  BackprojectResult result;
  PointCloud& cloud = result.points_in_world;
  const bool colour = frame.bgr != nullptr;
  const int s = options.stride;
  const std::size_t capacity =
      static_cast<std::size_t>((roi.width + s - 1) / s) * ((roi.height + s - 1) / s);
  // Written through raw pointers into arrays sized for every pixel, trimmed at the end.
  cloud.points.resize(capacity);
  if (colour) cloud.colors.resize(capacity);
  if (options.pixel_indices) result.pixel_index.resize(capacity);
  Vec3f* out_p = cloud.points.data();
  Rgb* out_c = colour ? cloud.colors.data() : nullptr;
  std::uint32_t* out_i = options.pixel_indices ? result.pixel_index.data() : nullptr;
  std::size_t n = 0;

  // Depth range as raw image values, so the per-pixel test is on integers; eq 15 in float (points
  // are stored as float).
  const PixelTransform T(rays, frame, options);
  const std::uint32_t raw_min = T.raw_min, raw_max = T.raw_max;
  const float inv_factor = T.inv_factor;
  double sx = 0.0, sy = 0.0, sz = 0.0;
  std::size_t considered = 0, no_depth = 0;

  for (int v = roi.y; v < roi.y + roi.height; v += s) {
    const FrameRow row(rays, frame, v);
    const std::uint16_t* drow = row.depth;
    const cv::Vec3b* crow = row.bgr;
    const std::uint8_t* mrow = row.mask;
    const float* rx = row.x_over_z;
    const float* ry = row.y_over_z;
    const std::size_t row0 = static_cast<std::size_t>(v) * rays.width;
    // Per-row sums in float (short, exact enough), accumulated in double per row.
    float rsx = 0.f, rsy = 0.f, rsz = 0.f;
    for (int u = roi.x; u < roi.x + roi.width; u += s) {
      if (mrow && !mrow[u]) continue;
      ++considered;
      const std::uint32_t raw = drow[u];
      if (raw < raw_min || raw > raw_max) {
        no_depth += raw == 0;
        continue;
      }
      // Eqs 11-14: depth in metres, then the camera-frame point along the pixel's ray.
      const float z = static_cast<float>(raw) * inv_factor;
      const float x = rx[u] * z;
      const float y = ry[u] * z;
      rsx += x;
      rsy += y;
      rsz += z;
      out_p[n] = Vec3f(T.world_x(x, y, z), T.world_y(x, y, z), T.world_z(x, y, z));
      if (out_c) {
        const cv::Vec3b& c = crow[u];
        out_c[n] = Rgb{c[2], c[1], c[0]};
      }
      if (out_i) out_i[n] = static_cast<std::uint32_t>(row0 + u);
      ++n;
    }
    sx += rsx;
    sy += rsy;
    sz += rsz;
  }
  cloud.points.resize(n);
  if (colour) cloud.colors.resize(n);
  if (out_i) result.pixel_index.resize(n);
  result.pixels_considered = considered;
  result.pixels_no_depth = no_depth;
  result.pixels_out_of_range = considered - no_depth - n;
  if (n > 0) result.centroid_in_cam = Vec3(sx, sy, sz) / static_cast<double>(n);
  return result;
}

}  // namespace objmap::geometry

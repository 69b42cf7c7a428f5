#include "objmap/segmentation/depth_gate.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "objmap/core/error.h"

namespace objmap::segmentation {

namespace {

std::string num(double v) { return std::to_string(v); }

// The raw depth values (in range) of the mask's pixels inside `roi`, into `out`.
void collect_depths(const Mask& mask, const cv::Rect& roi, const cv::Mat& depth,
                    std::uint16_t raw_min, std::uint16_t raw_max, std::vector<std::uint16_t>& out) {
  out.clear();
  for (int v = roi.y; v < roi.y + roi.height; ++v) {
    const std::uint8_t* m = mask.data.data() + static_cast<std::size_t>(v) * mask.width;
    const std::uint16_t* d = depth.ptr<std::uint16_t>(v);
    for (int u = roi.x; u < roi.x + roi.width; ++u)
      if (m[u] && d[u] >= raw_min && d[u] <= raw_max) out.push_back(d[u]);
  }
}

void check_inputs(const Mask& mask, const cv::Mat& depth, const Camera& camera) {
  require(mask.width > 0 && mask.height > 0 &&
              mask.data.size() ==
                  static_cast<std::size_t>(mask.width) * static_cast<std::size_t>(mask.height),
          "gate_mask_depth: mask", "data size does not match its width x height");
  require(depth.type() == CV_16UC1 && depth.cols == mask.width && depth.rows == mask.height,
          "gate_mask_depth: depth",
          "expected a 16-bit single-channel image of the mask's size " +
              std::to_string(mask.width) + "x" + std::to_string(mask.height));
  require(camera.fx > 0 && camera.fy > 0 && std::isfinite(camera.fx) && std::isfinite(camera.fy) &&
              camera.depth_factor > 0 && std::isfinite(camera.depth_factor),
          "gate_mask_depth: camera", "fx, fy and depth_factor must be finite and > 0");
}

}  // namespace

void DepthGateOptions::check() const {
  require(std::isfinite(min_depth_m) && min_depth_m >= 0, "DepthGateOptions.min_depth_m",
          "must be finite and >= 0, got " + num(min_depth_m));
  require(std::isfinite(max_depth_m) && max_depth_m > min_depth_m, "DepthGateOptions.max_depth_m",
          "must be finite and > min_depth_m, got " + num(max_depth_m));
  require(std::isfinite(size_factor) && size_factor > 0, "DepthGateOptions.size_factor",
          "must be finite and > 0, got " + num(size_factor));
  require(std::isfinite(min_band_m) && min_band_m >= 0, "DepthGateOptions.min_band_m",
          "must be finite and >= 0, got " + num(min_band_m));
  require(std::isfinite(noise_m_per_m2) && noise_m_per_m2 >= 0, "DepthGateOptions.noise_m_per_m2",
          "must be finite and >= 0, got " + num(noise_m_per_m2));
}

DepthGateResult gate_mask_depth(const Mask& mask, const cv::Rect& bounds, const cv::Mat& depth,
                                const Camera& camera, const DepthGateOptions& options) {
  options.check();
  check_inputs(mask, depth, camera);
  DepthGateResult result;
  const cv::Rect roi = bounds & cv::Rect(0, 0, mask.width, mask.height);
  if (roi.empty()) return result;

  // 1. The mask's depths in range (raw values: the depth factor scales them all alike).
  const double factor = camera.depth_factor;
  const auto raw = [&](double z_m) {
    return static_cast<std::uint16_t>(std::clamp(z_m * factor, 0.0, 65535.0));
  };
  const std::uint16_t raw_min = std::max<std::uint16_t>(1, raw(options.min_depth_m));
  const std::uint16_t raw_max = raw(options.max_depth_m);
  thread_local std::vector<std::uint16_t> depths;
  collect_depths(mask, roi, depth, raw_min, raw_max, depths);
  result.pixels = depths.size();
  if (depths.empty()) return result;

  // 2. z_med, the object's size S across the ray, and the band.
  auto mid = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
  std::nth_element(depths.begin(), mid, depths.end());
  const double z_med = *mid / factor;
  // The geometric mean of the box's sides: a bottle (tall, thin) is as deep as it is wide, not as
  // tall; a table seen at a grazing angle keeps its depth range (wide and fairly high in view).
  const double extent_px = std::sqrt((roi.width / camera.fx) * (roi.height / camera.fy));
  result.median_depth_m = z_med;
  result.size_m = extent_px * z_med;
  result.band_m = std::max(options.size_factor * result.size_m, options.min_band_m) +
                  options.noise_m_per_m2 * z_med * z_med;

  // 3. The pixels outside the band leave the mask (copied only when there are any).
  const double lo = (z_med - result.band_m) * factor, hi = (z_med + result.band_m) * factor;
  for (std::uint16_t d : depths) result.removed_pixels += d < lo || d > hi;
  if (result.removed_pixels == 0) return result;
  result.mask = mask;
  int u0 = roi.x + roi.width, v0 = roi.y + roi.height, u1 = roi.x - 1, v1 = roi.y - 1;
  for (int v = roi.y; v < roi.y + roi.height; ++v) {
    std::uint8_t* m = result.mask.data.data() + static_cast<std::size_t>(v) * mask.width;
    const std::uint16_t* d = depth.ptr<std::uint16_t>(v);
    for (int u = roi.x; u < roi.x + roi.width; ++u) {
      if (!m[u]) continue;
      if (d[u] >= raw_min && d[u] <= raw_max && (d[u] < lo || d[u] > hi)) {
        m[u] = 0;
        continue;
      }
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
  }
  if (u1 >= u0) result.bounds = cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1);
  return result;
}

}  // namespace objmap::segmentation

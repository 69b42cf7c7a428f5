#include "objmap/segmentation/mask_refine.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "objmap/core/error.h"

namespace objmap::segmentation {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string num(double v) { return std::to_string(v); }

// Per thread, reused from one mask to the next (no allocation per instance).
struct Workspace {
  std::vector<float> z;             // ROI-local depth in metres
  std::vector<std::int32_t> label;  // part id, or kOutside / kUnvisited
  std::vector<std::int32_t> queue;  // ROI-local pixel indices
  std::vector<std::size_t> sizes;   // pixels per part
};

Workspace& workspace() {
  thread_local Workspace ws;
  return ws;
}

constexpr std::int32_t kOutside = -1;    // not in the mask, or no depth in range
constexpr std::int32_t kUnvisited = -2;  // in the mask with depth, part not known yet

// Step 1: the mask's pixels with depth in range, ROI-local, into ws.z (metres) and ws.label
// (kUnvisited; kOutside for the others).
void mask_depths(Workspace& ws, const Mask& mask, const cv::Rect& roi, const cv::Mat& depth,
                 const Camera& camera, const MaskRefineOptions& options) {
  const int width = mask.width, bw = roi.width, bh = roi.height;
  const std::size_t area = static_cast<std::size_t>(bw) * static_cast<std::size_t>(bh);
  ws.z.assign(area, 0.f);
  ws.label.assign(area, kOutside);
  const float to_m = static_cast<float>(1.0 / camera.depth_factor);
  const float zmin = static_cast<float>(options.min_depth_m);
  const float zmax = static_cast<float>(options.max_depth_m);
  for (int y = 0; y < bh; ++y) {
    const std::uint8_t* m = mask.data.data() + static_cast<std::size_t>(roi.y + y) * width + roi.x;
    const std::uint16_t* d = depth.ptr<std::uint16_t>(roi.y + y) + roi.x;
    const std::size_t row = static_cast<std::size_t>(y) * bw;
    for (int x = 0; x < bw; ++x) {
      if (!m[x]) continue;
      const float z = d[x] * to_m;
      if (z < zmin || z > zmax) continue;
      ws.z[row + x] = z;
      ws.label[row + x] = kUnvisited;
    }
  }
}

// Step 2: parts of smooth depth: 8-neighbours join when their depths differ by at most the step
// of the nearer one (a symmetric rule, so the parts do not depend on the visiting order). Labels
// the pixels of step 1 with their part in ws.label, the part sizes in ws.sizes.
void smooth_parts(Workspace& ws, int bw, int bh, const Camera& camera,
                  const MaskRefineOptions& options) {
  const std::size_t area = static_cast<std::size_t>(bw) * static_cast<std::size_t>(bh);
  const float slope_per_m = static_cast<float>(std::tan(options.smooth_max_slope_deg * kPi / 180) *
                                               2 / (camera.fx + camera.fy));
  const float noise_per_m2 = static_cast<float>(options.smooth_noise_m_per_m2);
  static constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  ws.sizes.clear();
  for (std::size_t start = 0; start < area; ++start) {
    if (ws.label[start] != kUnvisited) continue;
    const std::int32_t id = static_cast<std::int32_t>(ws.sizes.size());
    ws.label[start] = id;
    ws.queue.assign(1, static_cast<std::int32_t>(start));
    for (std::size_t head = 0; head < ws.queue.size(); ++head) {
      const std::int32_t i = ws.queue[head];
      const int x = i % bw, y = i / bw;
      const float zi = ws.z[static_cast<std::size_t>(i)];
      for (int k = 0; k < 8; ++k) {
        const int xx = x + kDx[k], yy = y + kDy[k];
        if (xx < 0 || yy < 0 || xx >= bw || yy >= bh) continue;
        const std::int32_t j = yy * bw + xx;
        if (ws.label[static_cast<std::size_t>(j)] != kUnvisited) continue;
        const float zj = ws.z[static_cast<std::size_t>(j)];
        const float near = std::min(zi, zj);
        if (std::abs(zj - zi) > near * (slope_per_m + noise_per_m2 * near)) continue;
        ws.label[static_cast<std::size_t>(j)] = id;
        ws.queue.push_back(j);
      }
    }
    ws.sizes.push_back(ws.queue.size());
  }
}

// Step 3: spill, per part: parts without a pixel deeper than rim_px inside the mask (outside the
// ROI, i.e. the mask's outside and the image's border, counts as outside) and below
// min_part_share of the largest part.
std::vector<bool> spill_parts(const Workspace& ws, const Mask& mask, const cv::Rect& roi,
                              const MaskRefineOptions& options) {
  const int width = mask.width, bw = roi.width, bh = roi.height;
  cv::Mat inside(bh, bw, CV_8UC1);
  for (int y = 0; y < bh; ++y)
    std::copy_n(mask.data.data() + static_cast<std::size_t>(roi.y + y) * width + roi.x, bw,
                inside.ptr<std::uint8_t>(y));
  cv::Mat core;
  cv::erode(inside, core,
            cv::getStructuringElement(cv::MORPH_RECT,
                                      cv::Size(2 * options.rim_px + 1, 2 * options.rim_px + 1)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  std::vector<bool> deep(ws.sizes.size(), false);
  for (int y = 0; y < bh; ++y) {
    const std::uint8_t* c = core.ptr<std::uint8_t>(y);
    const std::int32_t* l = ws.label.data() + static_cast<std::size_t>(y) * bw;
    for (int x = 0; x < bw; ++x)
      if (c[x] && l[x] >= 0) deep[static_cast<std::size_t>(l[x])] = true;
  }
  const std::size_t largest = *std::max_element(ws.sizes.begin(), ws.sizes.end());
  const double share = options.min_part_share * static_cast<double>(largest);
  std::vector<bool> spill(ws.sizes.size(), false);
  for (std::size_t id = 0; id < ws.sizes.size(); ++id)
    spill[id] = !deep[id] && static_cast<double>(ws.sizes[id]) < share;
  return spill;
}

// Step 4: the spill parts' pixels leave result.mask (counted in removed_pixels); result.bounds is
// the rectangle of the kept pixels.
void remove_spill(const Workspace& ws, const cv::Rect& roi, const std::vector<bool>& spill,
                  MaskRefineResult& result) {
  const int width = result.mask.width, bw = roi.width, bh = roi.height;
  int x0 = bw, x1 = -1, y0 = bh, y1 = -1;
  for (int y = 0; y < bh; ++y) {
    std::uint8_t* m = result.mask.data.data() + static_cast<std::size_t>(roi.y + y) * width + roi.x;
    const std::int32_t* l = ws.label.data() + static_cast<std::size_t>(y) * bw;
    for (int x = 0; x < bw; ++x) {
      if (!m[x]) continue;
      if (l[x] >= 0 && spill[static_cast<std::size_t>(l[x])]) {
        m[x] = 0;
        ++result.removed_pixels;
        continue;
      }
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
  }
  if (x1 >= 0) result.bounds = cv::Rect(roi.x + x0, roi.y + y0, x1 - x0 + 1, y1 - y0 + 1);
}

}  // namespace

void MaskRefineOptions::check() const {
  require(std::isfinite(min_depth_m) && min_depth_m >= 0, "MaskRefineOptions.min_depth_m",
          "must be finite and >= 0, got " + num(min_depth_m));
  require(std::isfinite(max_depth_m) && max_depth_m > min_depth_m, "MaskRefineOptions.max_depth_m",
          "must be finite and > min_depth_m, got " + num(max_depth_m));
  require(
      std::isfinite(smooth_max_slope_deg) && smooth_max_slope_deg >= 0 && smooth_max_slope_deg < 90,
      "MaskRefineOptions.smooth_max_slope_deg",
      "must be in [0, 90) degrees, got " + num(smooth_max_slope_deg));
  require(std::isfinite(smooth_noise_m_per_m2) && smooth_noise_m_per_m2 >= 0,
          "MaskRefineOptions.smooth_noise_m_per_m2",
          "must be finite and >= 0, got " + num(smooth_noise_m_per_m2));
  require(rim_px >= 0 && rim_px <= 64, "MaskRefineOptions.rim_px",
          "must be in [0, 64], got " + std::to_string(rim_px));
  require(std::isfinite(min_part_share) && min_part_share >= 0 && min_part_share <= 1,
          "MaskRefineOptions.min_part_share", "must be in [0, 1], got " + num(min_part_share));
}

MaskRefineResult refine_mask(const Mask& mask, const cv::Rect& bounds, const cv::Mat& depth,
                             const Camera& camera, const MaskRefineOptions& options) {
  options.check();
  const int width = mask.width, height = mask.height;
  require(
      width > 0 && height > 0 &&
          mask.data.size() == static_cast<std::size_t>(width) * static_cast<std::size_t>(height),
      "refine_mask: mask", "data size does not match its width x height");
  require(depth.type() == CV_16UC1 && depth.cols == width && depth.rows == height,
          "refine_mask: depth",
          "expected a 16-bit single-channel image of the mask's size " + std::to_string(width) +
              "x" + std::to_string(height));
  require(camera.fx > 0 && camera.fy > 0 && std::isfinite(camera.fx) && std::isfinite(camera.fy) &&
              camera.depth_factor > 0 && std::isfinite(camera.depth_factor),
          "refine_mask: camera", "fx, fy and depth_factor must be finite and > 0");

  MaskRefineResult result;
  result.mask = mask;
  const cv::Rect roi = bounds & cv::Rect(0, 0, width, height);
  if (roi.empty()) return result;
  Workspace& ws = workspace();

  // 1. The mask's pixels with depth in range, ROI-local.
  mask_depths(ws, mask, roi, depth, camera, options);

  // 2. Parts of smooth depth.
  smooth_parts(ws, roi.width, roi.height, camera, options);
  result.parts = ws.sizes.size();
  if (ws.sizes.size() <= 1) {
    result.bounds = roi;
    return result;
  }

  // 3. Spill: parts within rim_px of the outline everywhere and smaller than min_part_share of the
  //    largest.
  const std::vector<bool> spill = spill_parts(ws, mask, roi, options);
  for (std::size_t id = 0; id < spill.size(); ++id) result.removed_parts += spill[id];
  if (result.removed_parts == 0) {
    result.bounds = roi;
    return result;
  }

  // 4. The spill parts leave the mask; everything else stays, pixels without depth included.
  remove_spill(ws, roi, spill, result);
  return result;
}

}  // namespace objmap::segmentation

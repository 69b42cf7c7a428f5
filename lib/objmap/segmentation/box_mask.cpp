#include "objmap/segmentation/box_mask.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/segmentation/box_mask_internal.h"

namespace objmap::segmentation {

using namespace box_mask_detail;

namespace {

std::string num(double v) {
  std::string s = std::to_string(v);
  while (s.size() > 1 && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

void require_range(double value, double lo, double hi, const char* field, const std::string& what) {
  require(std::isfinite(value) && value >= lo && value <= hi,
          std::string("BoxMaskOptions.") + field, what + ", got " + num(value));
}

int clip(double value, int hi) {
  if (!std::isfinite(value)) return 0;
  return static_cast<int>(std::clamp(value, 0.0, static_cast<double>(hi)));
}

ClippedBox clip_box(const Box& box, int width, int height) {
  return {clip(std::floor(box.x), width), clip(std::floor(box.y), height),
          clip(std::ceil(box.x + box.w), width), clip(std::ceil(box.y + box.h), height)};
}

// Step 1: the pixel rays of the image and the valid depths of the box into ws (z_m, kValid);
// counts them into valid_pixels. The bins are meaningful only when valid_pixels > 0.
DepthBins valid_depths(const BoxPixels& b, std::size_t& valid_pixels) {
  Workspace& ws = b.ws;
  ws.ray_x.resize(static_cast<std::size_t>(b.width));
  for (int u = 0; u < b.width; ++u)
    ws.ray_x[u] = static_cast<float>((u - b.camera.cx) / b.camera.fx);
  ws.ray_y.resize(static_cast<std::size_t>(b.height));
  for (int v = 0; v < b.height; ++v)
    ws.ray_y[v] = static_cast<float>((v - b.camera.cy) / b.camera.fy);
  ws.z_m.resize(b.area);
  ws.flags.assign(b.area, 0);
  float z_lo = b.zmax, z_hi = 0;
  for (int y = 0; y < b.bh; ++y) {
    const std::uint16_t* src = b.depth.ptr<std::uint16_t>(b.v0 + y) + b.u0;
    float* dst = ws.z_m.data() + static_cast<std::size_t>(y) * b.bw;
    std::uint8_t* fl = ws.flags.data() + static_cast<std::size_t>(y) * b.bw;
    for (int x = 0; x < b.bw; ++x) {
      const float z = src[x] * b.to_m;
      if (z >= b.zmin && z <= b.zmax) {
        dst[x] = z;
        fl[x] = kValid;
        z_lo = std::min(z_lo, z);
        z_hi = std::max(z_hi, z);
        ++valid_pixels;
      } else {
        dst[x] = 0;
      }
    }
  }
  return {z_lo, std::max(1, static_cast<int>((z_hi - z_lo) / b.options.bin_m) + 1)};
}

// Step 2, the histogram's weights: a separable Gaussian around the box centre, box-local.
void centre_weights(const BoxPixels& b) {
  Workspace& ws = b.ws;
  ws.weight_u.resize(static_cast<std::size_t>(b.bw));
  ws.weight_v.resize(static_cast<std::size_t>(b.bh));
  const double cu = b.box.x + 0.5 * b.box.w, cv = b.box.y + 0.5 * b.box.h;
  const double su = std::max(1.0, b.options.center_sigma_fraction * b.box.w);
  const double sv = std::max(1.0, b.options.center_sigma_fraction * b.box.h);
  for (int x = 0; x < b.bw; ++x) {
    const double t = (b.u0 + x + 0.5 - cu) / su;
    ws.weight_u[x] = static_cast<float>(std::exp(-0.5 * t * t));
  }
  for (int y = 0; y < b.bh; ++y) {
    const double t = (b.v0 + y + 0.5 - cv) / sv;
    ws.weight_v[y] = static_cast<float>(std::exp(-0.5 * t * t));
  }
}

// Step 2: the object's depth, the near mode of the histogram of the valid pixels without `exclude`
// flags; 0 when there is none.
double object_depth(const BoxPixels& b, const DepthBins& bins, std::uint8_t exclude) {
  return near_mode(b.ws, b.bw, b.bh, bins.z_lo, bins.bins, b.options.bin_m,
                   b.options.near_mode_min_share, exclude);
}

// Step 3, the plane samples: valid depths of the box's bottom rows and of the rows just below it,
// on a grid of at most about support_max_samples points, into ws.samples (camera frame).
void sample_support_strip(const BoxPixels& b) {
  const BoxMaskOptions& options = b.options;
  Workspace& ws = b.ws;
  const int rows_bottom = static_cast<int>(std::ceil(options.support_bottom_fraction * b.bh));
  const int rows_below = static_cast<int>(std::ceil(options.support_below_fraction * b.box.h));
  const int s0 = std::max(b.v0, b.v1 - rows_bottom), s1 = std::min(b.height, b.v1 + rows_below);
  ws.samples.clear();
  if (s1 <= s0) return;
  const double strip = static_cast<double>(b.bw) * (s1 - s0);
  const int stride =
      std::max(1, static_cast<int>(std::ceil(std::sqrt(strip / options.support_max_samples))));
  for (int v = s0; v < s1; v += stride) {
    for (int u = b.u0; u < b.u1; u += stride) {
      const float z = b.depth_at(u, v);
      if (z > 0) ws.samples.emplace_back(ws.ray_x[u] * z, ws.ray_y[v] * z, z);
    }
  }
}

// Step 3: flags the box pixels on the plane or beyond it kSupport (and no other); returns how many.
std::size_t set_aside_plane_pixels(const BoxPixels& b, const Plane& plane) {
  Workspace& ws = b.ws;
  std::size_t removed = 0;
  for (int y = 0; y < b.bh; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * b.bw;
    const float ry = ws.ray_y[b.v0 + y];
    for (int x = 0; x < b.bw; ++x) {
      std::uint8_t& f = ws.flags[row + x];
      f &= static_cast<std::uint8_t>(~kSupport);
      if (!(f & kValid)) continue;
      const float z = ws.z_m[row + x];
      const float dist =
          z * (plane.n.x() * ws.ray_x[b.u0 + x] + plane.n.y() * ry + plane.n.z()) + plane.d;
      if (dist < b.thr) {
        f |= kSupport;
        ++removed;
      }
    }
  }
  return removed;
}

// Step 3: does the object found without any plane (mode0's central pixels; the whole box's when
// the centre has none) stand on the camera's side of the plane? An occluder's face or the object's
// own face has the object behind it or on it.
bool object_stands_on(const BoxPixels& b, const Plane& plane, double mode0) {
  const Workspace& ws = b.ws;
  std::size_t above = 0, beyond = 0, count = 0;
  for (int pass = 0; pass < 2 && count == 0; ++pass) {
    const Window win = b.seed_window(pass == 0 ? b.options.seed_center_fraction : 1.0);
    for (int y = win.y0; y < win.y1; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * b.bw;
      const float ry = ws.ray_y[b.v0 + y];
      for (int x = win.x0; x < win.x1; ++x) {
        const float z = ws.z_m[row + x];
        if (!(ws.flags[row + x] & kValid) || std::abs(z - mode0) > b.tol) continue;
        const float dist =
            z * (plane.n.x() * ws.ray_x[b.u0 + x] + plane.n.y() * ry + plane.n.z()) + plane.d;
        above += dist > b.thr;
        beyond += dist < -b.thr;
        ++count;
      }
    }
  }
  return count > 0 && static_cast<double>(above) >= b.options.support_min_above_share * count &&
         static_cast<double>(beyond) <= b.options.support_max_beyond_share * count;
}

// Step 3: drops the plane's inliers from ws.samples, so that the next plane can be fitted.
void drop_plane_samples(const BoxPixels& b, const Plane& plane) {
  auto& samples = b.ws.samples;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (std::abs(plane.n.dot(samples[i]) + plane.d) > b.thr) samples[kept++] = samples[i];
  }
  samples.resize(kept);
}

// Step 3: the supporting surface. Planes are fitted to the box's bottom rows and the rows just
// below it; a plane is accepted when it is well supported, leaves a fair share of the box, and the
// object found without it (mode0) stands on it, on the camera's side. A rejected plane (an
// occluder's or the object's own face) gives up its samples and the next one is tried. With a
// plane, its pixels keep kSupport, the result gets the plane, and the object's depth is taken again
// without them: returned, mode0 without a plane.
double supporting_surface(const BoxPixels& b, const DepthBins& bins, double mode0,
                          BoxMaskResult& result) {
  const BoxMaskOptions& options = b.options;
  Workspace& ws = b.ws;
  sample_support_strip(b);
  for (int attempt = 0; attempt < options.support_max_planes; ++attempt) {
    const Plane plane =
        fit_plane(ws.samples, b.thr, options.support_ransac_iterations, ws.sample_inlier);
    const double needed = std::max<double>(options.support_min_inliers,
                                           options.support_min_inlier_share * ws.samples.size());
    if (!plane.valid || static_cast<double>(plane.inliers) < needed) break;
    // Set aside the box pixels on the plane or beyond it (the object stands on the camera's side).
    const std::size_t removed = set_aside_plane_pixels(b, plane);
    // The plane must leave a fair share of the box, and the object must stand on it.
    if (removed * 10 <= result.valid_pixels * 9 && object_stands_on(b, plane, mode0)) {
      const double mode = object_depth(b, bins, kSupport);
      if (mode > 0) {
        result.support_plane_removed = true;
        result.support_inliers = plane.inliers;
        result.support_pixels_removed = removed;
        result.support_plane_in_cam << plane.n.cast<double>(), plane.d;
        return mode;
      }
    }
    drop_plane_samples(b, plane);
  }
  for (auto& f : ws.flags) f &= static_cast<std::uint8_t>(~kSupport);
  return mode0;
}

// Step 6: a closing of the region (kInMask) into ws.scratch, restricted to pixels that may belong
// to the object (no depth, or in the band).
void close_region(const BoxPixels& b) {
  Workspace& ws = b.ws;
  auto& bits = ws.scratch;
  bits.resize(b.area);
  for (std::size_t i = 0; i < b.area; ++i) bits[i] = (ws.flags[i] & kInMask) ? 1 : 0;
  if (b.options.close_radius_px <= 0) return;
  morph(bits, ws.scratch2, b.bw, b.bh, b.options.close_radius_px, true);
  morph(bits, ws.scratch2, b.bw, b.bh, b.options.close_radius_px, false);
  for (std::size_t i = 0; i < b.area; ++i) {
    const std::uint8_t f = ws.flags[i];
    if (bits[i] && !(f & kInMask) && (f & kValid) && !(f & kBand)) bits[i] = 0;
  }
}

// The pixels of a mask and their bounding rectangle.
struct MaskExtent {
  std::size_t pixels = 0;
  cv::Rect bounds;
};

// Step 6: copies the closed region (ws.scratch) into the full-image mask; returns its extent.
MaskExtent place_in_mask(const BoxPixels& b, Mask& mask) {
  const auto& bits = b.ws.scratch;
  std::size_t pixels = 0;
  int bx0 = b.bw, bx1 = -1, by0 = b.bh, by1 = -1;  // box-local bounds of the mask's pixels
  for (int y = 0; y < b.bh; ++y) {
    std::uint8_t* out = mask.data.data() + static_cast<std::size_t>(b.v0 + y) * b.width + b.u0;
    const std::uint8_t* in = bits.data() + static_cast<std::size_t>(y) * b.bw;
    std::size_t row_pixels = 0;
    for (int x = 0; x < b.bw; ++x) {
      out[x] = in[x];
      row_pixels += in[x];
    }
    if (row_pixels == 0) continue;
    pixels += row_pixels;
    int first = 0, last = b.bw - 1;
    while (!in[first]) ++first;
    while (!in[last]) --last;
    bx0 = std::min(bx0, first);
    bx1 = std::max(bx1, last);
    by0 = std::min(by0, y);
    by1 = std::max(by1, y);
  }
  return {pixels, cv::Rect(b.u0 + bx0, b.v0 + by0, bx1 - bx0 + 1, by1 - by0 + 1)};
}

// Step 6: the closed region into result's mask, with its pixels, bounds and status (kTooSmall and
// an empty mask below the minimum area).
void clean_up(const BoxPixels& b, BoxMaskResult& result) {
  close_region(b);
  const MaskExtent extent = place_in_mask(b, result.mask);
  const double min_area = std::max<double>(
      b.options.min_pixels, b.options.min_box_fraction * static_cast<double>(b.area));
  if (static_cast<double>(extent.pixels) < min_area || extent.pixels == 0) {
    std::fill(result.mask.data.begin(), result.mask.data.end(), 0);
    result.status = BoxMaskStatus::kTooSmall;
    return;
  }
  result.pixels = extent.pixels;
  result.bounds = extent.bounds;
  result.status = BoxMaskStatus::kOk;
}

}  // namespace

void BoxMaskOptions::check() const {
  require_range(min_depth_m, 0.0, 1e3, "min_depth_m", "must be >= 0");
  require_range(max_depth_m, min_depth_m + 1e-9, 1e3, "max_depth_m", "must be > min_depth_m");
  require_range(bin_m, 1e-4, 1.0, "bin_m", "must be in (0, 1] metres");
  require(bin_m > 0 && (max_depth_m - min_depth_m) / bin_m <= 100000, "BoxMaskOptions.bin_m",
          "gives more than 100000 histogram bins over [min_depth_m, max_depth_m]");
  require_range(center_sigma_fraction, 1e-3, 1e3, "center_sigma_fraction", "must be > 0");
  require_range(near_mode_min_share, 0.0, 1.0, "near_mode_min_share", "must be in [0, 1]");
  require_range(seed_component_min_share, 0.0, 1.0, "seed_component_min_share",
                "must be in [0, 1]");
  require_range(seed_tolerance_bins, 0.5, 100.0, "seed_tolerance_bins", "must be in [0.5, 100]");
  require(
      std::isfinite(seed_center_fraction) && seed_center_fraction > 0 && seed_center_fraction <= 1,
      "BoxMaskOptions.seed_center_fraction", "must be in (0, 1], got " + num(seed_center_fraction));
  require_range(smooth_max_slope_deg, 0.0, 89.9, "smooth_max_slope_deg",
                "must be in [0, 89.9] degrees");
  require_range(smooth_noise_m_per_m2, 0.0, 1.0, "smooth_noise_m_per_m2", "must be in [0, 1]");
  require(smooth_max_slope_deg > 0 || smooth_noise_m_per_m2 > 0,
          "BoxMaskOptions.smooth_noise_m_per_m2", "must be > 0 when smooth_max_slope_deg is 0");
  require(connectivity == 4 || connectivity == 8, "BoxMaskOptions.connectivity",
          "must be 4 or 8, got " + std::to_string(connectivity));
  require_range(band_size_factor, 0.0, 100.0, "band_size_factor", "must be >= 0");
  require_range(band_min_m, 0.0, 1e3, "band_min_m", "must be >= 0");
  require_range(band_near_fraction, 0.0, 1.0, "band_near_fraction", "must be in [0, 1]");
  require_range(band_max_m, band_min_m, 1e3, "band_max_m", "must be >= band_min_m");
  require_range(support_inlier_m, 1e-4, 1.0, "support_inlier_m", "must be in (0, 1] metres");
  require_range(support_bottom_fraction, 0.0, 1.0, "support_bottom_fraction", "must be in [0, 1]");
  require_range(support_below_fraction, 0.0, 10.0, "support_below_fraction", "must be in [0, 10]");
  require(support_bottom_fraction > 0 || support_below_fraction > 0,
          "BoxMaskOptions.support_below_fraction",
          "must be > 0 when support_bottom_fraction is 0 (no rows to fit the plane to)");
  require_range(support_min_inlier_share, 0.0, 1.0, "support_min_inlier_share",
                "must be in [0, 1]");
  require(support_min_inliers >= 3, "BoxMaskOptions.support_min_inliers",
          "must be >= 3, got " + std::to_string(support_min_inliers));
  require(support_max_samples >= 3, "BoxMaskOptions.support_max_samples",
          "must be >= 3, got " + std::to_string(support_max_samples));
  require(support_ransac_iterations >= 1, "BoxMaskOptions.support_ransac_iterations",
          "must be >= 1, got " + std::to_string(support_ransac_iterations));
  require_range(support_reclaim_angle_deg, 0.0, 90.0, "support_reclaim_angle_deg",
                "must be in [0, 90] degrees");
  require(support_max_planes >= 1 && support_max_planes <= 10, "BoxMaskOptions.support_max_planes",
          "must be in [1, 10], got " + std::to_string(support_max_planes));
  require_range(support_min_above_share, 0.0, 1.0, "support_min_above_share", "must be in [0, 1]");
  require_range(support_max_beyond_share, 0.0, 1.0, "support_max_beyond_share",
                "must be in [0, 1]");
  require(close_radius_px >= 0 && close_radius_px <= 50, "BoxMaskOptions.close_radius_px",
          "must be in [0, 50], got " + std::to_string(close_radius_px));
  require(min_pixels >= 0, "BoxMaskOptions.min_pixels",
          "must be >= 0, got " + std::to_string(min_pixels));
  require_range(min_box_fraction, 0.0, 1.0, "min_box_fraction", "must be in [0, 1]");
  require(depth_candidates >= 1 && depth_candidates <= 10, "BoxMaskOptions.depth_candidates",
          "must be in [1, 10], got " + std::to_string(depth_candidates));
  require_range(max_border_leak, 0.0, 1.0, "max_border_leak", "must be in [0, 1]");
}

const char* to_string(BoxMaskStatus status) {
  switch (status) {
    case BoxMaskStatus::kOk:
      return "ok";
    case BoxMaskStatus::kOutsideImage:
      return "box outside the image";
    case BoxMaskStatus::kNoValidDepth:
      return "no valid depth in the box";
    case BoxMaskStatus::kTooSmall:
      return "region below the minimum area";
  }
  return "?";
}

BoxMaskResult mask_from_box(const Box& box, const cv::Mat& depth, const Camera& camera,
                            const BoxMaskOptions& options) {
  require(depth.empty() || depth.type() == CV_16UC1, "mask_from_box: depth",
          "image type " + std::to_string(depth.type()) + "; expected CV_16UC1 (16-bit raw depth)");
  require(camera.fx > 0 && camera.fy > 0 && std::isfinite(camera.fx) && std::isfinite(camera.fy),
          "mask_from_box: camera", "fx and fy must be finite and > 0");
  require(camera.depth_factor > 0 && std::isfinite(camera.depth_factor), "mask_from_box: camera",
          "depth_factor must be finite and > 0");

  BoxMaskResult result;
  if (depth.empty()) {
    result.status = BoxMaskStatus::kOutsideImage;
    return result;
  }
  result.mask.width = depth.cols;
  result.mask.height = depth.rows;
  result.mask.data.assign(static_cast<std::size_t>(depth.cols) * depth.rows, 0);

  // 1. Valid depths inside the box clipped to the image.
  const ClippedBox clipped = clip_box(box, depth.cols, depth.rows);
  result.u0 = clipped.u0;
  result.v0 = clipped.v0;
  result.u1 = std::max(clipped.u0, clipped.u1);
  result.v1 = std::max(clipped.v0, clipped.v1);
  if (clipped.u1 <= clipped.u0 || clipped.v1 <= clipped.v0) {
    result.status = BoxMaskStatus::kOutsideImage;
    return result;
  }
  const BoxPixels b(box, depth, camera, options, clipped);
  const DepthBins bins = valid_depths(b, result.valid_pixels);
  if (result.valid_pixels == 0) {
    result.status = BoxMaskStatus::kNoValidDepth;
    return result;
  }

  // 2. The object's depth: the nearest good peak of the centre-weighted depth histogram.
  centre_weights(b);
  const double mode0 = object_depth(b, bins, 0);
  if (mode0 <= 0) {
    result.status = BoxMaskStatus::kNoValidDepth;
    return result;
  }

  // 3. The supporting surface: a plane the object stands on; its pixels are set aside and the
  //    object's depth is taken again without them.
  double mode = options.remove_support_plane ? supporting_surface(b, bins, mode0, result) : mode0;

  // 4-5. Region growing from seeds at the object's depth; a region that runs on beyond the box
  //      (an occluder) gives way to the next candidate depth (box_mask_grow.cpp).
  const Grown grown = grow_region(b, bins, result, mode);
  result.mode_depth_m = mode;
  result.band_half_width_m = grown.band;
  result.seed_pixels = grown.seeds;
  result.border_leak = grown.leak();

  // 6. Clean-up: a closing within the band; a region below the minimum area gives an empty mask.
  clean_up(b, result);
  return result;
}

}  // namespace objmap::segmentation

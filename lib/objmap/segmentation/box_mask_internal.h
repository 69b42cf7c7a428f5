#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "objmap/segmentation/box_mask.h"

// Private to segmentation/box_mask*.cpp: what the steps of mask_from_box share. The box's pixels
// and per-thread buffers (box_mask.cpp: steps 1-3 and 6), its depth statistics and the support
// plane's fit (box_mask_depth.cpp), the region growing (box_mask_grow.cpp: steps 4-5).
namespace objmap::segmentation::box_mask_detail {

constexpr double kPi = 3.14159265358979323846;

// Per-pixel flags of the box-local buffers.
constexpr std::uint8_t kValid = 1;     // depth within [min_depth_m, max_depth_m]
constexpr std::uint8_t kSupport = 2;   // on or beyond the support plane
constexpr std::uint8_t kInMask = 4;    // grown region
constexpr std::uint8_t kBand = 8;      // valid, not support, within the depth band
constexpr std::uint8_t kChecked = 16;  // refused once by the region growing
constexpr std::uint8_t kSeed = 32;     // seed candidate: central, at the mode depth

// Buffers reused from call to call on the same thread (no allocation per pixel, few per call).
struct Workspace {
  std::vector<float> z_m;                       // box-local depth in metres, 0 = invalid
  std::vector<std::uint8_t> flags;              // box-local flags
  std::vector<std::uint8_t> saved_flags;        // flags of the first region (see step 5)
  std::vector<std::uint8_t> scratch, scratch2;  // morphology
  // Region growing: box-local pixels as (x, y), so that no division recovers them from an index.
  struct Px {
    std::int32_t x, y;
  };
  std::vector<Px> queue;
  std::vector<Px> seed_queue;
  std::vector<std::pair<Px, double>> components;  // seed components: start, weight
  std::vector<float> ray_x, ray_y;                // (u − cx)/fx per column, (v − cy)/fy per row
  std::vector<float> weight_u, weight_v;          // centre weights per column / row
  std::vector<double> hist, hist_z;               // depth histogram: weight, weighted depth sum
  std::vector<Eigen::Vector3f> samples;
  std::vector<std::uint8_t> sample_inlier;
};

// This thread's buffers.
Workspace& workspace();

struct Plane {
  Eigen::Vector3f n = Eigen::Vector3f::Zero();
  float d = 0;  // n·X + d = 0, d > 0: the camera is on the positive side
  std::size_t inliers = 0;
  bool valid = false;
};

// RANSAC on the samples, then a least-squares refit on the inliers.
Plane fit_plane(const std::vector<Eigen::Vector3f>& pts, float inlier_m, int iterations,
                std::vector<std::uint8_t>& inlier);

// The centre-weighted depth histogram of the valid pixels without `exclude` flags, into ws.hist
// (weight per bin) and ws.hist_z (weighted depth sum per bin); false when no pixel counts.
bool depth_histogram(Workspace& ws, int bw, int bh, float z_lo, int bins, double bin_m,
                     std::uint8_t exclude);

// The object's depth in ws's histogram (depth_histogram): the nearest peak (3-bin sums) holding at
// least `min_share` of the largest peak (`skip` > 0: the next such peaks, farther away). Returns
// the weighted mean depth of the pixels in that peak's three bins, or 0 when there is none.
double histogram_peak(const Workspace& ws, int bins, double min_share, int skip);

// The object's depth: histogram_peak of the histogram of the valid pixels without `exclude` flags;
// 0 when there is none.
double near_mode(Workspace& ws, int bw, int bh, float z_lo, int bins, double bin_m,
                 double min_share, std::uint8_t exclude);

// Separable square dilation (grow = true) or erosion of `bits` (0/1) in place, radius r. Outside
// the box counts as the neutral element (the border is neither grown into nor eroded from). Inner
// loops run along rows so that they vectorise.
void morph(std::vector<std::uint8_t>& bits, std::vector<std::uint8_t>& tmp, int bw, int bh, int r,
           bool grow);

constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};

// The box clipped to the image: pixels [u0, u1) × [v0, v1) (u1 < u0 or v1 < v0: outside).
struct ClippedBox {
  int u0, v0, u1, v1;
};

// A window of box-local pixels [x0, x1) × [y0, y1).
struct Window {
  int x0, x1, y0, y1;
};

// What every step reads: the call's inputs, the clipped box and the thresholds derived from the
// options; the box-local buffers are in ws.
struct BoxPixels {
  BoxPixels(const Box& box_, const cv::Mat& depth_, const Camera& camera_,
            const BoxMaskOptions& options_, const ClippedBox& clipped)
      : box(box_),
        depth(depth_),
        camera(camera_),
        options(options_),
        ws(workspace()),
        width(depth_.cols),
        height(depth_.rows),
        u0(clipped.u0),
        v0(clipped.v0),
        u1(clipped.u1),
        v1(clipped.v1),
        bw(u1 - u0),
        bh(v1 - v0),
        area(static_cast<std::size_t>(bw) * bh),
        to_m(static_cast<float>(1.0 / camera_.depth_factor)),
        zmin(static_cast<float>(options_.min_depth_m)),
        zmax(static_cast<float>(options_.max_depth_m)),
        tol(static_cast<float>(options_.seed_tolerance_bins * options_.bin_m)),
        thr(static_cast<float>(options_.support_inlier_m)) {}

  // Depth in metres at image pixel (u, v); 0 when not valid.
  float depth_at(int u, int v) const {
    const float z = depth.at<std::uint16_t>(v, u) * to_m;
    return (z >= zmin && z <= zmax) ? z : 0.0f;
  }

  // The central `frac` of the box (1: the whole box), box-local.
  Window seed_window(double frac) const {
    const double cu = box.x + 0.5 * box.w - u0, cv = box.y + 0.5 * box.h - v0;
    return Window{std::max(0, static_cast<int>(std::floor(cu - 0.5 * frac * box.w))),
                  std::min(bw, static_cast<int>(std::ceil(cu + 0.5 * frac * box.w))),
                  std::max(0, static_cast<int>(std::floor(cv - 0.5 * frac * box.h))),
                  std::min(bh, static_cast<int>(std::ceil(cv + 0.5 * frac * box.h)))};
  }

  const Box& box;
  const cv::Mat& depth;
  const Camera& camera;
  const BoxMaskOptions& options;
  Workspace& ws;
  const int width, height;   // the image
  const int u0, v0, u1, v1;  // the clipped box, pixels [u0, u1) × [v0, v1)
  const int bw, bh;          // its size
  const std::size_t area;
  const float to_m, zmin, zmax;  // raw depth to metres; valid depths
  const float tol;               // seeds: within this of the object's depth, metres
  const float thr;               // support plane inlier distance, metres
};

// The valid depths' histogram bins: bins of bin_m from z_lo.
struct DepthBins {
  float z_lo = 0;
  int bins = 0;
};

// A region grown at one candidate depth.
struct Grown {
  std::size_t pixels = 0, seeds = 0, touching = 0, continuing = 0;
  double band = 0;
  // Share of the region's pixels on the box border whose surface goes on outside the box.
  double leak() const { return touching ? static_cast<double>(continuing) / touching : 0.0; }
};

// Steps 4-5: the region grown from seeds at the object's depth `mode`; a region that runs on
// beyond the box gives way to the next candidate depth (mode becomes it).
Grown grow_region(const BoxPixels& b, const DepthBins& bins, const BoxMaskResult& result,
                  double& mode);

}  // namespace objmap::segmentation::box_mask_detail

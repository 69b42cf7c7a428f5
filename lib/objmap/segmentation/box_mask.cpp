#include "objmap/segmentation/box_mask.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "objmap/core/error.h"

namespace objmap::segmentation {

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

Workspace& workspace() {
  thread_local Workspace ws;
  return ws;
}

// Deterministic generator for RANSAC (same sequence on every platform).
struct Lcg {
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  std::uint32_t next() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::uint32_t>(state >> 33);
  }
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

struct Plane {
  Eigen::Vector3f n = Eigen::Vector3f::Zero();
  float d = 0;  // n·X + d = 0, d > 0: the camera is on the positive side
  std::size_t inliers = 0;
  bool valid = false;
};

// RANSAC on the samples, then a least-squares refit on the inliers.
Plane fit_plane(const std::vector<Eigen::Vector3f>& pts, float inlier_m, int iterations,
                std::vector<std::uint8_t>& inlier) {
  Plane best;
  const std::size_t n = pts.size();
  if (n < 3) return best;
  Lcg rng;
  for (int it = 0; it < iterations; ++it) {
    const std::size_t i0 = rng.below(n), i1 = rng.below(n), i2 = rng.below(n);
    if (i0 == i1 || i0 == i2 || i1 == i2) continue;
    const Eigen::Vector3f a = pts[i1] - pts[i0], b = pts[i2] - pts[i0];
    Eigen::Vector3f normal = a.cross(b);
    const float len = normal.norm();
    if (!(len > 1e-6f * a.norm() * b.norm()) || len <= 0) continue;  // collinear
    normal /= len;
    const float d = -normal.dot(pts[i0]);
    std::size_t count = 0;
    for (const auto& p : pts) count += std::abs(normal.dot(p) + d) <= inlier_m;
    if (count > best.inliers) {
      best.n = normal;
      best.d = d;
      best.inliers = count;
      best.valid = true;
      if (count * 20 >= n * 19) break;  // 95 % inliers: nothing better to find
    }
  }
  if (!best.valid) return best;
  // Refit: the plane through the inliers' centroid, normal = least-variance direction.
  inlier.assign(n, 0);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (std::abs(best.n.dot(pts[i]) + best.d) <= inlier_m) {
      inlier[i] = 1;
      mean += pts[i].cast<double>();
      ++m;
    }
  }
  if (m >= 3) {
    mean /= static_cast<double>(m);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      if (!inlier[i]) continue;
      const Eigen::Vector3d q = pts[i].cast<double>() - mean;
      cov += q * q.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
    const Eigen::Vector3f normal = solver.eigenvectors().col(0).cast<float>();
    const float d = static_cast<float>(-normal.cast<double>().dot(mean));
    std::size_t count = 0;
    for (const auto& p : pts) count += std::abs(normal.dot(p) + d) <= inlier_m;
    if (count >= best.inliers) {
      best.n = normal;
      best.d = d;
      best.inliers = count;
    }
  }
  if (best.d < 0) {
    best.n = -best.n;
    best.d = -best.d;
  }
  return best;
}

// The centre-weighted depth histogram of the valid pixels without `exclude` flags, into ws.hist
// (weight per bin) and ws.hist_z (weighted depth sum per bin); false when no pixel counts.
bool depth_histogram(Workspace& ws, int bw, int bh, float z_lo, int bins, double bin_m,
                     std::uint8_t exclude) {
  auto& hist = ws.hist;
  auto& hist_z = ws.hist_z;
  hist.assign(static_cast<std::size_t>(bins), 0.0);
  hist_z.assign(static_cast<std::size_t>(bins), 0.0);
  const float inv_bin = static_cast<float>(1.0 / bin_m);
  bool any = false;
  // Neighbouring pixels mostly fall in one bin: that bin's sums are kept in registers until the bin
  // changes (the same additions in the same order as hist[b] += w, without a store-to-load chain).
  int open = -1;
  double open_w = 0, open_z = 0;
  for (int y = 0; y < bh; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * bw;
    const float wv = ws.weight_v[y];
    for (int x = 0; x < bw; ++x) {
      const std::uint8_t f = ws.flags[row + x];
      if (!(f & kValid) || (f & exclude)) continue;
      const float z = ws.z_m[row + x];
      const int b = std::min(bins - 1, static_cast<int>((z - z_lo) * inv_bin));
      const float w = wv * ws.weight_u[x];
      if (b != open) {
        if (open >= 0) {
          hist[open] = open_w;
          hist_z[open] = open_z;
        }
        open = b;
        open_w = hist[b];
        open_z = hist_z[b];
      }
      open_w += w;
      open_z += w * z;
      any = true;
    }
  }
  if (open >= 0) {
    hist[open] = open_w;
    hist_z[open] = open_z;
  }
  return any;
}

// The object's depth in ws's histogram (depth_histogram): the nearest peak (3-bin sums) holding at
// least `min_share` of the largest peak (`skip` > 0: the next such peaks, farther away). Returns
// the weighted mean depth of the pixels in that peak's three bins, or 0 when there is none.
double histogram_peak(const Workspace& ws, int bins, double min_share, int skip) {
  const auto& hist = ws.hist;
  const auto& hist_z = ws.hist_z;
  const auto sum3 = [&](const std::vector<double>& h, int b) {
    return h[b] + (b > 0 ? h[b - 1] : 0.0) + (b + 1 < bins ? h[b + 1] : 0.0);
  };
  double largest = 0;
  for (int b = 0; b < bins; ++b) largest = std::max(largest, sum3(hist, b));
  for (int b = 0; b < bins; ++b) {  // nearest first
    const double here = sum3(hist, b);
    const double left = b > 0 ? sum3(hist, b - 1) : -1.0;
    const double right = b + 1 < bins ? sum3(hist, b + 1) : -1.0;
    if (here >= left && here > right && here >= min_share * largest && here > 0) {
      if (skip-- > 0) continue;
      return sum3(hist_z, b) / here;  // mean depth of the peak's three bins
    }
  }
  return 0.0;
}

// The object's depth: histogram_peak of the histogram of the valid pixels without `exclude` flags;
// 0 when there is none.
double near_mode(Workspace& ws, int bw, int bh, float z_lo, int bins, double bin_m,
                 double min_share, std::uint8_t exclude) {
  if (!depth_histogram(ws, bw, bh, z_lo, bins, bin_m, exclude)) return 0.0;
  return histogram_peak(ws, bins, min_share, 0);
}

// Separable square dilation (grow = true) or erosion of `bits` (0/1) in place, radius r. Outside
// the box counts as the neutral element (the border is neither grown into nor eroded from). Inner
// loops run along rows so that they vectorise.
void morph(std::vector<std::uint8_t>& bits, std::vector<std::uint8_t>& tmp, int bw, int bh, int r,
           bool grow) {
  tmp = bits;
  for (int y = 0; y < bh; ++y) {
    const std::uint8_t* in = bits.data() + static_cast<std::size_t>(y) * bw;
    std::uint8_t* out = tmp.data() + static_cast<std::size_t>(y) * bw;
    for (int k = 1; k <= r && k < bw; ++k) {
      if (grow) {
        for (int x = k; x < bw; ++x) out[x] |= in[x - k];
        for (int x = 0; x + k < bw; ++x) out[x] |= in[x + k];
      } else {
        for (int x = k; x < bw; ++x) out[x] &= in[x - k];
        for (int x = 0; x + k < bw; ++x) out[x] &= in[x + k];
      }
    }
  }
  bits = tmp;
  for (int y = 0; y < bh; ++y) {
    std::uint8_t* out = bits.data() + static_cast<std::size_t>(y) * bw;
    for (int k = -r; k <= r; ++k) {
      const int yy = y + k;
      if (k == 0 || yy < 0 || yy >= bh) continue;
      const std::uint8_t* in = tmp.data() + static_cast<std::size_t>(yy) * bw;
      if (grow) {
        for (int x = 0; x < bw; ++x) out[x] |= in[x];
      } else {
        for (int x = 0; x < bw; ++x) out[x] &= in[x];
      }
    }
  }
}

constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};

// The box clipped to the image: pixels [u0, u1) × [v0, v1) (u1 < u0 or v1 < v0: outside).
struct ClippedBox {
  int u0, v0, u1, v1;
};

int clip(double value, int hi) {
  if (!std::isfinite(value)) return 0;
  return static_cast<int>(std::clamp(value, 0.0, static_cast<double>(hi)));
}

ClippedBox clip_box(const Box& box, int width, int height) {
  return {clip(std::floor(box.x), width), clip(std::floor(box.y), height),
          clip(std::ceil(box.x + box.w), width), clip(std::ceil(box.y + box.h), height)};
}

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

// A region grown at one candidate depth.
struct Grown {
  std::size_t pixels = 0, seeds = 0, touching = 0, continuing = 0;
  double band = 0;
  // Share of the region's pixels on the box border whose surface goes on outside the box.
  double leak() const { return touching ? static_cast<double>(continuing) / touching : 0.0; }
};

// Step 4: region growing from seeds at a candidate depth (grow), over the flags kValid and
// kSupport of steps 1 and 3, which it does not change; the region is the pixels flagged kInMask.
class RegionGrower {
 public:
  RegionGrower(const BoxPixels& b, const BoxMaskResult& result)
      : b_(b),
        ws_(b.ws),
        slope_per_m_(static_cast<float>(std::tan(b.options.smooth_max_slope_deg * kPi / 180) * 2 /
                                        (b.camera.fx + b.camera.fy))),
        noise_per_m2_(static_cast<float>(b.options.smooth_noise_m_per_m2)),
        have_plane_(result.support_plane_removed),
        reclaim_(have_plane_ && b.options.support_reclaim_angle_deg < 90.0),
        plane_n_(result.support_plane_in_cam.head<3>().cast<float>()),
        plane_d_(static_cast<float>(result.support_plane_in_cam[3])),
        max_cos_(static_cast<float>(std::cos(b.options.support_reclaim_angle_deg * kPi / 180))) {
    // The queues of the floods and of the region growing: room for every box pixel (a pixel joins
    // each at most once), written through raw pointers.
    if (ws_.queue.size() < b.area) {
      ws_.queue.resize(b.area);
      ws_.seed_queue.resize(b.area);
    }
    queue_ = ws_.queue.data();
    seed_queue_ = ws_.seed_queue.data();
  }

  // The region at depth mode_m: the band around it, the seeds, the growing, the border leak.
  Grown grow(double mode_m) {
    Grown g;
    g.band = mark_band(mode_m);
    g.seeds = seed(mode_m);
    g.pixels = grow_from_seeds(g.seeds);
    measure_border_leak(g);
    return g;
  }

 private:
  using Px = Workspace::Px;

  // The depth change per pixel of a steep surface at depth z, plus sensor noise.
  float step_at(float z) const { return z * (slope_per_m_ + noise_per_m2_ * z); }

  // Flags kBand the valid non-support pixels within the depth band around mode_m (sized from the
  // box's metric size at that depth), clearing the previous candidate's flags; returns the band's
  // far half-width.
  double mark_band(double mode_m) {
    const BoxMaskOptions& options = b_.options;
    constexpr std::uint8_t kPerMode = kBand | kInMask | kChecked | kSeed;
    const double metric_size =
        std::max(b_.box.w * mode_m / b_.camera.fx, b_.box.h * mode_m / b_.camera.fy);
    const double band = std::clamp(options.band_size_factor * metric_size, options.band_min_m,
                                   std::max(options.band_min_m, options.band_max_m));
    band_lo_ = static_cast<float>(mode_m - band * options.band_near_fraction);
    band_hi_ = static_cast<float>(mode_m + band);
    for (std::size_t i = 0; i < b_.area; ++i) {
      std::uint8_t f = ws_.flags[i] & static_cast<std::uint8_t>(~kPerMode);
      if ((f & kValid) && !(f & kSupport) && ws_.z_m[i] >= band_lo_ && ws_.z_m[i] <= band_hi_) {
        f |= kBand;
      }
      ws_.flags[i] = f;
    }
    return band;
  }

  // Seeds: central pixels at the mode depth (the whole box when the centre has none), and of those
  // only the smooth-connected components with a good share of the heaviest one's centre weight: an
  // occluder's surface that crosses the mode depth elsewhere in the centre is not seeded. The seeds
  // go to seed_queue_ (flagged kInMask); returns how many.
  std::size_t seed(double mode_m) {
    std::size_t candidates = 0;
    for (int pass = 0; pass < 2 && candidates == 0; ++pass) {
      win_ = b_.seed_window(pass == 0 ? b_.options.seed_center_fraction : 1.0);
      for (int y = win_.y0; y < win_.y1; ++y) {
        for (int x = win_.x0; x < win_.x1; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * b_.bw + x;
          if ((ws_.flags[i] & kBand) &&
              std::abs(ws_.z_m[i] - static_cast<float>(mode_m)) <= b_.tol) {
            ws_.flags[i] |= kSeed;
            ++candidates;
          }
        }
      }
    }
    // Components of the candidates and their centre weights (kInMask marks "visited" meanwhile).
    auto& starts = ws_.components;
    starts.clear();
    double best_weight = 0;
    for (int y = win_.y0; y < win_.y1; ++y) {
      for (int x = win_.x0; x < win_.x1; ++x) {
        const std::uint8_t f = ws_.flags[static_cast<std::size_t>(y) * b_.bw + x];
        if (!(f & kSeed) || (f & kInMask)) continue;
        const double weight = flood_seeds({x, y});
        starts.emplace_back(Px{x, y}, weight);
        best_weight = std::max(best_weight, weight);
      }
    }
    for (int y = win_.y0; y < win_.y1; ++y) {
      for (int x = win_.x0; x < win_.x1; ++x) {
        ws_.flags[static_cast<std::size_t>(y) * b_.bw + x] &= static_cast<std::uint8_t>(~kInMask);
      }
    }
    // The seeds: the components holding at least seed_component_min_share of the best one's
    // weight (an object cut in two by a thin occluder keeps both halves; specks do not count).
    std::size_t seeds = 0;
    for (const auto& [start, weight] : starts) {
      if (weight < b_.options.seed_component_min_share * best_weight) continue;
      flood_seeds(start);
      std::copy(queue_, queue_ + queued_, seed_queue_ + seeds);
      seeds += queued_;
    }
    return seeds;
  }

  // Floods one component of the seed candidates in the seed window from `start` into queue_;
  // returns its centre weight.
  double flood_seeds(Px start) {
    // Locals, not members, in the loop: the byte stores to the flags would reload members.
    const int bw = b_.bw, n_neigh = b_.options.connectivity;
    const Window win = win_;
    Px* const queue = queue_;
    std::size_t queued = 0;
    queue[queued++] = start;
    ws_.flags[static_cast<std::size_t>(start.y) * bw + start.x] |= kInMask;
    double weight = 0;
    for (std::size_t head = 0; head < queued; ++head) {
      const int xi = queue[head].x, yi = queue[head].y;
      const std::int32_t i = yi * bw + xi;
      weight += static_cast<double>(ws_.weight_u[xi]) * ws_.weight_v[yi];
      const float z = ws_.z_m[i];
      const float step = step_at(z);
      for (int k = 0; k < n_neigh; ++k) {
        const int xx = xi + kDx[k], yy = yi + kDy[k];
        if (xx < win.x0 || yy < win.y0 || xx >= win.x1 || yy >= win.y1) continue;
        const std::int32_t j = yy * bw + xx;
        const std::uint8_t f = ws_.flags[j];
        if (!(f & kSeed) || (f & kInMask) || std::abs(ws_.z_m[j] - z) > step) continue;
        ws_.flags[j] = f | kInMask;
        queue[queued++] = {xx, yy};
      }
    }
    queued_ = queued;
    return weight;
  }

  // Region growing across smooth depth inside the band from the `seeds` first pixels of
  // seed_queue_; returns the region's size.
  std::size_t grow_from_seeds(std::size_t seeds) {
    const int bw = b_.bw, bh = b_.bh, n_neigh = b_.options.connectivity;
    Px* const seed_queue = seed_queue_;
    for (std::size_t head = 0; head < seeds; ++head) {
      const int x = seed_queue[head].x, y = seed_queue[head].y;
      const std::int32_t i = y * bw + x;
      const float z = ws_.z_m[i];
      const float step = step_at(z);
      for (int k = 0; k < n_neigh; ++k) {
        const int xx = x + kDx[k], yy = y + kDy[k];
        if (xx < 0 || yy < 0 || xx >= bw || yy >= bh) continue;
        const std::int32_t j = yy * bw + xx;
        const std::uint8_t f = ws_.flags[j];
        if ((f & kInMask) || !(f & kValid) || std::abs(ws_.z_m[j] - z) > step) continue;
        if (!(f & kBand)) {
          // A pixel within the plane's inlier distance joins when its surface is not the plane's:
          // the object's lowest rows, not the table.
          if (!reclaim_ || (f & kChecked) || !(f & kSupport) || ws_.z_m[j] < band_lo_ ||
              ws_.z_m[j] > band_hi_ || !off_plane(xx, yy)) {
            ws_.flags[j] = f | kChecked;
            continue;
          }
        }
        ws_.flags[j] = f | kInMask;
        seed_queue[seeds++] = {xx, yy};
      }
    }
    return seeds;
  }

  Eigen::Vector3f point(int x, int y) const {
    const float z = ws_.z_m[static_cast<std::size_t>(y) * b_.bw + x];
    return Eigen::Vector3f(ws_.ray_x[b_.u0 + x] * z, ws_.ray_y[b_.v0 + y] * z, z);
  }

  // May the support pixel (x, y) be taken back? When it lies on the plane, not beyond it, and its
  // normal (3D central differences over ±2 px) is off the plane's by the reclaim angle.
  bool off_plane(int x, int y) const {
    constexpr int k = 2;
    const int bw = b_.bw;
    if (x < k || y < k || x + k >= bw || y + k >= b_.bh) return false;
    const Eigen::Vector3f p = point(x, y);
    if (plane_n_.dot(p) + plane_d_ < -b_.thr) return false;  // beyond the plane
    // A smooth neighbourhood only (no step, no kink): across a depth edge the "normal" is
    // meaningless. Second differences along both axes below half a smoothness step.
    const float z = p.z(), tol = 0.5f * step_at(z);
    const std::size_t c = static_cast<std::size_t>(y) * bw + x;
    const std::size_t l = c - k, r = c + k, u = c - k * bw, d = c + k * bw;
    if (!(ws_.flags[l] & ws_.flags[r] & ws_.flags[u] & ws_.flags[d] & kValid)) return false;
    if (std::abs(ws_.z_m[l] + ws_.z_m[r] - 2 * z) > tol) return false;
    if (std::abs(ws_.z_m[u] + ws_.z_m[d] - 2 * z) > tol) return false;
    const Eigen::Vector3f n =
        (point(x + k, y) - point(x - k, y)).cross(point(x, y + k) - point(x, y - k));
    const float len = n.norm();
    return len > 0 && std::abs(n.dot(plane_n_)) < max_cos_ * len;
  }

  // Does the surface at box pixel i continue smoothly to image pixel (u, v) outside the box?
  bool continues(std::size_t i, int u, int v) const {
    const float z_out = b_.depth_at(u, v);
    if (z_out <= 0 || std::abs(z_out - ws_.z_m[i]) > step_at(ws_.z_m[i])) return false;
    if (!have_plane_) return true;
    const Eigen::Vector3f p(ws_.ray_x[u] * z_out, ws_.ray_y[v] * z_out, z_out);
    return plane_n_.dot(p) + plane_d_ >= b_.thr;  // the table outside the box does not count
  }

  // Border leak: the region's pixels on each box side that lies inside the image, and those whose
  // surface continues just outside (an occluder or background cut by the box goes on; the object
  // of a fitting box ends at it).
  void measure_border_leak(Grown& g) const {
    const auto border = [&](int x, int y, int u, int v) {
      const std::size_t i = static_cast<std::size_t>(y) * b_.bw + x;
      if (!(ws_.flags[i] & kInMask)) return;
      ++g.touching;
      g.continuing += continues(i, u, v) ? 1 : 0;
    };
    const int u0 = b_.u0, v0 = b_.v0, u1 = b_.u1, v1 = b_.v1, bw = b_.bw, bh = b_.bh;
    for (int y = 0; y < bh; ++y) {
      if (u0 > 0) border(0, y, u0 - 1, v0 + y);
      if (u1 < b_.width) border(bw - 1, y, u1, v0 + y);
    }
    for (int x = 0; x < bw; ++x) {
      if (v0 > 0) border(x, 0, u0 + x, v0 - 1);
      if (v1 < b_.height) border(x, bh - 1, u0 + x, v1);
    }
  }

  const BoxPixels& b_;
  Workspace& ws_;
  const float slope_per_m_, noise_per_m2_;
  const bool have_plane_;
  const bool reclaim_;  // support pixels off the plane's normal may join the region
  const Eigen::Vector3f plane_n_;
  const float plane_d_;
  const float max_cos_;
  Px* queue_ = nullptr;       // the flood of one seed component
  Px* seed_queue_ = nullptr;  // the seeds, then the region
  std::size_t queued_ = 0;
  float band_lo_ = 0, band_hi_ = 0;  // the current candidate's depth band
  Window win_{};                     // the current candidate's seed window
};

// Step 5, occluders: the first region (grown at `mode`) runs on beyond the box. The nearest
// farther candidate depth whose region stays inside the box wins (mode becomes it); when every
// candidate leaks, the first region is kept.
Grown grow_behind_occluder(RegionGrower& grower, const BoxPixels& b, const DepthBins& bins,
                           std::uint8_t exclude, const Grown& first, double& mode) {
  const BoxMaskOptions& options = b.options;
  Workspace& ws = b.ws;
  // grow() depends only on the mode and on flags it does not change (kValid, kSupport): the
  // nearest candidate's region is kept as its flags rather than grown again if every one leaks.
  bool regrown = false;
  // The farther candidates: peaks of one histogram (grow() does not change what it counts).
  const bool counted =
      depth_histogram(ws, b.bw, b.bh, bins.z_lo, bins.bins, options.bin_m, exclude);
  for (int k = 1; k < options.depth_candidates && counted; ++k) {
    const double next = histogram_peak(ws, bins.bins, options.near_mode_min_share, k);
    if (next <= 0) break;
    if (!regrown) ws.saved_flags = ws.flags;
    regrown = true;
    const Grown g = grower.grow(next);
    if (g.pixels > 0 && g.leak() <= options.max_border_leak) {
      mode = next;
      return g;
    }
  }
  if (regrown) ws.flags.swap(ws.saved_flags);
  return first;
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

  // 4. Region growing from seeds at the object's depth.
  RegionGrower grower(b, result);
  Grown grown = grower.grow(mode);

  // 5. Occluders: a region that runs on beyond the box gives way to the next candidate depth.
  if (grown.leak() > options.max_border_leak) {
    const std::uint8_t exclude = result.support_plane_removed ? kSupport : 0;
    grown = grow_behind_occluder(grower, b, bins, exclude, grown, mode);
  }
  result.mode_depth_m = mode;
  result.band_half_width_m = grown.band;
  result.seed_pixels = grown.seeds;
  result.border_leak = grown.leak();

  // 6. Clean-up: a closing within the band; a region below the minimum area gives an empty mask.
  clean_up(b, result);
  return result;
}

}  // namespace objmap::segmentation

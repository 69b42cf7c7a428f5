#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "objmap/segmentation/box_mask_internal.h"

namespace objmap::segmentation::box_mask_detail {

Workspace& workspace() {
  thread_local Workspace ws;
  return ws;
}

namespace {

// Deterministic generator for RANSAC (same sequence on every platform).
struct Lcg {
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  std::uint32_t next() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::uint32_t>(state >> 33);
  }
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

}  // namespace

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

}  // namespace objmap::segmentation::box_mask_detail

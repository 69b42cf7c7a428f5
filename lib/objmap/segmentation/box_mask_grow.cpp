#include <algorithm>
#include <cmath>

#include "objmap/segmentation/box_mask_internal.h"

namespace objmap::segmentation::box_mask_detail {

namespace {

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

}  // namespace

Grown grow_region(const BoxPixels& b, const DepthBins& bins, const BoxMaskResult& result,
                  double& mode) {
  // 4. Region growing from seeds at the object's depth.
  RegionGrower grower(b, result);
  Grown grown = grower.grow(mode);

  // 5. Occluders: a region that runs on beyond the box gives way to the next candidate depth.
  if (grown.leak() > b.options.max_border_leak) {
    const std::uint8_t exclude = result.support_plane_removed ? kSupport : 0;
    grown = grow_behind_occluder(grower, b, bins, exclude, grown, mode);
  }
  return grown;
}

}  // namespace objmap::segmentation::box_mask_detail

#include "objmap/fusion/dense_prune.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "objmap/core/error.h"

namespace objmap::fusion {

void DensePruneOptions::check() const {
  require(every_keyframes >= 0, "DensePruneOptions.every_keyframes",
          "must be >= 0 (0 = no pruning), got " + std::to_string(every_keyframes));
  require(min_views >= 1, "DensePruneOptions.min_views",
          "must be >= 1, got " + std::to_string(min_views));
  require(max_views >= min_views && max_views <= 64, "DensePruneOptions.max_views",
          "must be in [min_views, 64], got " + std::to_string(max_views));
  require(std::isfinite(truncation_m) && truncation_m > 0, "DensePruneOptions.truncation_m",
          "must be > 0 m, got " + std::to_string(truncation_m));
  require(std::isfinite(tolerance_voxels) && tolerance_voxels >= 0,
          "DensePruneOptions.tolerance_voxels",
          "must be >= 0, got " + std::to_string(tolerance_voxels));
  require(rejudge >= 0 && rejudge <= 16, "DensePruneOptions.rejudge",
          "must be in [0, 16], got " + std::to_string(rejudge));
  require(std::isfinite(peak_ratio) && peak_ratio >= 0 && peak_ratio <= 1,
          "DensePruneOptions.peak_ratio", "must be in [0, 1], got " + std::to_string(peak_ratio));
  require(std::isfinite(peak_sigmas) && peak_sigmas > 0 && peak_sigmas <= 10,
          "DensePruneOptions.peak_sigmas",
          "must be in (0, 10], got " + std::to_string(peak_sigmas));
  require(std::isfinite(sigma_base_m) && sigma_base_m >= 0 && std::isfinite(sigma_quadratic) &&
              sigma_quadratic >= 0 && std::isfinite(sigma_ref_z_m),
          "DensePruneOptions.sigma", "the depth noise model must be finite and >= 0");
}

RecentViews::RecentViews(const Camera& camera, std::size_t capacity)
    : camera_(camera), distorted_(camera.has_distortion()), capacity_(capacity) {}

void RecentViews::add(const cv::Mat& depth, const Pose& world_from_cam) {
  require(depth.type() == CV_16UC1 && depth.cols == camera_.width && depth.rows == camera_.height,
          "RecentViews::add", "expected a CV_16UC1 depth image of the camera's size");
  if (capacity_ == 0) return;
  if (views_.size() == capacity_) views_.pop_front();
  // Every second pixel of every second row: a quarter of the memory, and the views' samples stay in
  // the cache while a prune reads them (a voxel's depth is looked up within a pixel).
  cv::Mat half((depth.rows + 1) / kStep, (depth.cols + 1) / kStep, CV_16UC1);
  for (int v = 0; v < half.rows; ++v) {
    const std::uint16_t* in = depth.ptr<std::uint16_t>(v * kStep);
    std::uint16_t* out = half.ptr<std::uint16_t>(v);
    for (int u = 0; u < half.cols; ++u) out[u] = in[u * kStep];
  }
  const Pose cam_from_world = world_from_cam.inverse();
  views_.push_back(
      {half, cam_from_world.linear(), cam_from_world.translation(), world_from_cam.translation()});
}

void RecentViews::judge(const std::vector<Vec3>& points, double voxel_m,
                        const DensePruneOptions& options, std::vector<std::uint8_t>& noise) const {
  const std::size_t m = points.size();
  const std::size_t enough = static_cast<std::size_t>(std::clamp(options.max_views, 1, 64));
  std::vector<float> s(m * enough);   // the signed distances of point i: s[i * enough ..]
  std::vector<std::uint8_t> n(m, 0);  // how many
  const double inv_factor = 1.0 / camera_.depth_factor;
  for (auto it = views_.rbegin(); it != views_.rend(); ++it) {  // the latest view first
    const View& view = *it;
    for (std::size_t i = 0; i < m; ++i) {
      if (n[i] >= enough) continue;
      const Vec3 p = view.cam_from_world_r * points[i] + view.cam_from_world_t;
      if (p.z() <= 1e-3) continue;
      double u, v;
      if (distorted_) {
        const Eigen::Vector2d px = camera_.project(p);
        u = px.x();
        v = px.y();
      } else {
        u = camera_.fx * p.x() / p.z() + camera_.cx;
        v = camera_.fy * p.y() / p.z() + camera_.cy;
      }
      // The nearest kept sample (pixels kStep·i).
      const double ui = std::floor(u / kStep + 0.5), vi = std::floor(v / kStep + 0.5);
      if (!(ui >= 0 && vi >= 0 && ui < view.depth.cols && vi < view.depth.rows)) continue;
      const std::uint16_t raw =
          view.depth.at<std::uint16_t>(static_cast<int>(vi), static_cast<int>(ui));
      if (raw == 0) continue;  // no depth: no evidence
      const double d = raw * inv_factor - p.z();
      if (d < -options.truncation_m) continue;  // something in front of it: occluded here
      s[i * enough + n[i]++] = static_cast<float>(std::min(d, options.truncation_m));
    }
  }
  noise.assign(m, 0);
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t k = n[i];
    if (k == 0 || k < static_cast<std::size_t>(options.min_views)) continue;  // no verdict
    // The median of the truncated signed distances.
    float* a = s.data() + i * enough;
    std::nth_element(a, a + k / 2, a + k);
    double median = a[k / 2];
    if (k % 2 == 0) median = 0.5 * (median + *std::max_element(a, a + k / 2));
    noise[i] = std::abs(median) > options.tolerance_voxels * voxel_m;
  }
}

// The peak rule's search for one voxel: the ray through its mean point, the samples along it.
struct RecentViews::PeakRay {
  Vec3 point, dir;
  double step = 0.0;   // between samples: half a voxel
  int samples = 0;     // on each side
  double above = 0.0;  // the voxel is noise when one of the ray's voxels holds more points
  VoxelKey own = geometry::kNoVoxel;
  VoxelKey sample(const VoxelMap& map, int j) const {  // j = 0, 1, 2, ...: +1, −1, +2, −2 steps
    const double t = (j / 2 + 1) * step * (j % 2 ? -1.0 : 1.0);
    return map.key_of((point + t * dir).cast<float>());
  }
};

RecentViews::PeakRay RecentViews::peak_ray(const Vec3& point, std::uint32_t count, double voxel_m,
                                           const DensePruneOptions& options) const {
  // The ray: from the latest view that has the point in its image, else the latest view.
  const View* ray_view = &views_.back();
  double z = -1.0;
  for (auto it = views_.rbegin(); it != views_.rend(); ++it) {
    const Vec3 p = it->cam_from_world_r * point + it->cam_from_world_t;
    if (p.z() <= 1e-3) continue;
    const double u = camera_.fx * p.x() / p.z() + camera_.cx;
    const double v = camera_.fy * p.y() / p.z() + camera_.cy;
    if (u < 0 || v < 0 || u >= camera_.width || v >= camera_.height) continue;
    ray_view = &*it;
    z = p.z();
    break;
  }
  PeakRay ray;
  ray.point = point;
  const Vec3 along = point - ray_view->centre_in_world;
  const double range = along.norm();
  if (range < 1e-6) return ray;  // no direction: no samples, no verdict
  if (z < 0) z = range;
  const double dz = z - options.sigma_ref_z_m;
  const double sigma = options.sigma_base_m + options.sigma_quadratic * dz * dz;
  const double half = std::max(voxel_m, options.peak_sigmas * sigma);
  ray.dir = along / range;
  ray.step = 0.5 * voxel_m;
  ray.samples = std::min(kMaxSamples / 2, static_cast<int>(std::ceil(half / ray.step)));
  ray.above = count / options.peak_ratio;
  return ray;
}

void RecentViews::judge_peaks(const std::vector<Vec3>& points,
                              const std::vector<std::uint32_t>& counts, const VoxelMap& map,
                              const DensePruneOptions& options,
                              std::vector<std::uint8_t>& noise) const {
  noise.assign(points.size(), 0);
  if (views_.empty()) return;
  // In batches: the rays first, then each voxel's samples nearest first until one holds more
  // than counts[i] / peak_ratio points (a noise voxel's bigger neighbour is usually the next
  // one), the first samples of a later voxel prefetched meanwhile (their cache misses overlap).
  constexpr std::size_t kBatch = 256, kAhead = 6;
  std::vector<PeakRay> rays(kBatch);
  for (std::size_t b = 0; b < points.size(); b += kBatch) {
    const std::size_t e = std::min(points.size(), b + kBatch);
    for (std::size_t i = b; i < e; ++i) {
      rays[i - b] = peak_ray(points[i], counts[i], map.voxel_m(), options);
      rays[i - b].own = map.key_of(points[i].cast<float>());
    }
    const auto prefetch = [&](const PeakRay& ray) {
      for (int j = 0; j < std::min(2, 2 * ray.samples); ++j) map.prefetch(ray.sample(map, j));
    };
    for (std::size_t i = b; i < std::min(e, b + kAhead); ++i) prefetch(rays[i - b]);
    for (std::size_t i = b; i < e; ++i) {
      if (i + kAhead < e) prefetch(rays[i + kAhead - b]);
      const PeakRay& ray = rays[i - b];
      // The samples' keys: the first two now (prefetched above), the rest, prefetched together,
      // only when those two did not decide.
      VoxelKey keys[kMaxSamples], seen[kMaxSamples];
      const int total = 2 * ray.samples;
      int m = 0;
      for (int j = 0; j < total; ++j) {
        if (j < 2) {
          keys[j] = ray.sample(map, j);
        } else if (j == 2) {
          for (int k = 2; k < total; ++k) map.prefetch(keys[k] = ray.sample(map, k));
        }
        const VoxelKey key = keys[j];
        if (key == ray.own || std::find(seen, seen + m, key) != seen + m) continue;
        seen[m++] = key;
        const VoxelData* v = map.find(key);
        if (v && v->count > ray.above) {
          noise[i] = 1;
          break;
        }
      }
    }
  }
}

bool RecentViews::contradicted(const Vec3& point_in_world, double voxel_m,
                               const DensePruneOptions& options) const {
  std::vector<std::uint8_t> noise;
  judge({point_in_world}, voxel_m, options, noise);
  return noise[0] != 0;
}

}  // namespace objmap::fusion

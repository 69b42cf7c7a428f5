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
  views_.push_back({half, cam_from_world.linear(), cam_from_world.translation()});
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

bool RecentViews::contradicted(const Vec3& point_in_world, double voxel_m,
                               const DensePruneOptions& options) const {
  std::vector<std::uint8_t> noise;
  judge({point_in_world}, voxel_m, options, noise);
  return noise[0] != 0;
}

}  // namespace objmap::fusion

#include "objmap/fusion/visibility.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "objmap/core/error.h"

namespace objmap::fusion {

void VisibilityOptions::check() const {
  require(sample_points >= 1 && sample_points <= 4096, "VisibilityOptions.sample_points",
          "must be in [1, 4096], got " + std::to_string(sample_points));
  require(std::isfinite(min_visible_fraction) && min_visible_fraction > 0.0 &&
              min_visible_fraction <= 1.0,
          "VisibilityOptions.min_visible_fraction",
          "must be in (0, 1], got " + std::to_string(min_visible_fraction));
  require(std::isfinite(occlusion_tolerance_m) && occlusion_tolerance_m >= 0.0,
          "VisibilityOptions.occlusion_tolerance_m",
          "must be >= 0 m, got " + std::to_string(occlusion_tolerance_m));
  require(std::isfinite(occlusion_tolerance_per_m) && occlusion_tolerance_per_m >= 0.0,
          "VisibilityOptions.occlusion_tolerance_per_m",
          "must be >= 0, got " + std::to_string(occlusion_tolerance_per_m));
  require(std::isfinite(range_factor) && range_factor >= 1.0, "VisibilityOptions.range_factor",
          "must be >= 1, got " + std::to_string(range_factor));
}

ViewLog::ViewLog(const Camera& camera) : camera_(camera) {}

cv::Mat ViewLog::thin(const cv::Mat& depth) const {
  require(depth.type() == CV_16UC1 && depth.cols == camera_.width && depth.rows == camera_.height,
          "ViewLog::thin", "expected a CV_16UC1 depth image of the camera's size");
  cv::Mat out((depth.rows + kStep - 1) / kStep, (depth.cols + kStep - 1) / kStep, CV_16UC1);
  for (int v = 0; v < out.rows; ++v) {
    const std::uint16_t* in = depth.ptr<std::uint16_t>(v * kStep);
    std::uint16_t* row = out.ptr<std::uint16_t>(v);
    for (int u = 0; u < out.cols; ++u) row[u] = in[u * kStep];
  }
  return out;
}

void ViewLog::add(double timestamp, cv::Mat thinned, const Pose& world_from_cam) {
  require(thinned.type() == CV_16UC1 && thinned.cols == (camera_.width + kStep - 1) / kStep &&
              thinned.rows == (camera_.height + kStep - 1) / kStep,
          "ViewLog::add", "expected a depth image made by ViewLog::thin");
  const Pose cam_from_world = world_from_cam.inverse();
  views_.push_back({timestamp, std::move(thinned), cam_from_world.linear(),
                    cam_from_world.translation(), world_from_cam.translation()});
}

std::size_t ViewLog::bytes() const {
  std::size_t n = 0;
  for (const View& v : views_) n += v.depth.total() * v.depth.elemSize() + sizeof(View);
  return n;
}

bool ViewLog::visible(const View& view, const Vec3& point, const VisibilityOptions& o) const {
  const Vec3 p = view.cam_from_world_r * point + view.cam_from_world_t;
  if (p.z() <= 0.05) return false;
  const Eigen::Vector2d px = camera_.project(p);
  const double u = px.x(), v = px.y();
  if (!(u >= 0.0 && v >= 0.0 && u < camera_.width && v < camera_.height)) return false;
  // The nearest kept sample (pixels kStep·i).
  const int ui = std::min(view.depth.cols - 1, static_cast<int>(std::lround(u / kStep)));
  const int vi = std::min(view.depth.rows - 1, static_cast<int>(std::lround(v / kStep)));
  const std::uint16_t raw = view.depth.at<std::uint16_t>(vi, ui);
  if (raw == 0) return false;  // no depth: says nothing
  const double measured = raw / camera_.depth_factor;
  const double tolerance = o.occlusion_tolerance_m + o.occlusion_tolerance_per_m * p.z();
  return measured >= p.z() - tolerance;
}

std::vector<double> ViewLog::frames_in_view(const std::vector<Vec3>& sample, const Vec3& centroid,
                                            double max_distance_m,
                                            const VisibilityOptions& options) const {
  std::vector<double> frames;
  if (sample.empty()) return frames;
  const double need =
      std::max(1.0, std::ceil(options.min_visible_fraction * static_cast<double>(sample.size())));
  for (const View& view : views_) {
    if (max_distance_m > 0.0 && (view.centre_in_world - centroid).norm() > max_distance_m) continue;
    std::size_t seen = 0, left = sample.size();
    for (const Vec3& p : sample) {
      seen += visible(view, p, options);
      --left;
      if (seen >= need || seen + left < need) break;
    }
    if (seen >= need) frames.push_back(view.timestamp);
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

}  // namespace objmap::fusion

#include "objmap/track/position_3d.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/io/dataset.h"
#include "objmap/io/image.h"
#include "objmap/io/trajectory.h"

namespace objmap::track {

namespace fs = std::filesystem;

void Position3dOptions::check() const {
  require(std::isfinite(min_depth_m) && min_depth_m >= 0, "Position3dOptions.min_depth_m",
          "must be >= 0 metres, got " + std::to_string(min_depth_m));
  require(std::isfinite(max_depth_m) && max_depth_m > min_depth_m, "Position3dOptions.max_depth_m",
          "must be > min_depth_m, got " + std::to_string(max_depth_m));
  require(min_pixels >= 1, "Position3dOptions.min_pixels",
          "must be >= 1, got " + std::to_string(min_pixels));
  require(std::isfinite(pose_max_diff_s) && pose_max_diff_s >= 0,
          "Position3dOptions.pose_max_diff_s",
          "must be >= 0 seconds, got " + std::to_string(pose_max_diff_s));
  box_mask.check();
}

namespace {

// The median of `values` (the upper one of an even count; deterministic), reordering them.
float median_of(std::vector<float>& values) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

InstancePosition instance_position(const segmentation::Instance& instance, const cv::Mat& depth,
                                   const Camera& camera, const geometry::RayTable& rays,
                                   const Pose& world_from_cam, const Position3dOptions& options) {
  InstancePosition out;
  segmentation::Mask box_mask;
  const segmentation::Mask* mask = instance.mask ? &*instance.mask : nullptr;
  if (!mask) {
    out.mask_from_box = true;
    auto made = segmentation::mask_from_box(instance.bbox, depth, camera, options.box_mask);
    if (made.status != segmentation::BoxMaskStatus::kOk) {
      out.status = PositionStatus::kNoMaskFromBox;
      return out;
    }
    box_mask = std::move(made.mask);
    mask = &box_mask;
  }
  geometry::BackprojectOptions bp;
  bp.min_depth_m = options.min_depth_m;
  bp.max_depth_m = options.max_depth_m;
  const geometry::DepthFrame frame(depth, world_from_cam, nullptr, mask,
                                   geometry::mask_bounds(*mask));
  if (frame.roi.empty()) {
    out.status = PositionStatus::kTooFewDepthPixels;
    return out;
  }
  const geometry::BackprojectResult points = geometry::backproject(rays, frame, bp);
  out.pixels = points.points_in_world.size();
  if (out.pixels < static_cast<std::size_t>(options.min_pixels)) {
    out.status = PositionStatus::kTooFewDepthPixels;
    return out;
  }
  Vec3 median;
  std::vector<float> axis(out.pixels);
  for (int k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < out.pixels; ++i) axis[i] = points.points_in_world.points[i][k];
    median[k] = median_of(axis);
  }
  out.point_in_world = median;
  return out;
}

FramePositionsFn depth_positions(const io::Dataset& dataset, const std::vector<double>& timestamps,
                                 const Trajectory& trajectory, const Camera& camera,
                                 const Position3dOptions& options) {
  options.check();
  camera.check();
  const io::Dataset& tum = dataset;
  io::PoseLookupOptions lookup;
  lookup.max_diff_s = options.pose_max_diff_s;
  lookup.check();

  // Per segmentation frame: its depth image and pose, when both exist.
  struct FrameInput {
    const io::FramePair* frame = nullptr;
    std::optional<Pose> world_from_cam;
  };
  auto inputs = std::make_shared<std::vector<FrameInput>>();
  for (const double timestamp : timestamps) {
    FrameInput in;
    const auto it =
        std::lower_bound(tum.frames.begin(), tum.frames.end(), timestamp,
                         [](const io::FramePair& p, double t) { return p.rgb_timestamp < t; });
    for (auto c = it == tum.frames.begin() ? it : it - 1; c != tum.frames.end() && c <= it; ++c)
      if (std::abs(c->rgb_timestamp - timestamp) <= 1e-4) in.frame = &*c;
    in.world_from_cam = io::lookup_pose(trajectory, timestamp, lookup);
    inputs->push_back(std::move(in));
  }
  auto rays = std::make_shared<geometry::RayTable>(geometry::make_ray_table(camera));
  return [inputs, rays, camera, options, &dataset](std::size_t index,
                                                   const segmentation::FrameSegmentation& frame) {
    FramePositions out;
    const FrameInput& in = inputs->at(index);
    if (!in.frame || !in.world_from_cam) return out;
    out.has_pose = true;
    const auto& instances = frame.instances;
    if (instances.empty()) return out;
    const cv::Mat depth = io::read_frame_depth(dataset, *in.frame, camera);
    for (const auto& instance : instances)
      out.instances.push_back(
          instance_position(instance, depth, camera, *rays, *in.world_from_cam, options));
    return out;
  };
}

}  // namespace objmap::track

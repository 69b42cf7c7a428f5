// Depth in the colour camera: the layout's invalid value cleared, depth from another camera
// registered into the colour image.
#include <algorithm>
#include <cmath>
#include <limits>

#include "objmap/core/error.h"
#include "objmap/io/dataset.h"
#include "objmap/io/image.h"

namespace objmap::io {

namespace {

// Each depth pixel back-projected with the depth camera (distortion removed), moved into the
// colour camera, projected (distortion applied) and splatted over the square of colour pixels its
// footprint covers (the ratio of the focal lengths, at least one pixel); where several land on one
// colour pixel the nearest wins.
cv::Mat register_depth(const cv::Mat& depth, const Dataset::DepthCamera& from, const Camera& to) {
  const Camera& dc = from.camera;
  cv::Mat out(to.height, to.width, CV_16UC1, cv::Scalar(0));
  const double to_m = 1.0 / dc.depth_factor;
  const double ratio = std::max(to.fx / dc.fx, to.fy / dc.fy);
  require(ratio <= 16.0, dc.name,
          "the colour camera's focal length is " + std::to_string(ratio) +
              " times the depth camera's; expected at most 16 (are the intrinsics swapped?)");
  const int half = static_cast<int>(ratio / 2.0);
  for (int v = 0; v < depth.rows; ++v) {
    const auto* row = depth.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth.cols; ++u) {
      if (row[u] == 0) continue;
      const Vec3 point_in_color = from.color_from_depth * dc.unproject(u, v, row[u] * to_m);
      if (point_in_color.z() <= 1e-6) continue;
      const Eigen::Vector2d px = to.project(point_in_color);
      const double value = std::round(point_in_color.z() * to.depth_factor);
      if (!(value >= 1 && value <= 65535)) continue;
      const auto z = static_cast<std::uint16_t>(value);
      const int cu = static_cast<int>(std::lround(px.x())),
                cv_ = static_cast<int>(std::lround(px.y()));
      for (int y = cv_ - half; y <= cv_ + half; ++y) {
        if (y < 0 || y >= to.height) continue;
        auto* out_row = out.ptr<std::uint16_t>(y);
        for (int x = cu - half; x <= cu + half; ++x)
          if (x >= 0 && x < to.width && (out_row[x] == 0 || z < out_row[x])) out_row[x] = z;
      }
    }
  }
  return out;
}

// The frame's depth as stored: its file, or the dataset's source, of the given size.
cv::Mat stored_depth(const Dataset& dataset, const FramePair& frame, int width, int height) {
  if (!dataset.source) return read_depth(frame.depth_file, width, height);
  cv::Mat depth = dataset.source->depth(frame.source_index);
  require(depth.cols == width && depth.rows == height, frame.depth_file.string(),
          "depth image of " + std::to_string(depth.cols) + "x" + std::to_string(depth.rows) +
              "; expected " + std::to_string(width) + "x" + std::to_string(height) +
              " (the camera's size)");
  return depth;
}

}  // namespace

cv::Mat read_frame_rgb(const Dataset& dataset, const FramePair& frame, int width, int height) {
  if (!dataset.source) return read_rgb(frame.rgb_file, width, height);
  cv::Mat rgb = dataset.source->color(frame.source_index);
  require(width <= 0 || (rgb.cols == width && rgb.rows == height), frame.rgb_file.string(),
          "colour image of " + std::to_string(rgb.cols) + "x" + std::to_string(rgb.rows) +
              "; expected " + std::to_string(width) + "x" + std::to_string(height) +
              " (the camera's size)");
  return rgb;
}

cv::Mat read_frame_depth(const Dataset& dataset, const FramePair& frame,
                         const Camera& color_camera) {
  if (dataset.depth_camera) {
    const Camera& dc = dataset.depth_camera->camera;
    cv::Mat depth = stored_depth(dataset, frame, dc.width, dc.height);
    if (dataset.depth_invalid != 0) depth.setTo(0, depth == dataset.depth_invalid);
    return register_depth(depth, *dataset.depth_camera, color_camera);
  }
  cv::Mat depth = stored_depth(dataset, frame, color_camera.width, color_camera.height);
  if (dataset.depth_invalid != 0) depth.setTo(0, depth == dataset.depth_invalid);
  return depth;
}

}  // namespace objmap::io

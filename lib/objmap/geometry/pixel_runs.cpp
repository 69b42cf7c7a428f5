#include "objmap/geometry/pixel_runs.h"

#include <string>

#include "objmap/core/error.h"

namespace objmap::geometry {

std::size_t PixelRuns::bytes() const {
  return first.size() * sizeof(std::uint32_t) + end.size() * sizeof(std::uint32_t) +
         raw.size() * sizeof(std::uint16_t) + colors.size() * sizeof(Rgb);
}

PixelRuns make_pixel_runs(const std::vector<std::uint32_t>& pixel_index, const cv::Mat& depth,
                          const std::vector<Rgb>& colors, int stride) {
  require(stride >= 1, "make_pixel_runs: stride", "must be >= 1, got " + std::to_string(stride));
  require(depth.type() == CV_16UC1, "make_pixel_runs: depth",
          "expected a 16-bit single-channel (CV_16UC1) image");
  require(colors.empty() || colors.size() == pixel_index.size(), "make_pixel_runs: colors",
          std::to_string(colors.size()) + " colours for " + std::to_string(pixel_index.size()) +
              " points; expected none or one per point");
  const std::size_t pixels = depth.total();
  const auto width = static_cast<std::uint32_t>(depth.cols);
  PixelRuns runs;
  runs.stride = stride;
  runs.raw.reserve(pixel_index.size());
  runs.colors = colors;
  for (std::size_t i = 0; i < pixel_index.size(); ++i) {
    const std::uint32_t p = pixel_index[i];
    require(p < pixels, "make_pixel_runs: pixel_index",
            "index " + std::to_string(p) + " outside the " + std::to_string(pixels) +
                "-pixel depth image");
    // A run goes on while the next pixel is `stride` further along the same row.
    const bool goes_on = i > 0 && p == pixel_index[i - 1] + static_cast<std::uint32_t>(stride) &&
                         p / width == pixel_index[i - 1] / width;
    if (!goes_on) {
      if (i > 0) runs.end.push_back(static_cast<std::uint32_t>(i));
      runs.first.push_back(p);
    }
    runs.raw.push_back(depth.ptr<std::uint16_t>(static_cast<int>(p / width))[p % width]);
  }
  if (!pixel_index.empty()) runs.end.push_back(static_cast<std::uint32_t>(pixel_index.size()));
  runs.first.shrink_to_fit();
  runs.end.shrink_to_fit();
  return runs;
}

PointCloud points_from_runs(const RayTable& rays, const PixelRuns& runs,
                            const Pose& world_from_cam) {
  DepthFrame frame;
  frame.world_from_cam = world_from_cam;
  const PixelTransform T(rays, frame, BackprojectOptions{});
  const std::size_t pixels = rays.x_over_z.size();
  PointCloud cloud;
  cloud.points.resize(runs.size());
  cloud.colors = runs.colors;
  require(runs.end.size() == runs.first.size() &&
              (runs.end.empty() ? runs.raw.empty() : runs.end.back() == runs.raw.size()) &&
              (runs.colors.empty() || runs.colors.size() == runs.raw.size()),
          "points_from_runs", "runs, ends, depths and colours do not agree");
  std::size_t n = 0;
  for (std::size_t r = 0; r < runs.first.size(); ++r) {
    require(runs.end[r] > n, "points_from_runs",
            "run " + std::to_string(r) + " is empty; expected ascending ends");
    const std::size_t count = runs.end[r] - n;
    const std::size_t last = runs.first[r] + (count - 1) * static_cast<std::size_t>(runs.stride);
    require(last < pixels, "points_from_runs",
            "run " + std::to_string(r) + " ends at pixel " + std::to_string(last) +
                "; expected a pixel of the " + std::to_string(pixels) + "-pixel ray table");
    for (std::size_t k = 0, p = runs.first[r]; k < count; ++k, ++n, p += runs.stride) {
      // As backproject(): eqs 11-14 in float, then eq 15.
      const float z = static_cast<float>(runs.raw[n]) * T.inv_factor;
      const float x = rays.x_over_z[p] * z;
      const float y = rays.y_over_z[p] * z;
      cloud.points[n] = Vec3f(T.world_x(x, y, z), T.world_y(x, y, z), T.world_z(x, y, z));
    }
  }
  return cloud;
}

}  // namespace objmap::geometry

#pragma once
// What the mask clean-up tests (refine_mask, the depth gate) share: a 640 x 480 camera with depth
// factor 5000, masks made of rectangles, and pixel counts.
#include <cstddef>
#include <opencv2/core.hpp>

#include "objmap/core/camera.h"
#include "objmap/segmentation/types.h"

namespace objmap::segmentation::test_masks {

inline Camera camera() {
  Camera c;
  c.width = 640;
  c.height = 480;
  c.fx = c.fy = 525.0;
  c.cx = 319.5;
  c.cy = 239.5;
  c.depth_factor = 5000.0;
  return c;
}

// Sets the pixels of `r` in `m`.
inline void add(Mask& m, const cv::Rect& r) {
  for (int v = r.y; v < r.y + r.height; ++v)
    for (int u = r.x; u < r.x + r.width; ++u) m.data[static_cast<std::size_t>(v) * 640 + u] = 1;
}

// A 640 x 480 mask of the pixels of `r`.
inline Mask mask_of(const cv::Rect& r) {
  Mask m;
  m.width = 640;
  m.height = 480;
  m.data.assign(640 * 480, 0);
  add(m, r);
  return m;
}

// A depth image of the camera's size at `z_m` everywhere, and `r` of it set to `z_m`.
inline cv::Mat flat(double z_m) {
  return cv::Mat(480, 640, CV_16UC1, cv::Scalar(static_cast<int>(z_m * 5000.0)));
}
inline void fill(cv::Mat& depth, const cv::Rect& r, double z_m) {
  depth(r).setTo(cv::Scalar(static_cast<int>(z_m * 5000.0)));
}

inline std::size_t count(const Mask& m) {
  std::size_t n = 0;
  for (auto b : m.data) n += b != 0;
  return n;
}

}  // namespace objmap::segmentation::test_masks

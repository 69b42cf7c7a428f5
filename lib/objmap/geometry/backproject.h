#pragma once
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/core/mask.h"
#include "objmap/core/types.h"

// Back-projection of a depth image into the world (paper eqs 11-15):
//   z = depth / depth_factor,  x = X(u, v) · z,  y = Y(u, v) · z,  point_in_world = world_from_cam
//   · (x, y, z)
// where (X, Y) are the undistorted normalised coordinates of pixel (u, v), computed once per camera
// in a RayTable so that the per-pixel work is two multiplications and one rigid transform.
namespace objmap::geometry {

// Per-pixel rays of a camera: x/z and y/z of pixel (u, v) at index v * width + u, distortion
// removed.
struct RayTable {
  int width = 0;
  int height = 0;
  double depth_factor = 5000.0;  // depth image value per metre, from the camera
  std::vector<float> x_over_z;
  std::vector<float> y_over_z;

  bool empty() const { return x_over_z.empty(); }
};

// Throws InputError when the camera is invalid (Camera::check). `threads` threads share the rows
// (the iterative undistortion of fr1's 640x480 pixels takes ~37 ms on one core); the table is the
// same for any count.
RayTable make_ray_table(const Camera& camera, int threads = 1);

struct BackprojectOptions {
  double min_depth_m =
      0.1;  // pixels nearer than this are dropped (the paper uses 0.01; a config value)
  double max_depth_m =
      4.0;         // pixels farther than this are dropped (Kinect depth is poor beyond ~4 m)
  int stride = 1;  // use every stride-th pixel in u and v (1 = every pixel)
  bool pixel_indices = false;  // also return v * width + u of each point
  void check() const;          // throws InputError naming the bad field
};

// What to back-project: a CV_16UC1 depth image (value = depth_m · depth_factor, 0 = no depth), its
// pose, and optionally the CV_8UC3 BGR image of the same size (colours), an instance mask (only
// pixels with mask value != 0) and a region of interest (only pixels inside; e.g. a detection box,
// or the mask's bounding box to skip the rest of the image).
struct DepthFrame {
  DepthFrame() = default;
  DepthFrame(const cv::Mat& depth_image, const Pose& world_from_cam_pose,
             const cv::Mat* bgr_image = nullptr, const Mask* instance_mask = nullptr,
             cv::Rect region = cv::Rect())
      : depth(&depth_image),
        world_from_cam(world_from_cam_pose),
        bgr(bgr_image),
        mask(instance_mask),
        roi(region) {}

  const cv::Mat* depth = nullptr;  // required, CV_16UC1, size of the ray table
  Pose world_from_cam = Pose::Identity();
  const cv::Mat* bgr = nullptr;  // optional, CV_8UC3, same size
  const Mask* mask = nullptr;    // optional, same size
  cv::Rect roi;                  // optional; empty = the whole image
};

struct BackprojectResult {
  PointCloud points_in_world;              // in pixel order (row-major); colours when bgr was given
  std::vector<std::uint32_t> pixel_index;  // v * width + u per point, when options.pixel_indices
  Vec3 centroid_in_cam = Vec3::Zero();     // mean of the points in the camera frame (0 when none)
  std::size_t pixels_considered = 0;       // pixels looked at (inside roi and mask, after stride)
  std::size_t pixels_no_depth = 0;         // of those: depth 0
  std::size_t pixels_out_of_range = 0;     // of those: depth outside [min_depth_m, max_depth_m]
};

// Throws InputError when the images do not match the ray table (type, size) or the options are bad.
BackprojectResult backproject(const RayTable& rays, const DepthFrame& frame,
                              const BackprojectOptions& options = {});

// What backproject() checks before it starts: the images match the ray table (type, size).
// Throws InputError naming the image.
void check_depth_frame(const RayTable& rays, const DepthFrame& frame);

// The per-pixel constants of eqs 11-15 in float, as backproject() uses them: the depth range of
// `options` as raw depth-image values (a pixel is back-projected when its value is in
// [raw_min, raw_max]; raw_min >= 1: 0 means no depth, whatever min_depth_m is), 1 / depth factor,
// and world_from_cam.
struct PixelTransform {
  PixelTransform(const RayTable& rays, const DepthFrame& frame, const BackprojectOptions& options);
  std::uint32_t raw_min = 1, raw_max = 65535;
  float inv_factor = 0;
  float r[9] = {};  // rotation, row-major
  float t[3] = {};
  // Eq 15: R · (x, y, z) + t, in float (the same operations wherever a point is made).
  float world_x(float x, float y, float z) const { return r[0] * x + r[1] * y + r[2] * z + t[0]; }
  float world_y(float x, float y, float z) const { return r[3] * x + r[4] * y + r[5] * z + t[1]; }
  float world_z(float x, float y, float z) const { return r[6] * x + r[7] * y + r[8] * z + t[2]; }
};

// Row v of a frame's images and of the ray table, as the back-projection loops read them.
struct FrameRow {
  FrameRow(const RayTable& rays, const DepthFrame& frame, int v);
  const std::uint16_t* depth;  // raw depth values
  const cv::Vec3b* bgr;        // nullptr without a colour image
  const std::uint8_t* mask;    // nullptr without a mask
  const float* x_over_z;       // the rays
  const float* y_over_z;
};

// The bounding rectangle of a mask's non-zero pixels (empty rect for an empty mask).
cv::Rect mask_bounds(const Mask& mask);

}  // namespace objmap::geometry

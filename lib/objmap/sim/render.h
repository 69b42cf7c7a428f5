#pragma once
#include <opencv2/core.hpp>

#include "objmap/core/camera.h"
#include "objmap/sim/scene.h"

// Ray casting of the analytic scene: one ray per pixel centre, through Camera::unproject (so that
// back-projecting a rendered depth with the same camera lands exactly on the surface).
namespace objmap::sim {

struct RenderedFrame {
  cv::Mat rgb;      // CV_8UC3, BGR (OpenCV order, ready for cv::imwrite)
  cv::Mat depth_m;  // CV_32FC1, exact depth along the optical axis (z), 0 where nothing was hit
  cv::Mat labels;   // CV_16UC1, id of the ground-truth object seen at the pixel, 0 for structure
};

// Renders the scene from `world_from_cam`. Rows are split over `threads` threads (0 = all cores);
// the result does not depend on the thread count. The camera must have no distortion.
RenderedFrame render_frame(const Scene& scene, const Camera& camera, const Pose& world_from_cam,
                           int threads = 1);

}  // namespace objmap::sim

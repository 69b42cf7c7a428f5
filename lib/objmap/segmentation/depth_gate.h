#pragma once
#include <cstddef>
#include <opencv2/core.hpp>

#include "objmap/core/camera.h"
#include "objmap/segmentation/types.h"

// Per-observation depth gate along the ray: the paper's outlier idea (eq 18) applied to one
// instance's pixels before they become points. A given mask (label image, Mask R-CNN, YOLO-seg)
// overlaps the object's silhouette by a pixel or two; where the background behind that border is
// far (a can at a table's edge, the floor a metre behind), those pixels back-project to points far
// behind the object. They are a few per cent of the pixels, but each falls in a voxel of its own
// while the object's thousands of pixels collapse into a few hundred voxels, so in the voxel cloud
// they weigh as much as the object. refine_mask() removes spill that is a part of its own; spill
// joined to the object by the ramp of mixed depth pixels that RGB-D sensors draw along occlusion
// edges stays a part of the object, and only its depth tells it apart.
//
// The rule: an object extends along the ray about as far as across it. Let z_med be the median
// depth of the mask's pixels (robust while bleed is a minority) and S the metric size of the mask's
// bounding rectangle at that depth (the geometric mean of its sides in pixels × z_med / f: a
// bottle is as deep as it is wide, not as tall). A pixel is kept when
//   |z − z_med| ≤ max(size_factor · S, min_band_m) + noise_m_per_m2 · z_med²
// and removed from the mask otherwise (an occluder in front of the object is removed as well).
namespace objmap::segmentation {

struct DepthGateOptions {
  bool enabled = true;  // false: masks are used as given (the paper)
  // Depth range of the pixels that count (those outside give no point and stay in the mask).
  double min_depth_m = 0.1;
  double max_depth_m = 4.0;
  double size_factor = 1.0;       // half-width of the band, in object sizes S
  double min_band_m = 0.05;       // the band is never narrower than this (small objects)
  double noise_m_per_m2 = 0.005;  // plus the sensor's depth noise at z_med (Kinect: ~0.005·z²)
  void check() const;             // throws InputError naming the bad field
};

struct DepthGateResult {
  Mask mask;                       // the kept pixels; empty when nothing was removed
  cv::Rect bounds;                 // bounding rectangle of `mask` (when it is not empty)
  double median_depth_m = 0.0;     // z_med (0 when no pixel has depth in range)
  double size_m = 0.0;             // S
  double band_m = 0.0;             // the band's half-width
  std::size_t pixels = 0;          // mask pixels with depth in range
  std::size_t removed_pixels = 0;  // of those, outside the band
};

// `bounds` must contain every non-zero pixel of `mask`; the depth image is CV_16UC1 of the mask's
// size, read with camera.depth_factor. When no pixel is removed, the result's mask is left empty
// (no copy). Throws InputError on a size or type mismatch or bad options.
DepthGateResult gate_mask_depth(const Mask& mask, const cv::Rect& bounds, const cv::Mat& depth,
                                const Camera& camera, const DepthGateOptions& options = {});

}  // namespace objmap::segmentation

#pragma once
#include <cstddef>
#include <opencv2/core.hpp>

#include "objmap/core/camera.h"
#include "objmap/segmentation/types.h"

// Instance masks that come with the segmentation (Mask R-CNN, label images, the synthetic
// scenes' noisy masks) spill a pixel or two over the object's outline. Where the outline is an
// occlusion edge, those pixels see the background far behind the object (or an occluder in
// front of it): back-projected, they are points in the wrong place, and since every view spills
// somewhere else along the edge they pile up into strips (the table behind a book) that neither
// the voxel support nor eq 18 removes. refine_mask() splits the mask's pixels into parts of
// smooth depth — the region growing of box masks (box_mask.h), with every mask pixel a seed —
// and removes the parts that are spill: within a few pixels of the mask's outline everywhere (a
// rim, not a limb: a chair's far legs are parts of their own too, but wider) and smaller than a
// share of the largest part.
namespace objmap::segmentation {

struct MaskRefineOptions {
  bool enabled = true;  // false: masks are used as given (the paper)
  // Depth range of the pixels that count (those outside give no point and stay in the mask).
  double min_depth_m = 0.1;
  double max_depth_m = 4.0;
  // Neighbours p, q (8-connected, both in the mask) are one part when |z_p − z_q| ≤ step(min(z_p,
  // z_q)), the step of BoxMaskOptions: tan(slope) · z / f + noise · z².
  double smooth_max_slope_deg = 80.0;
  double smooth_noise_m_per_m2 = 0.005;
  // A part is spill when every pixel of it is within rim_px of the mask's outline (none is left
  // by an erosion of the mask with a (2 rim_px + 1)² square) and it has fewer pixels than
  // min_part_share of the largest part. The synthetic scenes' masks spill up to 2 px, Mask R-CNN's
  // 1-3 px.
  int rim_px = 3;
  double min_part_share = 0.5;
  void check() const;  // throws InputError naming the bad field
};

struct MaskRefineResult {
  Mask mask;                       // the kept pixels (same size as the input mask)
  cv::Rect bounds;                 // bounding rectangle of `mask` (empty when nothing is kept)
  std::size_t parts = 0;           // smooth-depth parts of the mask's pixels with depth
  std::size_t removed_parts = 0;   // of those, the parts removed as spill
  std::size_t removed_pixels = 0;  // their pixels
};

// `bounds` must contain every non-zero pixel of `mask` (e.g. geometry::mask_bounds(mask)); the
// depth image is CV_16UC1 of the mask's size, read with camera.depth_factor. Pixels of the mask
// without depth in range are kept. Throws InputError on a size or type mismatch.
MaskRefineResult refine_mask(const Mask& mask, const cv::Rect& bounds, const cv::Mat& depth,
                             const Camera& camera, const MaskRefineOptions& options = {});

}  // namespace objmap::segmentation

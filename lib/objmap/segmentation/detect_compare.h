#pragma once
#include <cstddef>
#include <vector>

#include "objmap/segmentation/types.h"

// How close two detectors' instance masks are on the same frames (a backend or a speed option of
// `objmap detect` against the reference path): instances matched one-to-one within a class by
// mask IoU, greedily from the best pair, pairs of IoU 0 never matched.
namespace objmap::segmentation {

struct MaskAgreement {
  std::vector<double> ious;   // one per matched pair, in match order
  std::size_t reference = 0;  // instances of the reference
  std::size_t other = 0;      // instances of the other
  std::size_t unmatched_reference = 0, unmatched_other = 0;
  double min_iou() const;     // 1 when no pair
  double median_iou() const;  // 1 when no pair
  void add(const MaskAgreement& more);
};

// Mask IoU of two masks of one size (0 when either is empty or the sizes differ).
double mask_iou(const Mask& a, const Mask& b);

// The agreement of one frame's instances; instances without a mask take their box as the mask.
MaskAgreement compare_masks(const std::vector<Instance>& reference,
                            const std::vector<Instance>& other);

}  // namespace objmap::segmentation

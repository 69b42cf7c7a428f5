#pragma once
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/segmentation/box_mask.h"
#include "objmap/segmentation/depth_gate.h"
#include "objmap/segmentation/mask_refine.h"
#include "objmap/segmentation/types.h"

// The cleaned instance masks of one keyframe, the step before back-projection: each instance above
// the score gets a mask (its own, refined by depth, or made from its box and the depth), and one
// object keeps one instance of the keyframe (a second box of the same object is dropped).
namespace objmap::segmentation {

struct InstanceMaskOptions {
  double min_score = 0.0;  // instances below this detector score are skipped
  // Two instances of one class whose smaller box lies at least this much inside the other's box
  // and whose smaller mask lies at least this much inside the other's mask are one object boxed
  // twice: the lower score is dropped (1: keep all).
  double duplicate_overlap = 0.5;
  BoxMaskOptions box;        // masks of the instances that have only a box
  MaskRefineOptions refine;  // given masks: parts across a depth edge from the rest removed
  DepthGateOptions gate;     // given masks: pixels off the object's depth band removed
  void check() const;        // throws InputError naming the bad field
};

// One instance of a keyframe with its mask. The mask is the instance's own (`given`) or `owned`:
// made from the box, or the given mask after refine_mask / gate_mask_depth removed pixels from it.
struct InstanceMask {
  static constexpr std::size_t kPixelsUnknown = ~std::size_t{0};
  const Instance* instance = nullptr;  // in the keyframe's segmentation (which must outlive this)
  const Mask* given = nullptr;         // the instance's mask, used as given; nullptr: `owned`
  Mask owned;
  cv::Rect bounds;     // the bounding rectangle of the mask's pixels (not empty)
  std::string cls;     // canonical class (coco_classes.h), for the duplicate rule
  std::size_t pixels;  // of the mask; kPixelsUnknown until counted (a box mask knows its own)
  InstanceMask() : pixels(kPixelsUnknown) {}
  const Mask& mask() const { return given ? *given : owned; }
};

// What the cleaning did to a keyframe's instances.
struct InstanceMaskCounts {
  std::size_t instances = 0;    // instances seen
  std::size_t below_score = 0;  // skipped: score < min_score
  std::size_t from_box = 0;     // instances without a mask, whose mask was made from the box
  std::size_t empty = 0;        // instances left without a mask pixel (the box's or the cleaned)
  std::size_t refined = 0;      // given masks that lost pixels in refine_mask
  std::size_t depth_gated = 0;  // given masks that lost pixels in gate_mask_depth
  std::size_t duplicates = 0;   // instances dropped by the duplicate rule
  std::uint64_t refine_pixels_removed = 0;  // pixels the refined masks lost
  std::uint64_t gate_pixels_removed = 0;    // pixels the depth-gated masks lost
};

// Each instance's mask and its bounds, in the segmentation's order: instances below the score
// and those whose mask has no pixel are left out (counted). `depth` is the keyframe's CV_16UC1
// depth image of the camera's size. Throws InputError on bad options or a mask or depth that does
// not fit the camera.
std::vector<InstanceMask> make_instance_masks(const FrameSegmentation& seg, const cv::Mat& depth,
                                              const Camera& camera,
                                              const InstanceMaskOptions& options,
                                              InstanceMaskCounts& counts);

// One instance per object: of two instances of one class whose smaller box and smaller mask lie
// at least `overlap` inside the other's (both shares), the higher score (then the one listed
// first) is kept. Removes the others from `masks` (the order of the rest is kept) and counts them.
// overlap in (0, 1]; 1 keeps all.
void drop_duplicates(std::vector<InstanceMask>& masks, double overlap, InstanceMaskCounts& counts);

// make_instance_masks, then drop_duplicates with options.duplicate_overlap: the masks of a
// keyframe's instances that become observations, in the segmentation's order.
std::vector<InstanceMask> clean_instance_masks(const FrameSegmentation& seg, const cv::Mat& depth,
                                               const Camera& camera,
                                               const InstanceMaskOptions& options,
                                               InstanceMaskCounts& counts);

}  // namespace objmap::segmentation

#pragma once
#include <cstddef>
#include <vector>

#include "objmap/core/trajectory.h"
#include "objmap/io/dataset.h"
#include "objmap/pipeline/fuse.h"
#include "objmap/pipeline/segmentation_frames.h"

// Steps 1-2 of `objmap fuse`: what a fuse reads before the keyframes.
namespace objmap::pipeline {

// What a fuse reads before the keyframes: the TUM folder, the camera, the trajectory, the
// segmentation, and the keyframes with their segmentation frames.
struct FuseInputs {
  io::Dataset dataset;
  Trajectory trajectory;
  segmentation::ReadOptions read;
  SegmentationSource seg_source;
  std::vector<std::ptrdiff_t> seg_of;  // each keyframe's segmentation frame, -1: none
  std::size_t with_seg = 0;            // keyframes with a segmentation frame
};

// Steps 1-2 of a fuse; fills the inputs' part of `result` (camera, frames, keyframes, times).
FuseInputs load_inputs(const FuseOptions& options, FuseResult& result);

// Keyframe i's instances: read now (canonical JSON, into `lazy`) or taken from the whole
// segmentation; nullptr when the keyframe has no segmentation frame.
const segmentation::FrameSegmentation* keyframe_segmentation(const FuseInputs& in, std::size_t i,
                                                             segmentation::FrameSegmentation& lazy);

}  // namespace objmap::pipeline

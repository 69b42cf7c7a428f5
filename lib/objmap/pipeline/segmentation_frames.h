#pragma once
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "objmap/pipeline/keyframes.h"
#include "objmap/segmentation/read.h"
#include "objmap/segmentation/types.h"

// Which segmentation frame each keyframe takes: the frames of a segmentation folder by timestamp,
// matched to the keyframes by their rgb timestamps, and read when a keyframe needs them.
namespace objmap::pipeline {

// Where the instances of a keyframe come from: one canonical JSON file per frame (read lazily), or
// a segmentation read whole (box files, PNG images, the paper's txt layout).
struct SegmentationSource {
  std::vector<std::pair<double, std::filesystem::path>>
      files;                         // canonical JSON: (timestamp, file), sorted
  segmentation::Segmentation whole;  // the other formats
  std::vector<double> stamps;        // frame timestamps, sorted
};

// The frames of the segmentation folder `dir` in `format` (already detected): canonical JSON
// frames carry full-image masks, so they are listed here and read by the workers one keyframe at
// a time (memory does not grow with the length of the sequence); other formats are read whole with
// `read`.
SegmentationSource list_segmentation_frames(const std::filesystem::path& dir,
                                            const std::string& format,
                                            const segmentation::ReadOptions& read);

// Each keyframe's segmentation frame (an index into `stamps`, -1: none): the one named by its rgb
// timestamp (within 1 ms). `with_seg` counts the keyframes that have one.
std::vector<std::ptrdiff_t> match_segmentation_frames(const std::vector<double>& stamps,
                                                      const std::vector<Keyframe>& keyframes,
                                                      std::size_t& with_seg);

// Segmentation frame `index`'s instances: read now (canonical JSON, into `lazy`) or taken from the
// whole segmentation; nullptr for index -1.
const segmentation::FrameSegmentation* segmentation_frame(const SegmentationSource& source,
                                                          const segmentation::ReadOptions& read,
                                                          std::ptrdiff_t index,
                                                          segmentation::FrameSegmentation& lazy);

}  // namespace objmap::pipeline

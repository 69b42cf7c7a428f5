#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "objmap/segmentation/types.h"

// Writer of the canonical segmentation format: SEG/<timestamp>.json, one file per frame,
// {"instances":[{"class":"cup","score":0.9,"track_id":7,"bbox":[x,y,w,h],
//                "mask":{"size":[h,w],"counts":"<COCO RLE>"}}]}  (track_id and mask only when set).
// Schema: schemas/segmentation.schema.json.
namespace objmap::segmentation {

// The JSON text of one frame (deterministic: same frame, same bytes).
std::string frame_json(const FrameSegmentation& frame);

// Writes one frame file atomically (temporary file + rename). Throws InputError when it cannot.
void write_frame_json(const std::filesystem::path& file, const FrameSegmentation& frame);

// Throws InputError((dir / name), ...) when two of `timestamps` get the same file name
// (frame_file_name), before anything is written.
void require_distinct_frame_names(const std::filesystem::path& dir,
                                  const std::vector<double>& timestamps);

// Writes one <timestamp>.json per frame into `dir` (created if needed). Throws InputError when two
// frames get the same file name.
void write_segmentation(const std::filesystem::path& dir, const Segmentation& segmentation);

// "%.6f.json" of the timestamp, e.g. "1305031453.359684.json".
std::string frame_file_name(double timestamp);

}  // namespace objmap::segmentation

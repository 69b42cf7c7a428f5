#pragma once
#include <vector>

#include <opencv2/core/types.hpp>

#include "objmap/segmentation/detect.h"

// What the decoders of detect.cpp (Darknet YOLO, Mask R-CNN) and yolo_seg.cpp (ONNX segmentation)
// share. Not part of the library's interface.
namespace objmap::segmentation::detail {

// A detection before non-maximum suppression.
struct Candidate {
  int class_id = 0;
  float score = 0;
  cv::Rect2d box;  // pixels of the image, clamped
  int source = 0;  // index into the network's detections (Mask R-CNN: its mask; ONNX: its row)
};

// Non-maximum suppression over all kept classes at once (options.nms_across_classes) or per
// class; the kept candidates sorted by class id, then decreasing score, then box position.
std::vector<Candidate> suppress_non_maxima(const std::vector<Candidate>& candidates,
                                           const DetectOptions& options);

}  // namespace objmap::segmentation::detail

#pragma once
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/mask.h"

// The one in-memory form of a segmentation, whatever format it was read from.
namespace objmap::segmentation {

// Box in pixels: top-left corner (x, y), width and height (COCO convention).
struct Box {
  double x = 0, y = 0, w = 0, h = 0;
};

// Binary mask (core/mask.h: geometry/ back-projects masks without depending on segmentation/).
using Mask = objmap::Mask;

struct Instance {
  std::string class_name;       // COCO name with spaces, e.g. "teddy bear", "tv"
  double score = 1.0;           // detector confidence in [0, 1]
  std::optional<int> track_id;  // tracking id, when the source has one
  Box bbox;                     // always set (computed from the mask when the source has none)
  std::optional<Mask> mask;     // per-pixel mask, when the source has one
};

struct FrameSegmentation {
  double timestamp = 0.0;  // the rgb timestamp the instances belong to
  std::string source;      // file or folder read, for messages
  std::vector<Instance> instances;
};

struct Segmentation {
  std::string format;  // "json", "png", "txt-paper", "boxes-named", "boxes-coco", "boxes-xywh"
  std::string source;  // folder read
  std::vector<FrameSegmentation> frames;  // sorted by timestamp
};

}  // namespace objmap::segmentation

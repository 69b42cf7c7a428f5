#pragma once
#include <map>
#include <string>
#include <vector>

// Class names: one spelling for every source (COCO JSON, Darknet coco.names, PASCAL VOC, the
// paper).
namespace objmap::segmentation {

// The canonical spelling of a class name: lower case, '_' -> ' ', blanks trimmed and collapsed to
// one space, then the documented aliases (docs/formats.md, "Class names") mapped to one name:
//   "tv", "tvmonitor", "tv monitor"                -> "tv monitor"
//   "motorbike" -> "motorcycle", "aeroplane" -> "airplane", "sofa" -> "couch",
//   "pottedplant" -> "potted plant", "diningtable" -> "dining table",
//   "cellphone", "mobile phone" -> "cell phone", "hair dryer", "hairdryer" -> "hair drier",
//   "teddybear" -> "teddy bear", "doughnut" -> "donut", "tennis racquet" -> "tennis racket",
//   "wineglass" -> "wine glass", "hotdog" -> "hot dog"
// Names outside COCO-80 keep their normalised spelling ("009_gelatin_box" -> "009 gelatin box").
std::string canonical_class(const std::string& name);

// The aliases above: normalised spelling (lower case, '_' -> ' ', blanks collapsed) -> canonical.
const std::map<std::string, std::string>& class_aliases();

// The 80 COCO class names in canonical spelling, index = 0-based id of Darknet's coco.names
// (0 "person", 56 "chair", 62 "tv monitor", 79 "toothbrush").
const std::vector<std::string>& coco80_names();

// The 0-based COCO-80 id of `name` (any spelling canonical_class accepts), -1 when not a COCO
// class.
int coco80_id(const std::string& name);

}  // namespace objmap::segmentation

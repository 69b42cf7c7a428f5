#include "objmap/segmentation/coco_classes.h"

#include <cctype>
#include <map>

namespace objmap::segmentation {

namespace {

// Other spellings (after lower-casing, '_' -> ' ' and blank collapsing) -> canonical name.
const std::map<std::string, std::string>& alias_table() {
  static const std::map<std::string, std::string> table = {
      {"tv", "tv monitor"},
      {"tvmonitor", "tv monitor"},
      {"tv-monitor", "tv monitor"},
      {"motorbike", "motorcycle"},
      {"aeroplane", "airplane"},
      {"sofa", "couch"},
      {"pottedplant", "potted plant"},
      {"diningtable", "dining table"},
      {"cellphone", "cell phone"},
      {"mobile phone", "cell phone"},
      {"hair dryer", "hair drier"},
      {"hairdryer", "hair drier"},
      {"hairdrier", "hair drier"},
      {"teddybear", "teddy bear"},
      {"doughnut", "donut"},
      {"tennis racquet", "tennis racket"},
      {"wineglass", "wine glass"},
      {"hotdog", "hot dog"},
  };
  return table;
}

}  // namespace

const std::map<std::string, std::string>& class_aliases() { return alias_table(); }

std::string canonical_class(const std::string& name) {
  std::string normal;
  bool pending_space = false;
  for (char c : name) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (c == '_' || std::isspace(u)) {
      pending_space = !normal.empty();
      continue;
    }
    if (pending_space) normal.push_back(' ');
    pending_space = false;
    normal.push_back(static_cast<char>(std::tolower(u)));
  }
  const auto alias = alias_table().find(normal);
  return alias == alias_table().end() ? normal : alias->second;
}

const std::vector<std::string>& coco80_names() {
  // Darknet's coco.names order (0-based ids of YOLO models), COCO 2017 spellings except "tv
  // monitor".
  static const std::vector<std::string> names = {
      "person",        "bicycle",       "car",           "motorcycle",
      "airplane",      "bus",           "train",         "truck",
      "boat",          "traffic light", "fire hydrant",  "stop sign",
      "parking meter", "bench",         "bird",          "cat",
      "dog",           "horse",         "sheep",         "cow",
      "elephant",      "bear",          "zebra",         "giraffe",
      "backpack",      "umbrella",      "handbag",       "tie",
      "suitcase",      "frisbee",       "skis",          "snowboard",
      "sports ball",   "kite",          "baseball bat",  "baseball glove",
      "skateboard",    "surfboard",     "tennis racket", "bottle",
      "wine glass",    "cup",           "fork",          "knife",
      "spoon",         "bowl",          "banana",        "apple",
      "sandwich",      "orange",        "broccoli",      "carrot",
      "hot dog",       "pizza",         "donut",         "cake",
      "chair",         "couch",         "potted plant",  "bed",
      "dining table",  "toilet",        "tv monitor",    "laptop",
      "mouse",         "remote",        "keyboard",      "cell phone",
      "microwave",     "oven",          "toaster",       "sink",
      "refrigerator",  "book",          "clock",         "vase",
      "scissors",      "teddy bear",    "hair drier",    "toothbrush",
  };
  return names;
}

int coco80_id(const std::string& name) {
  const std::string canonical = canonical_class(name);
  const auto& names = coco80_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == canonical) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace objmap::segmentation

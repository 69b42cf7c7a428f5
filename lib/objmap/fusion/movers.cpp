#include "objmap/fusion/movers.h"

#include <algorithm>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

const std::vector<std::string>& default_movers() {
  static const std::vector<std::string> kMovers = {"person", "bird",  "cat",    "dog",
                                                   "horse",  "sheep", "cow",    "elephant",
                                                   "bear",   "zebra", "giraffe"};
  return kMovers;
}

std::vector<std::string> parse_movers(const std::string& text, const std::string& where) {
  if (text == "default") return default_movers();
  if (text == "none") return {};
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    const std::string name = segmentation::canonical_class(item);
    require(!name.empty(), where,
            "'" + text + "' has an empty class name; expected default, none or classes a,b,c");
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  }
  require(!out.empty(), where, "empty; expected default, none or classes a,b,c");
  return out;
}

std::vector<ObjectRecord> take_movers(std::vector<ObjectRecord>& records,
                                      const std::vector<std::string>& movers) {
  std::vector<ObjectRecord> moving, staying;
  for (ObjectRecord& r : records) {
    const std::string c = segmentation::canonical_class(r.class_name);
    const bool mover = std::find(movers.begin(), movers.end(), c) != movers.end();
    (mover ? moving : staying).push_back(std::move(r));
  }
  records = std::move(staying);
  return moving;
}

}  // namespace objmap::fusion

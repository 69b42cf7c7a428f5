#include "objmap/change/visit.h"

#include <algorithm>
#include <array>

namespace objmap::change {

double VisitObject::radius_m() const { return std::max(0.05, half_extent.norm()); }

bool moves_by_itself(const std::string& class_name) {
  // COCO's person and its ten animals (detectors spell "teddy bear" apart: a toy stays put).
  static const std::array<const char*, 11> kMoving = {"person", "bird",  "cat",    "dog",
                                                      "horse",  "sheep", "cow",    "elephant",
                                                      "bear",   "zebra", "giraffe"};
  return std::any_of(kMoving.begin(), kMoving.end(),
                     [&](const char* c) { return class_name == c; });
}

}  // namespace objmap::change

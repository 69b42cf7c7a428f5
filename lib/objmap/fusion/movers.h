#pragma once
#include <string>
#include <vector>

#include "objmap/fusion/object_map.h"

// What moves is not the map (docs/fusion.md, "Sightings"): objects of classes that move by
// themselves (a person, the COCO animals) are not static map objects. After fusion they are listed
// apart as sightings, and left out of the dense and semantic maps, the relations and the duplicate
// check.
namespace objmap::fusion {

// person, bird, cat, dog, horse, sheep, cow, elephant, bear, zebra, giraffe.
const std::vector<std::string>& default_movers();

// "default" (default_movers), "none" (no class; `fuse --method paper`) or a comma-separated list of
// classes, each canonicalised (segmentation::canonical_class: "Person", "teddy_bear"). Throws
// InputError(where, ...) naming an empty name.
std::vector<std::string> parse_movers(const std::string& text, const std::string& where);

// Takes the records whose class (canonical) is one of `movers` out of `records` (the others keep
// their order) and returns them, in their order.
std::vector<ObjectRecord> take_movers(std::vector<ObjectRecord>& records,
                                      const std::vector<std::string>& movers);

}  // namespace objmap::fusion

#pragma once
#include <string>
#include <vector>

#include "objmap/core/types.h"

// The fixed class palette of the semantic maps (map_semantic.ply, objects-only map).
namespace objmap::fusion {

// The 80 COCO class names in the usual 0-based order (as in coco.names, spaces not underscores).
const std::vector<std::string>& coco80_names();

// The colour of a class. Eight classes of the TUM desk/office scenes have hand-picked, well
// separated colours: person, chair, tv, keyboard, mouse, cup, book, teddy bear. The other COCO-80
// classes get a colour from a golden-ratio hue walk over their COCO index. Names are matched
// case-insensitively with
// '_' read as ' ' ("teddy_bear"), and "tvmonitor"/"monitor" read as "tv". Unknown names: grey 128.
Rgb class_color(const std::string& class_name);

// The normalised name used for the lookup (lower case, '_' -> ' ', aliases resolved).
std::string normalize_class_name(const std::string& class_name);

}  // namespace objmap::fusion

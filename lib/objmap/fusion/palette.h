#pragma once
#include <string>

#include "objmap/core/types.h"

// The fixed class palette of the semantic maps (map_semantic.ply, objects-only map).
namespace objmap::fusion {

// The colour of a class, looked up by its canonical name (segmentation::canonical_class: any
// spelling of a COCO class, e.g. "tvmonitor", "tv", "teddy_bear"). Eight classes of the TUM
// desk/office scenes have hand-picked, well separated colours: person, chair, tv monitor, keyboard,
// mouse, cup, book, teddy bear. The other COCO-80 classes get a colour from a golden-ratio hue walk
// over their COCO index. Unknown names: grey 128.
Rgb class_color(const std::string& class_name);

}  // namespace objmap::fusion

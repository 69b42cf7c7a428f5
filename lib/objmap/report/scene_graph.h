#pragma once
#include <string>

#include "objmap/io/scene_json.h"

// The scene graph of a run as a picture: the support surfaces along the bottom (floor first, then
// by height), each object above what it stands on, an `on` edge from it down to its support.
namespace objmap::report {

// A self-contained SVG; an empty string when the scene has no object.
std::string scene_graph_svg(const io::SceneDescription& scene);

}  // namespace objmap::report

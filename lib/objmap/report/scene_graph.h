#pragma once
#include <optional>
#include <string>

#include "objmap/io/scene_json.h"

// The scene graph of a run as a person reads it: one card per support surface (the floor first,
// then by height), titled with its height above the floor, holding the objects that stand on it;
// an object on another object sits indented under it with a connector. The cards wrap to the
// page's width. The same tree as a nested Markdown list for report.md.
namespace objmap::report {

struct SceneGraphOptions {
  double width_px = 1180;  // the page's content width: cards and the objects in them wrap to it
  void check() const;      // throws InputError naming the bad field
};

// The height of the floor in the gravity frame: the largest surface labelled "floor" (by area,
// then the lowest); nullopt when no surface is labelled so ("no floor found").
std::optional<double> floor_height_m(const io::SceneDescription& scene);

// "0.72 m above the floor", or "no floor found" without a floor.
std::string height_text(const io::SceneSurface& surface, const std::optional<double>& floor_m);

// A self-contained SVG at most `options.width_px` wide; an empty string when the scene has no
// object. Each object is a box with data-node="object ID" (and data-edge="on object ID
// surface|object ID" when it stands on something); each surface's title data-node="surface ID".
// Surfaces with nothing on them share one card; objects on nothing (or on what the file does not
// list) one card "on no surface". Every text is escaped.
std::string scene_graph_svg(const io::SceneDescription& scene,
                            const SceneGraphOptions& options = {});

// The same tree as a nested Markdown list: "- S1 table, 0.72 m above the floor" with its objects
// ("  - 3 keyboard") and what stands on them one level deeper; '<', '>' and '&' of the run's
// names written as entities.
std::string scene_graph_markdown(const io::SceneDescription& scene);

}  // namespace objmap::report

#pragma once
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/io/scene_json.h"

// `objmap query`: "cup on table" asked of a run's objects.json (docs/scene.md, "Queries").
// Grammar: CLASS [RELATION TARGET], RELATION = on | near | above | under, TARGET = CLASS | floor |
// table | seat | surface. Class names as fuse writes them (any spelling canonical_class accepts),
// plural allowed ("cups", "tv monitors", "mice").
namespace objmap::scene {

// The scene of a run: io::read_map_scene(RUN/objects.json) (io/scene_json.h).
using MapScene = io::SceneDescription;
using MapObject = io::SceneObject;
using MapSurface = io::SceneSurface;

struct Query {
  std::string text;
  std::string subject;   // canonical class
  std::string relation;  // "", "on", "near", "above", "under"
  std::string target;    // canonical class or a surface label
  bool target_is_surface = false;
};

// The canonical class (segmentation::canonical_class) that `phrase` names among `known` (canonical
// names), plural allowed ("cups", "tv monitors", "mice"); none when it names none of them.
std::optional<std::string> class_named(const std::string& phrase,
                                       const std::set<std::string>& known);

// Parses `text` with the known class names (COCO-80 and the map's own; compared as
// segmentation::canonical_class spells them). Throws InputError("query", "...") naming the word it
// did not understand.
Query parse_query(const std::string& text, const MapScene& scene);

struct QueryMatch {
  const MapObject* object = nullptr;
  std::string why;          // "on surface 2 (table), gap 0.004 m", "near 5 (keyboard), 0.21 m"
  double distance_m = 0.0;  // the relation's figure (gap or distance)
  // The surface it stands on, following `on` through objects (a cup on a book on the table: the
  // table), whatever the relation asked; none when it stands on nothing found.
  std::optional<int> surface;
};

struct QueryResult {
  std::vector<QueryMatch> matches;  // smallest |distance_m| first
  // When nothing matches: the objects of the subject's class (with what they relate to), or, when
  // there is none, the objects that satisfy the relation whatever their class.
  std::vector<QueryMatch> candidates;
};

QueryResult run_query(const Query& query, const MapScene& scene);

}  // namespace objmap::scene

#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/types.h"

// `objmap query`: "cup on table" asked of a run's objects.json (docs/scene.md, "Queries").
// Grammar: CLASS [RELATION TARGET], RELATION = on | near | above | under, TARGET = CLASS | floor |
// table | seat | surface. Class names as fuse writes them (any spelling canonical_class accepts),
// plural allowed ("cups", "tv monitors", "mice").
namespace objmap::scene {

// The scene of a run as objects.json gives it.
struct MapSurface {
  int id = 0;
  std::string label;
  double height_m = 0.0;
  Vec3 center = Vec3::Zero();
  std::vector<Vec3> outline;
  std::optional<int> object;
};

struct MapRelation {
  std::string kind;  // "surface" or "object"
  int id = 0;
  std::string label;
  double gap_m = 0.0;
};

struct MapObject {
  int id = 0;
  std::string class_name;  // canonical
  Vec3 position = Vec3::Zero();
  std::optional<MapRelation> on;
  std::vector<std::pair<int, double>> near, above, under;  // id, distance or gap (m)
};

struct MapScene {
  Vec3 up = Vec3::UnitZ();
  Eigen::Matrix3d gravity_from_world = Eigen::Matrix3d::Identity();
  std::vector<MapObject> objects;
  std::vector<MapSurface> surfaces;
  const MapObject* object(int id) const;
  const MapSurface* surface(int id) const;
};

// Reads RUN/objects.json. Throws InputError naming the file and the field for malformed JSON or a
// run without the scene fields (written by an objmap before `up_in_world`).
MapScene read_map_scene(const std::filesystem::path& objects_json);

struct Query {
  std::string text;
  std::string subject;   // canonical class
  std::string relation;  // "", "on", "near", "above", "under"
  std::string target;    // canonical class or a surface label
  bool target_is_surface = false;
};

// Parses `text` with the known class names (COCO-80 and the map's own). Throws InputError("query",
// "...") naming the word it did not understand.
Query parse_query(const std::string& text, const MapScene& scene);

struct QueryMatch {
  const MapObject* object = nullptr;
  std::string why;             // "on surface 2 (table), gap 0.004 m", "near 5 (keyboard), 0.21 m"
  double distance_m = 0.0;     // the relation's figure (gap or distance)
  std::optional<int> surface;  // the surface it stands on, if any
};

struct QueryResult {
  std::vector<QueryMatch> matches;
  // When nothing matches: the objects of the subject's class (with what they relate to), or, when
  // there is none, the objects that satisfy the relation whatever their class.
  std::vector<QueryMatch> candidates;
};

QueryResult run_query(const Query& query, const MapScene& scene);

}  // namespace objmap::scene

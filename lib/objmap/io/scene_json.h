#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "objmap/core/types.h"

// The scene fields of RUN/objects.json (`objmap fuse`, docs/scene.md) and of objects_gt.json
// (`objmap synth`): the up direction, the horizontal support surfaces and each object's relations.
// The one reader of them: `objmap query`, the report's scene graph and `objmap eval scene`.
namespace objmap::io {

// What an object rests on: a surface (id of a surface of the same file) or an object (its id).
struct SceneRelation {
  enum class Kind { kSurface, kObject };
  Kind kind = Kind::kSurface;
  int id = 0;
  std::string label;   // the surface's label or the object's class ("" when the file gives none)
  double gap_m = 0.0;  // the object's bottom − the support's top (objects.json; else 0)
};

struct SceneSurface {
  int id = 0;
  std::string label;  // "floor", "table", "seat" or "surface"
  double height_m = 0.0;
  Vec3 center = Vec3::Zero();
  std::vector<Vec3> outline;  // corners in cyclic order (may be empty)
  double area_m2 = 0.0;       // 0 when the file gives none
  std::optional<int> object;  // the object whose top it is (a seat: its chair)
};

struct SceneObject {
  int id = 0;
  std::string class_name;        // as the file writes it ("" when objects_gt.json gives none)
  Vec3 position = Vec3::Zero();  // objects.json `position` (objects_gt.json: 0)
  std::optional<SceneRelation> on;
  // objects.json relations (objects_gt.json: empty): id and distance_m (near) or gap_m.
  std::vector<std::pair<int, double>> near, above, under;
  // relations.near_surfaces: the surfaces (id, distance_m) near it; absent from an objects.json
  // written before fuse wrote them (query then measures from the object's position).
  std::optional<std::vector<std::pair<int, double>>> near_surfaces;
};

struct SceneDescription {
  std::string source;  // the file, for messages and reports
  Vec3 up = Vec3::UnitZ();
  // Row-major in the file; takes up to +z (objects.json; objects_gt.json: the identity).
  Eigen::Matrix3d gravity_from_world = Eigen::Matrix3d::Identity();
  std::vector<SceneSurface> surfaces;
  std::vector<SceneObject> objects;  // in the file's order
  const SceneObject* object(int id) const;
  const SceneSurface* surface(int id) const;
};

// RUN/objects.json of `objmap fuse`: up_in_world, gravity_from_world, surfaces[] and per object id,
// class, position and relations {on, near, above, under}. Throws InputError naming the file and the
// missing or malformed field (a run of an objmap before the scene step has no up_in_world).
SceneDescription read_map_scene(const std::filesystem::path& objects_json);
// objects_gt.json of `objmap synth`: up_in_world, surfaces[] and per object id, class and on.
SceneDescription read_gt_scene(const std::filesystem::path& objects_gt_json);

}  // namespace objmap::io

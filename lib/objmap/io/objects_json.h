#pragma once
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "objmap/core/types.h"

// Reading the object database that `objmap fuse` writes (RUN/objects.json,
// schemas/objects.schema.json): what evaluation and reports need of each object.
namespace objmap::io {

struct MappedObject {
  int id = -1;
  std::string class_name;
  double score = 0.0;
  Vec3 centroid = Vec3::Zero();  // the paper's position: mean of the filtered points
  Vec3 position = Vec3::Zero();  // objmap's: its box centre (`position`; the centroid without one)
  Aabb aabb;
  Obb obb;
  std::size_t points = 0;  // filtered points (its PLY)
  int observations = 0;
  std::string ply;  // relative to the run folder; checked to resolve inside it (io/run_path.h)
};

// Throws InputError "<file>: <field>: ..." for malformed JSON, a missing field or a wrong type.
std::vector<MappedObject> read_objects_json(const std::filesystem::path& file);

// A thing that moves by itself, seen during the run (objects.json `sightings`, docs/fusion.md).
struct Sighting {
  int id = -1;
  std::string class_name;
  double score = 0.0;
  Vec3 position = Vec3::Zero();              // where it was (its points over all its keyframes)
  double first_seen = 0.0, last_seen = 0.0;  // timestamps, s
  int frames = 0;                            // keyframes with an observation of it
};

// objects.json `sightings`; empty when the file has none (an objmap before sightings, or fuse
// --movers none). Throws as read_objects_json.
std::vector<Sighting> read_sightings(const std::filesystem::path& file);

}  // namespace objmap::io

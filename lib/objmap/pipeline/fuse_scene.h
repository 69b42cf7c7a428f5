#pragma once
#include <nlohmann/json.hpp>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/fusion/object_map.h"
#include "objmap/scene/scene.h"

// fuse's scene step (docs/scene.md): the up direction from the keyframes' cameras and the dense
// map, the objects' boxes and positions turned to stand on it, then the support surfaces and the
// relations; and their JSON for objects.json and run.json.
namespace objmap::pipeline {

// Step 1 is scene::find_up_and_surfaces, on the dense map alone (it runs beside the objects'
// filtering). Step 2, with the objects: every record's position (percentile box, unless
// `record_options` makes it the centroid) and oriented box taken in the gravity frame (the box
// turns about up only; with up = +z the positions are those of fusion::ObjectMap::records, bit for
// bit), the surfaces that are an object's top, the relations.
void relate_to_scene(std::vector<fusion::ObjectRecord>& records, const scene::SceneOptions& options,
                     const fusion::RecordOptions& record_options, scene::SceneGraph& graph);

// objects.json: "up_in_world", "gravity_from_world", "surfaces" (top level) and each object's
// "relations" (in the order of the records).
void add_scene_json(const scene::SceneGraph& graph, nlohmann::ordered_json& objects_doc);
// run.json "scene": the evidence for the up direction, the surfaces' count and rules, the times.
nlohmann::ordered_json scene_run_json(const scene::SceneGraph& graph);

}  // namespace objmap::pipeline

#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "objmap/sim/camera_path.h"
#include "objmap/sim/scene.h"

// The built-in scenes. "tabletop": a 5 x 5 m room, one table with a monitor, keyboard, mouse, two
// cups, a bottle, three books and a teddy bear, and two chairs (12 objects). "office": a 7 x 6 m
// room, two tables and three chairs, the same classes with more instances (22 objects).
namespace objmap::sim {

// The eight COCO classes of the paper, spelled as the detector spells them.
const std::vector<std::string>& paper_classes();

// Names accepted by make_scene.
const std::vector<std::string>& scene_presets();

// Builds the scene; `seed` moves objects by a few centimetres, turns them a little and varies
// colours and textures. Throws InputError for an unknown preset.
Scene make_scene(const std::string& preset, std::uint64_t seed);

// The camera orbit that suits the preset (around the table, or both tables).
CameraPathOptions preset_camera_path(const std::string& preset);

}  // namespace objmap::sim

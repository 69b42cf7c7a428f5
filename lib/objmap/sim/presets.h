#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "objmap/sim/camera_path.h"
#include "objmap/sim/scene.h"

// The built-in scenes. "tabletop": a 5 x 5 m room, one table with a monitor, keyboard, mouse, two
// cups, a bottle, three books and a teddy bear, and two chairs (12 objects). "office": a 7 x 6 m
// room, two tables and three chairs, the same classes with more instances (22 objects). "edge": a
// 5 x 5 m room, a small 0.9 x 0.6 m table and six objects (two cups, a bottle, a mouse, a book and
// a teddy bear) standing 1-2 cm from its edges, seen from a low orbit: the floor and walls show
// right behind their silhouettes, where a bleeding mask (SegNoiseOptions::bleed_px) reaches.
namespace objmap::sim {

// The eight COCO classes of the paper, spelled as the detector spells them.
const std::vector<std::string>& paper_classes();

// Names accepted by make_scene.
const std::vector<std::string>& scene_presets();
// Throws InputError("--preset", ...) listing the presets unless `preset` is one of them.
void check_scene_preset(const std::string& preset);

// Builds the scene; `seed` moves objects by a few centimetres, turns them a little and varies
// colours and textures. Throws InputError for an unknown preset.
Scene make_scene(const std::string& preset, std::uint64_t seed);

// The camera orbit that suits the preset (around the table, or both tables).
CameraPathOptions preset_camera_path(const std::string& preset);

}  // namespace objmap::sim

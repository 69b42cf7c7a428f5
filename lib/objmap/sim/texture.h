#pragma once
#include "objmap/core/types.h"
#include "objmap/sim/scene.h"

// Procedural textures: colour of a surface point from its material, evaluated in the part's frame.
namespace objmap::sim {

// Smooth 3D value noise in [0, 1) (trilinear, smoothstep), lattice spacing 1.
double value_noise(const Vec3& p, std::uint32_t seed);
// Fractal sum of 3 octaves of value noise in [0, 1).
double fractal_noise(const Vec3& p, std::uint32_t seed);

// Albedo (r, g, b in [0, 1]) of the material at `point_in_part` (metres).
Eigen::Vector3d albedo(const Material& material, const Vec3& point_in_part);

}  // namespace objmap::sim

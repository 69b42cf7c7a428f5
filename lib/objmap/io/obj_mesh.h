#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "objmap/core/mesh.h"
#include "objmap/core/types.h"

// Wavefront OBJ meshes (the YCB models of `objmap eval surface`) and the poses that place them.
namespace objmap::io {

// The `v` and `f` lines of an OBJ file (faces as v, v/vt, v//vn or v/vt/vn, 1-based or negative;
// polygons become triangle fans); other lines are skipped. Throws InputError "<file>:<line>" for a
// bad number or a face naming a vertex the file does not have.
TriangleMesh read_obj_mesh(const std::filesystem::path& file);

// One model's place in the world.
struct ModelPose {
  std::string name;  // the model file's stem, e.g. 009_gelatin_box
  Pose world_from_object = Pose::Identity();
};

// Lines "label name tx ty tz qx qy qz qw [more]" ('#' comments), as ycbv_0000_10f's
// objects_pose.txt. Throws InputError "<file>:<line>" naming what is wrong.
std::vector<ModelPose> read_model_poses(const std::filesystem::path& file);

}  // namespace objmap::io

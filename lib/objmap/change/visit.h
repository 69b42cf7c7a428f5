#pragma once
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/core/types.h"

// One visit of a place as the change detection sees it: the objects of its map, its dense map and
// the views its camera had, all in the visit's own world frame. Plain values: pipeline/diff.cpp
// reads them from a run folder of `objmap fuse`.
namespace objmap::change {

struct VisitObject {
  int id = -1;
  std::string class_name;
  Vec3 position = Vec3::Zero();     // objects.json `position` (box centre), world
  Vec3 half_extent = Vec3::Zero();  // of its oriented box, metres
  std::vector<Vec3f> points;        // its filtered points (objects/<id>_<class>.ply), world
  std::optional<Vec3> colour;       // mean red, green, blue (0-255) of its points, when they have
                                    // colours
  // Radius of its box, at least 5 cm: the gate of "same place" grows with the object.
  double radius_m() const;
};

struct Visit {
  std::string name;                     // for messages: the run folder
  Vec3 up_in_world = Vec3::UnitZ();     // objects.json up_in_world
  Eigen::Matrix3d gravity_from_world =  // objects.json gravity_from_world: takes up to +z
      Eigen::Matrix3d::Identity();
  std::vector<VisitObject> objects;
  PointCloud dense;                  // map_dense.ply, world
  Camera camera;                     // run.json inputs.camera
  std::vector<Pose> world_from_cam;  // the keyframes' poses (views of the place)
};

// Classes whose objects move by themselves (COCO's person and animals): sightings, not map
// objects; the change detection leaves them out.
bool moves_by_itself(const std::string& class_name);

}  // namespace objmap::change

#pragma once
#include <filesystem>
#include <future>
#include <memory>
#include <optional>

#include "objmap/core/clock.h"
#include "objmap/fusion/object_map.h"
#include "objmap/fusion/visibility.h"
#include "objmap/fusion/voxel_map.h"
#include "objmap/mesh/tsdf.h"
#include "objmap/pipeline/dense_cloud.h"
#include "objmap/pipeline/fuse.h"
#include "objmap/pipeline/fuse_inputs.h"
#include "objmap/pipeline/fuse_mesh.h"
#include "objmap/scene/scene.h"
#include "objmap/segmentation/class_sizes.h"

// What the keyframes of a fuse build (step 3) and what is made of it (steps 4-5): `objmap fuse`
// builds them once from every keyframe; `objmap follow` keeps them up to date keyframe by keyframe
// and finishes a copy at each publish.
namespace objmap::pipeline {

struct FuseMaps {
  fusion::VoxelMapOptions dense_options;
  fusion::VoxelMap dense;                      // the dense map (empty with dense_map false)
  fusion::ObjectMap objects;                   // the object map as the keyframes made it
  std::optional<ObjectViews> object_views;     // the objects' meshes' views (--mesh objects|all)
  std::optional<mesh::TsdfModel> scene_model;  // the scene's model (--mesh scene|all)
  std::optional<fusion::ViewLog> view_log;     // where each keyframe looked (the detected share)
  // The dense map's cloud, made beside finish_fuse (objmap follow's DenseSnapshot; `dense` is then
  // left empty: the objects' steps start meanwhile); not valid: finish_fuse takes it from `dense`.
  std::shared_future<std::shared_ptr<const DenseCloud>> dense_cloud;
  // The up direction and the surfaces, made beside finish_fuse (objmap follow: of this dense cloud
  // or of the one of the publish before); not valid: finish_fuse finds them on the dense cloud.
  std::shared_future<std::shared_ptr<const scene::SceneGraph>> scene;
};

// The empty maps of a fuse with these options (result.camera, result.threads and
// result.keyframes.still_camera set).
FuseMaps make_fuse_maps(const FuseOptions& options, const FuseChoices& choices,
                        const FuseResult& result);

// Steps 4-5 of a fuse after the keyframes: the merge pass and the filters, the dense cloud with the
// up and the surfaces, the oversize cut, the sightings, the duplicates, the relations, the meshes,
// and the run folder's files written into `dir` (a staging folder); run.json's total time is from
// `started`. The maps are used up.
void finish_fuse(const FuseOptions& options, const FuseChoices& choices, const FuseInputs& inputs,
                 const segmentation::ClassSizes& class_sizes, FuseMaps& maps,
                 const std::filesystem::path& dir, Clock::time_point started, FuseResult& result);

}  // namespace objmap::pipeline

#pragma once
#include <optional>

#include "objmap/fusion/object_map.h"
#include "objmap/fusion/visibility.h"
#include "objmap/mesh/tsdf.h"
#include "objmap/pipeline/fuse.h"
#include "objmap/segmentation/class_sizes.h"

// Step 4 of `objmap fuse`: the object map after the keyframes: the merge pass, the splits, where
// each object was in view, the confirmed objects' filtered records, the oversize cut, the
// sightings and the meshes.
namespace objmap::pipeline {

// The object map's options: a camera that hardly moves has one viewpoint, its frames are the views.
fusion::ObjectMapOptions object_map_options(const FuseOptions& options, const FuseChoices& choices,
                                            bool still_camera);

// How each confirmed object's record is made: filters and position.
fusion::RecordOptions record_options(const FuseOptions& options, int threads);

// Step 4: the final merge pass (ID-switch repair) and the split of clusters seen apart, then where
// each object was in view and each confirmed object's filtered record.
void merge_and_filter_objects(const FuseOptions& options, fusion::ObjectMap& objects,
                              const fusion::ViewLog* view_log, FuseResult& result);

// Step 4c: with the up known, the objects wider than their class allows are cut (one mask over
// chairs packed along a table). When any is, its parts are judged in view and recorded (every
// object again only if the detected-share bar moved).
void cut_oversize_objects(const FuseOptions& options, const segmentation::ClassSizes& sizes,
                          fusion::ObjectMap& objects, const fusion::ViewLog* view_log,
                          FuseResult& result);

// Step 4a (docs/fusion.md, "Sightings"): the objects of a mover class are taken out of
// result.objects into result.sightings, so they stay out of the duplicates, the relations and the
// maps.
void take_sightings(const FuseChoices& choices, FuseResult& result);

// Step 4e: the objects' meshes (with `object_views`) and the scene's (with `scene_model`, which
// is released).
void make_meshes(const FuseOptions& options, const fusion::ObjectMap& objects,
                 const ObjectViews* object_views, std::optional<mesh::TsdfModel>& scene_model,
                 FuseResult& result);

}  // namespace objmap::pipeline

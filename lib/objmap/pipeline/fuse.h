#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/filters/outlier.h"
#include "objmap/fusion/dense_prune.h"
#include "objmap/fusion/duplicates.h"
#include "objmap/fusion/object_map.h"
#include "objmap/geometry/backproject.h"
#include "objmap/geometry/bounds.h"
#include "objmap/pipeline/config.h"
#include "objmap/pipeline/fuse_mesh.h"
#include "objmap/pipeline/keyframes.h"
#include "objmap/scene/scene.h"
#include "objmap/segmentation/box_mask.h"
#include "objmap/segmentation/depth_gate.h"
#include "objmap/segmentation/mask_refine.h"

// `objmap fuse`: the object-oriented semantic map (paper §3.2–3.3). Keyframes with their poses are
// back-projected into a dense voxel map; each instance of each keyframe becomes an observation that
// the ObjectMap associates (eq 22) with an object or starts one; a final merge pass repairs ID
// switches; each confirmed object's cloud is outlier-filtered (eq 18). Written atomically to one
// run folder: objects.json, objects/<id>_<class>.ply, map_dense.ply, map_semantic.ply,
// map_objects.ply, run.json; with --mesh, objects/<id>_<class>_mesh.ply and map_mesh.ply.
namespace objmap::pipeline {

// The option strings of FuseOptions as the values the stages take: parsed once, by check().
struct FuseChoices {
  fusion::OverlapMeasure overlap_measure = fusion::OverlapMeasure::kContainment;
  fusion::DistanceScore distance_score = fusion::DistanceScore::kLinear;
  fusion::Confirmation confirmation = fusion::Confirmation::kViews;
  std::vector<std::string> movers;  // the classes that move by themselves (fusion/movers.h)
  mesh::MeshSelection meshes;       // mesh.select
};

struct FuseOptions {
  // "objmap" (default): the options as set. "paper": the paper's rules; set_method_preset() sets
  // them (the command line does so for every option not given, docs/cli.md). run_fuse() only
  // records the method.
  std::string method = "objmap";
  // Inputs and output.
  std::filesystem::path dataset;         // recording folder in any layout (io/dataset.h)
  std::string layout = "auto";           // its layout: auto (detected), a name or a layout JSON
  std::string topics;                    // rosbag: "COLOR,DEPTH" image topics (empty: chosen)
  std::filesystem::path trajectory;      // TUM trajectory, world_from_cam; empty: the dataset's own
                                         // poses (written to OUT/dataset_trajectory.txt)
  std::filesystem::path segmentation;    // segmentation folder, any supported format
  std::filesystem::path out;             // run folder (replaced atomically when complete)
  std::string camera;                    // empty: camera.json, folder name or rgb.txt header
  std::string seg_format = "auto";       // segmentation format or auto-detect
  std::string default_class = "object";  // class of box formats without one (fr3_cabinet)

  double max_diff_s = 0.02;            // rgb/depth association window
  KeyframeOptions keyframes;           // which frames are fused
  geometry::BackprojectOptions depth;  // depth range [0.1, 4.0] m (the paper's lower bound 0.01)
  double map_voxel_m = 0.01;           // dense/semantic map voxel (1 cm)
  int dense_stride = 1;                // back-project every n-th pixel into the dense map
  bool dense_map = true;  // false: objects only, no map_dense.ply / map_semantic.ply (faster)
  fusion::DensePruneOptions dense_prune;  // the dense map's noise voxels (fusion/dense_prune.h)
  double min_instance_score = 0.0;        // instances below this detector score are ignored
  double duplicate_overlap = 0.5;  // same class, box and mask this much inside another: one kept
  segmentation::BoxMaskOptions box_mask;        // masks for instances that have only a box
  segmentation::MaskRefineOptions mask_refine;  // given masks: parts across depth edges removed
  segmentation::DepthGateOptions depth_gate;    // given masks: depths off the object's band removed
  std::string overlap_measure = "containment";  // M of eq 21: containment (default) or iou (paper)
  std::string distance_score = "linear";  // f(D) of eq 22: linear (default) or gate (paper, eq 17)
  std::string confirmation = "views";     // views (default) or id_keyframes (paper)
  double min_voxel_support = 0.1;    // an object keeps voxels seen in >= 10% of its observations
  fusion::ObjectMapOptions objects;  // association (eq 22), confirmation, merge pass
  // Class sizes (segmentation/class_sizes.h) for objects.oversize: "builtin" (the COCO table),
  // "none" (no class has a size), or a JSON file of sizes added to the built-in table.
  std::string class_sizes = "builtin";
  fusion::VisibilityOptions visibility;  // where an object was in view (the detected share)
  bool outlier_filter = true;            // eq 18 on each object's cloud
  filters::OutlierOptions outlier;       // K = 20, k = 1.0
  bool outlier_on_points = false;        // eq 18 before the voxel filter, on the points (paper)
  bool voxel_nearest_centre = false;     // the voxel filter keeps the point nearest the centre
  bool position_is_centroid = false;     // objects.json `position`: the centroid (eq 16, paper)
  // `position` and `obb` leave out the strip of the table/floor an object rests on that its masks
  // bled onto (geometry::support_strip; needs the scene step's up).
  bool position_without_support = true;
  // Classes that move by themselves: their objects are sightings, not map objects
  // (fusion/movers.h): "default" (person and the COCO animals), "none" (the paper) or a,b,c.
  std::string movers = "default";
  geometry::SupportStripOptions support_strip;  // its lowest layer 1 cm, footprint cells 2 cm
  fusion::DuplicateOptions duplicates;          // suspected duplicates in run.json: touching = 2 cm
  scene::SceneOptions scene;                    // up direction, support surfaces, relations
  MeshOptions mesh;                             // objects' and scene meshes (pipeline/fuse_mesh.h)
  int threads = 0;  // worker threads, 0 = all cores; outputs identical for any count
  // Throws InputError naming the bad field; returns the option strings parsed (FuseChoices).
  FuseChoices check() const;
};

struct StageTime {
  std::string stage;
  double seconds = 0.0;
};

struct FuseResult {
  Camera camera;
  std::string camera_reason;
  std::string layout;             // the dataset's layout as read
  std::string trajectory_source;  // the trajectory file, or the dataset's own poses (their files)
  std::vector<std::string> warnings;  // what the readers accepted but the user should know
  std::string seg_format;
  std::size_t frames = 0;  // associated rgb/depth pairs
  KeyframeSelection keyframes;
  std::size_t instances_seen = 0;  // instances on keyframes
  std::size_t instances_skipped_score = 0;
  std::size_t instances_from_box = 0;     // masks made from boxes
  std::size_t instances_refined = 0;      // given masks that lost pixels in refine_mask
  std::size_t instances_duplicate = 0;    // dropped as a second instance of an object (keyframe)
  std::uint64_t mask_pixels_removed = 0;  // pixels those masks lost
  std::size_t instances_depth_gated = 0;  // given masks that lost pixels in gate_mask_depth
  std::uint64_t depth_gate_pixels_removed = 0;  // pixels those masks lost
  std::size_t instances_empty = 0;  // no usable pixels (box mask empty, no depth, too few points)
  std::size_t observations = 0;     // added to the object map
  std::size_t objects_total = 0;    // objects before the confirmation rule
  std::size_t instances_spanning = 0;  // one mask over two objects of its class (drop_spanning)
  std::size_t instances_bleed = 0;     // another instance's surface in the frame (drop_bleed)
  std::size_t objects_below_share = 0;
  double detected_share_bar = 0.0;  // the detected share an object needed (0: the rule off)  //
                                    // with enough views, left out by the detected share
  std::vector<fusion::MergeLink> merges;
  std::vector<fusion::SplitLink> splits;      // objects split in parts (split_clusters)
  std::vector<fusion::SplitLink> oversize;    // objects cut for their class's size (oversize)
  std::vector<fusion::ClassRename> renamed;   // objects named after another class for their size
  std::vector<fusion::MergeLink> part_joins;  // objects joined as parts of one instance
  std::vector<fusion::ObjectRecord> objects;  // confirmed, ascending id
  // Confirmed objects of a mover class (FuseOptions::movers), ascending id: not in `objects`, the
  // duplicates, the relations or the maps.
  std::vector<fusion::ObjectRecord> sightings;
  std::size_t dense_voxels_of_sightings = 0;  // dense map voxels left out as a sighting's
  fusion::DuplicateReport duplicates;         // same-class pairs that overlap or touch
  std::vector<ObjectMesh> object_meshes;      // one per object of `objects` with --mesh objects|all
  mesh::ModelResult scene_mesh;               // with --mesh scene|all
  scene::SceneGraph scene;                    // up, surfaces, each object's relations
  // Table 6: points.
  std::uint64_t dense_points_raw = 0;      // back-projected points of all keyframes
  std::size_t dense_points_map = 0;        // voxels of the dense map (= points of map_dense.ply)
  std::uint64_t dense_voxels_pruned = 0;   // voxels dropped from it as noise (dense_prune)
  std::size_t object_points_raw = 0;       // points of the confirmed objects' observations
  std::size_t object_points_voxel = 0;     // after the voxel filter
  std::size_t object_points_filtered = 0;  // after the outlier filter (map_objects.ply)
  std::vector<StageTime> times;
  double seconds_total = 0.0;
  long peak_rss_kb = 0;
  int threads = 1;  // worker threads used (--threads, 0 resolved to the cores)
};

// Every tunable field of FuseOptions (not the input/output paths) with its JSON key, flag and help.
std::vector<ConfigField> fuse_config_fields(FuseOptions& options);

// Sets the options of `options.method`: nothing for "objmap"; for "paper" every rule as the paper
// states it (docs/fusion.md, "The paper's method"), each with its equation or section:
//  - association (§3.2, eqs 17, 21, 22): P = w_id·P_ID + w_d·[D < 0.1 m] + w_m·IoU with
//    w = (0.5, 0.5, 0.5), K = 0.4: the same track ID alone (0.5 > K) or a centroid within the fixed
//    0.1 m gate alone (0.5 > K) joins, the overlap alone only above the paper's 0.8 (0.5·0.8 = K);
//    IoU of the exact voxel sets at the map's resolution; each instance in turn, no final merge;
//  - confirmation: the object's track ID seen in >= 3 keyframes;
//  - filters (§3.3): eq 18 on the object's back-projected points, then the voxel filter keeping
//    the point nearest each voxel's centre; every voxel kept; centroid = mean of the points (eq
//    16);
//  - masks as given (no refinement, no depth gate, no duplicate rule), depth >= 0.01 m (eq 11).
// Throws InputError("method", ...) for an unknown method.
void set_method_preset(FuseOptions& options);

// done/total keyframes, for a progress bar.
using FuseProgress = std::function<void(std::size_t done, std::size_t total)>;

// Runs the whole fuse and writes the run folder. Throws InputError for bad input; nothing is left
// behind then.
FuseResult run_fuse(const FuseOptions& options, const FuseProgress& progress = {});

// The instance observations of the given keyframes (indices into the run's keyframes), re-made
// from the inputs exactly as run_fuse makes them (masks, back-projection, points in the world with
// the trajectory's poses), before any association, in the order of `keyframe_indices`; no map, no
// output (options.out is not used). What objmap correct aligns to earlier views. Throws InputError
// like run_fuse, and for a keyframe index the inputs do not have.
std::vector<fusion::Observation> remake_observations(const FuseOptions& options,
                                                     const std::vector<int>& keyframe_indices);

}  // namespace objmap::pipeline

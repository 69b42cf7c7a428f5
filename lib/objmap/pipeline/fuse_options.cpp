// objmap fuse's options: the config tables (flags, config keys, help), the paper's preset and
// FuseOptions::check().
#include "objmap/pipeline/fuse.h"

#include <sys/resource.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <future>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <thread>
#include "objmap/core/error.h"
#include "objmap/core/parallel.h"
#include "objmap/core/version.h"
#include "objmap/fusion/frame_voxels.h"
#include "objmap/fusion/movers.h"
#include "objmap/fusion/palette.h"
#include "objmap/fusion/voxel_map.h"
#include "objmap/io/atomic.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/image.h"
#include "objmap/io/ply.h"
#include "objmap/io/trajectory.h"
#include "objmap/io/tum_dataset.h"
#include "objmap/pipeline/fuse_scene.h"
#include "objmap/segmentation/class_sizes.h"
#include "objmap/segmentation/instance_masks.h"
#include "objmap/segmentation/read.h"

namespace objmap::pipeline {

namespace {

// Association windows, threads, keyframes, depth range and the dense map.
std::vector<ConfigField> inputs_fields(FuseOptions& o) {
  auto& k = o.keyframes;
  return {
      {"max_diff_s", "--max-diff", "rgb/depth and frame/pose association window, s", &o.max_diff_s},
      {"threads", "--threads",
       "worker threads (0 = all cores); outputs are identical for any count", &o.threads},
      {"keyframes.mode", "--keyframes",
       "auto|all|motion|stride (auto: all frames of a keyframe trajectory, else by motion; "
       "all when motion keeps fewer keyframes than --min-observations)",
       &k.mode},
      {"keyframes.min_translation_m", "--kf-translation",
       "motion keyframes: new after this "
       "translation, m",
       &k.min_translation_m},
      {"keyframes.min_rotation_deg", "--kf-rotation", "motion keyframes: ... or this rotation, deg",
       &k.min_rotation_deg},
      {"keyframes.stride", "--stride", "stride keyframes: every n-th posed frame", &k.stride},
      {"depth.min_m", "--min-depth", "nearest depth used, m (the paper: 0.01)",
       &o.depth.min_depth_m},
      {"depth.max_m", "--max-depth", "farthest depth used, m", &o.depth.max_depth_m},
      {"map.voxel_m", "--voxel", "dense and semantic map voxel, m", &o.map_voxel_m},
      {"map.dense_stride", "--dense-stride", "back-project every n-th pixel into the dense map",
       &o.dense_stride},
      {"map.dense", "--dense-map",
       "write the dense and semantic maps; false: the objects only (about 1.7x faster, 40% of "
       "the memory; objects.json is the same)",
       &o.dense_map},
      {"map.prune_every", "--dense-prune-every",
       "dense map: after every n keyframes, drop the voxels opened earlier that the recent views "
       "contradict (they measure the surface elsewhere along the ray); 0: keep every voxel (the "
       "paper)",
       &o.dense_prune.every_keyframes},
      {"map.prune_tolerance", "--dense-prune-tolerance",
       "dense map: a voxel is kept when the median of the recent views' signed distances to it "
       "is within this many voxels",
       &o.dense_prune.tolerance_voxels},
      {"map.prune_peak_ratio", "--dense-prune-peak",
       "dense map: judge by the peak rule instead, a voxel is noise when a voxel along its ray "
       "within 2 sigma(z) holds more than 1/ratio times its points; 0: the median rule",
       &o.dense_prune.peak_ratio},
      {"map.prune_rejudge", "--dense-prune-rejudge",
       "dense map: a voxel that survives is judged again 2, 4, 8, ... prunes later, this many "
       "times",
       &o.dense_prune.rejudge},
  };
}

// How the segmentation is read and which instances are kept.
std::vector<ConfigField> segmentation_fields(FuseOptions& o) {
  return {
      {"segmentation.format", "--seg-format",
       "auto|json|png|txt-paper|boxes-named|boxes-coco|boxes-xywh", &o.seg_format},
      {"segmentation.default_class", "--default-class", "class of box files without one",
       &o.default_class},
      {"segmentation.min_score", "--min-score", "instances below this detector score are ignored",
       &o.min_instance_score},
      {"segmentation.duplicate_overlap", "--duplicate-overlap",
       "two instances of one class in a keyframe whose smaller box and smaller mask lie at least "
       "this much inside the other's are one object boxed twice: the lower score is dropped (1: "
       "keep all)",
       &o.duplicate_overlap},
  };
}

// Association of observations with objects (eqs 17, 21).
std::vector<ConfigField> association_fields(FuseOptions& o) {
  auto& m = o.objects;
  return {
      {"objects.distance_score", "--distance-score",
       "D in eq 22: linear (f = 1 - D / 2G: 1/2 at the gate) or gate (the paper, eq 17: 1 within "
       "the gate, else 0)",
       &o.distance_score},
      {"objects.best_first", "--best-first",
       "a keyframe's best (instance, object) pair is fused first; false: each instance in turn "
       "(the paper)",
       &m.best_first},
      {"objects.voxel_m", "--object-voxel", "object voxel sets and overlap M (eq 21), m",
       &m.voxel_m},
      {"objects.distance_gate_m", "--distance-gate", "centroid gate D (eq 17), m",
       &m.distance_gate_m},
      {"objects.overlap_measure", "--overlap",
       "M of eq 21: containment (shared / the observation's voxels) or iou (the paper)",
       &o.overlap_measure},
      {"objects.overlap_tolerance_voxels", "--overlap-tolerance",
       "a voxel counts as shared when the object has one within this many voxels (0: exact)",
       &m.overlap_tolerance_voxels},
      {"objects.gate_radius_factor", "--gate-radius-factor",
       "the gate grows to this x the object's RMS radius for large objects (0: fixed)",
       &m.gate_radius_factor},
      {"objects.one_observation_per_frame", "--one-per-frame",
       "an object takes at most one instance of a keyframe", &m.one_observation_per_frame},
  };
}

// The merge pass and the class-confusion pass.
std::vector<ConfigField> merging_fields(FuseOptions& o) {
  auto& m = o.objects;
  return {
      {"objects.final_merge", "--final-merge",
       "after the keyframes, join objects of one class that eq 22 says are one (ID-switch "
       "repair); false: no such pass (the paper)",
       &m.final_merge},
      {"objects.merge_min_overlap", "--merge-min-overlap",
       "merge pass: containment of the smaller object in the larger at least this",
       &m.merge_min_overlap},
      {"objects.merge_class_confusions", "--merge-class-confusions",
       "after the merge pass, an object lying almost all on an object of another class with "
       "several times its views joins it (the detector's other name for it)",
       &m.merge_class_confusions},
      {"objects.merge_fragments_in_box", "--merge-fragments",
       "after them, an object inside the oriented box of a larger object of its class, with "
       "several times fewer views and few shared keyframes, joins it (its far side, its top)",
       &m.merge_fragments_in_box},
      {"objects.drop_spanning", "--drop-spanning",
       "an instance of which a quarter or more lies on each of two confirmed objects of its class "
       "is ignored (one mask over two objects side by side)",
       &m.drop_spanning},
      {"objects.split_clusters", "--split-clusters",
       "after the merges, an object whose surface forms clusters apart that its observations see "
       "one at a time is split, one object per cluster (chairs side by side joined by an ID swap)",
       &m.split_clusters},
      {"objects.split_oversize", "--split-oversize",
       "an object wider than its class allows (--class-sizes) is cut at the emptiest place along "
       "its long axis, again while a part is (one mask over chairs packed along a table)",
       &m.oversize.enabled},
      {"objects.oversize_margin", "--oversize-margin",
       "... wider than the class's largest usual size times 1 + this", &m.oversize.margin},
      {"objects.join_parts", "--join-parts",
       "with --split-oversize: two objects of one class, rarely seen together, whose union is no "
       "wider than the class allows and whose boxes are at most 10 cm apart, are one instance when "
       "the smaller lies over the larger's footprint, both are one surface where they meet "
       "(--join-continuous), or they share a track id (a chair's back seen over a table, its legs "
       "below it; a couch seen from two places)",
       &m.oversize.join_parts},
      {"objects.join_continuous", "--join-continuous",
       "with --join-parts: two parts whose surfaces run on without a gap where they meet are one "
       "instance (a large object seen from two places, frames apart, each part its nearer side)",
       &m.oversize.join_continuous},
      {"objects.join_under", "--join-under",
       "with --join-parts: an object one instance too wide for every class it was called that lies "
       "under a larger object of another class, at most --join-under-gap below it, is that "
       "object's part (a monitor's foot called mouse and cell phone)",
       &m.oversize.join_under},
      {"objects.join_under_gap", "--join-under-gap",
       "... in metres (the neck of a monitor's stand is thin and rarely seen)",
       &m.oversize.under_gap_m},
      {"objects.name_for_size", "--name-for-size",
       "with --split-oversize: an object too wide for its voted class that is one instance (no "
       "gap to cut at, nothing to trim) takes the name of another class of its votes that admits "
       "its width, voted at least --name-for-size-vote times as much (a monitor called laptop)",
       &m.oversize.rename},
      {"objects.name_for_size_vote", "--name-for-size-vote",
       "... the other class's score at least this share of the voted class's",
       &m.oversize.rename_min_vote},
      {"objects.class_sizes", "--class-sizes",
       "builtin (the COCO classes' usual sizes, docs/fusion.md), none, or a JSON file "
       "{\"sizes\": {\"chair\": [0.4, 0.7]}} of sizes in metres added to the built-in table",
       &o.class_sizes},
      {"objects.drop_bleed", "--drop-bleed",
       "an instance lying on another of its class in the same keyframe, a fifth of its size or "
       "less, is ignored (a mask that bled onto the object in front)",
       &m.drop_bleed},
      {"objects.confusion_min_containment", "--confusion-containment",
       "class confusion: share of the smaller object's voxels on the larger's",
       &m.confusion_min_containment},
      {"objects.confusion_min_view_ratio", "--confusion-view-ratio",
       "class confusion: the larger object has at least this many times the smaller's views",
       &m.confusion_min_view_ratio},
      {"objects.confusion_min_support", "--confusion-support",
       "class confusion: the larger object's voxels that count were in at least this share of "
       "its observations",
       &m.confusion_min_support},
      {"objects.merge_max_shared_frames", "--merge-max-shared-frames",
       "merge pass: never join two objects both labelled their class in more than this share of "
       "the smaller one's keyframes (stacked books)",
       &m.merge_max_shared_frames},
  };
}

// Voxel support, eq 22 and confirmation.
std::vector<ConfigField> scoring_fields(FuseOptions& o) {
  auto& m = o.objects;
  return {
      {"objects.min_voxel_support", "--min-voxel-support",
       "an object keeps the voxels seen in at least this share of its observations",
       &o.min_voxel_support},
      {"objects.weight_id", "--weight-id", "w_id of eq 22", &m.weight_id},
      {"objects.weight_distance", "--weight-distance", "w_d of eq 22", &m.weight_distance},
      {"objects.weight_overlap", "--weight-overlap", "w_m of eq 22", &m.weight_overlap},
      {"objects.match_threshold", "--match-threshold", "K of eq 22: match when P > K",
       &m.match_threshold},
      {"objects.merge_threshold", "--merge-threshold", "K of the final merge pass",
       &m.merge_threshold},
      {"objects.min_observations", "--min-observations",
       "views to confirm an object (observations from distinct viewpoints)", &m.min_observations},
      {"objects.confirmation", "--confirmation",
       "what --min-observations counts: views, or id_keyframes (the paper: the keyframes in which "
       "the object's track ID was seen)",
       &o.confirmation},
      {"objects.min_detected_share", "--min-detected-share",
       "an object is confirmed only when detected in at least this share of the keyframes that "
       "had its place in view, not occluded (0: no such rule; the paper)",
       &m.min_detected_share},
      {"objects.detected_share_of_median", "--detected-share-of-median",
       "... and at least this times the median share of the objects with enough views (the "
       "detector's recall on this recording)",
       &m.detected_share_of_median},
      {"visibility.min_visible_fraction", "--visible-fraction",
       "a keyframe has an object in view when this share of its sampled points is in the image "
       "and not occluded",
       &o.visibility.min_visible_fraction},
      {"visibility.range_factor", "--view-range-factor",
       "... and the camera within this times the farthest distance it was detected from",
       &o.visibility.range_factor},
      {"objects.view_min_translation_m", "--view-translation",
       "an observation is a new view of its object after this much camera motion, m (or the "
       "rotation below; 0 and 0: every observation is a view)",
       &m.view_min_translation_m},
      {"objects.view_min_rotation_deg", "--view-rotation",
       "... or after this much camera rotation, degrees", &m.view_min_rotation_deg},
      {"objects.min_points", "--min-points", "observations with fewer points are ignored",
       &m.min_points},
      {"objects.require_same_class", "--same-class", "match only objects of the same voted class",
       &m.require_same_class},
  };
}

// Eq 18, masks from boxes, and the clean-up of given masks.
std::vector<ConfigField> filters_and_masks_fields(FuseOptions& o) {
  auto& b = o.box_mask;
  return {
      {"outlier.enabled", "--outlier-filter", "statistical outlier removal (eq 18) per object",
       &o.outlier_filter},
      {"outlier.neighbours", "--outlier-k", "K nearest neighbours of eq 18", &o.outlier.neighbours},
      {"outlier.std_ratio", "--outlier-std", "k of t = m + k·s (eq 18)", &o.outlier.std_ratio},
      {"outlier.on_points", "--outlier-on-points",
       "eq 18 on each object's back-projected points, then the voxel filter (the paper); false: "
       "on the voxel filter's points",
       &o.outlier_on_points},
      {"objects.voxel_nearest_centre", "--voxel-nearest-centre",
       "the voxel filter keeps each voxel's point nearest its centre (the paper); false: the mean "
       "of its points",
       &o.voxel_nearest_centre},
      {"objects.position_is_centroid", "--position-is-centroid",
       "an object's position is its centroid, the mean of its points (eq 16, the paper); false: "
       "the centre of the box of its points' 1st-99th percentiles",
       &o.position_is_centroid},
      {"objects.position_without_support", "--position-without-support",
       "an object's position and box leave out the strip of the table or floor it rests on that "
       "its masks bled onto: its points at the height of that surface of the map outside the "
       "footprint of its points above",
       &o.position_without_support},
      {"objects.support_band_m", "--support-band",
       "the strip: points within this of the height of the surface the object rests on, m",
       &o.support_strip.band_m},
      {"objects.support_cell_m", "--support-cell",
       "the footprint of the points above the layer: grid cell (widened by one), m",
       &o.support_strip.cell_m},
      {"box_mask.bin_m", "--box-bin", "box masks: depth histogram bin, m", &b.bin_m},
      {"box_mask.near_mode_min_share", "--box-near-share",
       "box masks: share of the largest peak for the nearest peak to win", &b.near_mode_min_share},
      {"box_mask.band_size_factor", "--box-band", "box masks: depth band / metric box size",
       &b.band_size_factor},
      {"box_mask.remove_support_plane", "--box-support-plane",
       "box masks: remove the supporting table/floor plane", &b.remove_support_plane},
      {"box_mask.support_inlier_m", "--box-support-inlier", "box masks: plane inlier distance, m",
       &b.support_inlier_m},
      {"mask_refine.enabled", "--mask-refine",
       "given masks: remove the parts across a depth edge from the rest (spill onto the "
       "background); false: masks as given (the paper)",
       &o.mask_refine.enabled},
      {"mask_refine.min_part_share", "--mask-min-part",
       "given masks: a smooth-depth part within 3 px of the outline (a rim) with fewer pixels "
       "than this share of the largest part is removed",
       &o.mask_refine.min_part_share},
      {"depth_gate.enabled", "--depth-gate",
       "given masks: remove the pixels whose depth is off the object's band |z - median| <= "
       "size factor x object size (bleed onto a far background, occluders in front); false: masks "
       "as given (the paper)",
       &o.depth_gate.enabled},
      {"depth_gate.size_factor", "--depth-gate-size",
       "given masks: half-width of the depth band in object sizes (the mask's box at its median "
       "depth)",
       &o.depth_gate.size_factor},
  };
}

// The scene after the objects: up direction, support surfaces, relations (docs/scene.md).
std::vector<ConfigField> scene_fields(FuseOptions& o) {
  return {
      {"objects.movers", "--movers",
       "classes that move by themselves: their objects are sightings (objects.json `sightings`), "
       "not map objects, kept out of the maps and relations: default (person and the COCO "
       "animals), none (the paper) or a,b,c",
       &o.movers},
      {"scene.up", "--up",
       "the world's up: auto (the cameras, refined by the map's horizontal planes), an axis (z, "
       "-y, ...) or a vector x,y,z; boxes turn about it, heights are along it",
       &o.scene.up.mode},
      {"scene.surfaces", "--surfaces",
       "find the support surfaces (floor, tables, seats) in the dense map for the objects' `on` "
       "relations",
       &o.scene.surfaces.enabled},
      {"scene.near_scale", "--near-scale",
       "relations: two objects are `near` when the clearance between them (their footprints' and "
       "heights' gaps) is at most this times the smaller one's largest horizontal extent ...",
       &o.scene.relations.near_scale},
      {"scene.near_min_m", "--near-min", "... but at least this, m", &o.scene.relations.near_min_m},
      {"scene.near_max_m", "--near-max", "... and at most this, m", &o.scene.relations.near_max_m},
      {"scene.near_by_centres", "--near-by-centres",
       "relations: the old `near`, box centres within --near-radius",
       &o.scene.relations.near_by_centres},
      {"scene.near_radius_m", "--near-radius",
       "relations, with --near-by-centres: objects whose box centres are within this distance are "
       "`near`, m",
       &o.scene.relations.near_radius_m},
  };
}

// The objects' and the scene's meshes (pipeline/fuse_mesh.h, docs/mesh.md).
std::vector<ConfigField> mesh_fields(FuseOptions& o) {
  auto& m = o.mesh;
  return {
      {"mesh.select", "--mesh",
       "none|objects|scene|all: a TSDF mesh of each object (objects/<id>_<class>_mesh.ply) and/or "
       "of the scene (map_mesh.ply)",
       &m.select},
      {"mesh.voxel_m", "--mesh-voxel",
       "object models' voxel, m; 0: from the object's size (--mesh-voxel-fraction)",
       &m.tsdf.voxel_m},
      {"mesh.voxel_fraction", "--mesh-voxel-fraction",
       "object models' voxel as this share of the box's largest side, within [min, max]",
       &m.tsdf.voxel_fraction},
      {"mesh.min_voxel_m", "--mesh-min-voxel", "smallest object model voxel, m",
       &m.tsdf.min_voxel_m},
      {"mesh.max_voxel_m", "--mesh-max-voxel", "largest object model voxel, m",
       &m.tsdf.max_voxel_m},
      {"mesh.truncation_voxels", "--mesh-truncation",
       "signed distances are truncated at this many voxels (and at least 1 cm)",
       &m.tsdf.truncation_voxels},
      {"mesh.space_carving", "--mesh-carving",
       "fuse the free space in front of each ray's band as empty (carves bleed and flying pixels)",
       &m.tsdf.space_carving},
      {"mesh.min_weight", "--mesh-min-weight",
       "a surface only where its voxels carry this weight (1 = one ray at 1 m; 0.005: at 4 m)",
       &m.tsdf.min_weight},
      {"mesh.scene_voxel_m", "--scene-mesh-voxel", "the scene model's voxel, m", &m.scene_voxel_m},
  };
}

}  // namespace

std::vector<ConfigField> fuse_config_fields(FuseOptions& o) {
  // In the order of the data flow (the order of --help and of run.json's options), after the
  // method.
  std::vector<ConfigField> fields{
      {"method", "--method",
       "objmap (default) or paper: every rule as the paper states it (docs/fusion.md); an option "
       "given as well overrides the paper's value",
       &o.method}};
  for (auto part : {inputs_fields, segmentation_fields, association_fields, merging_fields,
                    scoring_fields, filters_and_masks_fields, scene_fields, mesh_fields}) {
    std::vector<ConfigField> more = part(o);
    fields.insert(fields.end(), more.begin(), more.end());
  }
  return fields;
}

void set_method_preset(FuseOptions& o) {
  require(o.method == "objmap" || o.method == "paper", "method",
          "'" + o.method + "' is not a method; expected objmap or paper");
  if (o.method != "paper") return;
  // Masks as given (§3.1): no refinement, no depth gate, no duplicate rule; depth >= 0.01 m.
  o.mask_refine.enabled = false;
  o.depth_gate.enabled = false;
  o.duplicate_overlap = 1.0;
  o.depth.min_depth_m = 0.01;
  // The dense map keeps every voxel (§3.3: the voxel filter only).
  o.dense_prune.every_keyframes = 0;
  // Association and confirmation (§3.2, eqs 17, 21, 22; fusion::set_paper_rules), the voxel
  // sets at the map's resolution (the paper's octree).
  fusion::set_paper_rules(o.objects);
  o.objects.voxel_m = o.map_voxel_m;
  o.distance_score = fusion::to_string(o.objects.distance_score);
  o.overlap_measure = fusion::to_string(o.objects.overlap_measure);
  o.confirmation = fusion::to_string(o.objects.confirmation);
  // Filters (§3.3): eq 18 on the raw points, then the voxel filter (nearest to the centre); all
  // voxels kept.
  o.min_voxel_support = 0.0;
  o.outlier_filter = true;
  o.outlier_on_points = true;
  o.voxel_nearest_centre = true;
  // The object's position is its centroid (eq 16).
  o.position_is_centroid = true;
  o.position_without_support = false;
  // Persons are objects like any other (§4).
  o.movers = "none";
}

FuseChoices FuseOptions::check() const {
  FuseChoices choices;
  require(!dataset.empty(), "--dataset", "missing; expected a recording folder");
  io::DatasetOptions dataset_options;
  dataset_options.layout = layout;
  dataset_options.check();
  require(!segmentation.empty(), "--segmentation", "missing; expected a segmentation folder");
  require(!out.empty(), "--out", "missing; expected the run folder to write");
  require(std::isfinite(max_diff_s) && max_diff_s > 0 && max_diff_s < 1, "max_diff_s",
          "must be in (0, 1) s");
  keyframes.check();
  check_part([&] { depth.check(); }, "BackprojectOptions", "depth",
             {{"min_depth_m", "depth.min_m"}, {"max_depth_m", "depth.max_m"}});
  require(std::isfinite(map_voxel_m) && map_voxel_m >= 0.001 && map_voxel_m <= 1.0, "map.voxel_m",
          "must be in [0.001, 1] m");
  require(dense_stride >= 1 && dense_stride <= 64, "map.dense_stride", "must be in [1, 64]");
  check_part([&] { dense_prune.check(); }, "DensePruneOptions", "map.prune",
             {{"every_keyframes", "map.prune_every"},
              {"tolerance_voxels", "map.prune_tolerance"},
              {"peak_ratio", "map.prune_peak_ratio"},
              {"rejudge", "map.prune_rejudge"}});
  require(std::isfinite(min_instance_score) && min_instance_score >= 0 && min_instance_score <= 1,
          "segmentation.min_score", "must be in [0, 1]");
  require(std::isfinite(duplicate_overlap) && duplicate_overlap > 0 && duplicate_overlap <= 1,
          "segmentation.duplicate_overlap", "must be in (0, 1]");
  check_part([&] { box_mask.check(); }, "BoxMaskOptions", "box_mask");
  check_part([&] { mask_refine.check(); }, "MaskRefineOptions", "mask_refine");
  check_part([&] { depth_gate.check(); }, "DepthGateOptions", "depth_gate");
  check_part([&] { objects.check(); }, "ObjectMapOptions", "objects");
  check_part([&] { objects.oversize.check(); }, "OversizeOptions", "objects",
             {{"margin", "objects.oversize_margin"},
              {"rename_min_vote", "objects.name_for_size_vote"},
              {"under_gap_m", "objects.join_under_gap"}});
  require(!class_sizes.empty(), "objects.class_sizes",
          "is empty; expected builtin, none or a JSON file of class sizes");
  check_part([&] { visibility.check(); }, "VisibilityOptions", "visibility");
  choices.overlap_measure =
      fusion::parse_overlap_measure(overlap_measure, "objects.overlap_measure");
  choices.distance_score = fusion::parse_distance_score(distance_score, "objects.distance_score");
  choices.confirmation = fusion::parse_confirmation(confirmation, "objects.confirmation");
  require(method == "objmap" || method == "paper", "method",
          "'" + method + "' is not a method; expected objmap or paper");
  require(std::isfinite(min_voxel_support) && min_voxel_support >= 0 && min_voxel_support <= 1,
          "objects.min_voxel_support", "must be in [0, 1]");
  check_part([&] { support_strip.check(); }, "SupportStripOptions", "objects",
             {{"band_m", "objects.support_band_m"}, {"cell_m", "objects.support_cell_m"}});
  check_part([&] { outlier.check(); }, "OutlierOptions", "outlier");
  check_part([&] { duplicates.check(); }, "DuplicateOptions", "duplicates");
  choices.movers = fusion::parse_movers(movers, "objects.movers");
  check_part([&] { scene.up.check(); }, "UpOptions", "scene.up", {{"mode", "scene.up"}});
  check_part([&] { scene.surfaces.check(); }, "SurfaceOptions", "scene.surfaces");
  check_part([&] { scene.relations.check(); }, "RelationOptions", "scene.relations",
             {{"near_radius_m", "scene.near_radius_m"},
              {"near_scale", "scene.near_scale"},
              {"near_min_m", "scene.near_min_m"},
              {"near_max_m", "scene.near_max_m"}});
  mesh.check();
  choices.meshes = mesh::parse_mesh_selection(mesh.select, "mesh.select");
  if (choices.meshes.objects || choices.meshes.scene) mesh::require_meshes();  // before any work
  require(threads >= 0 && threads <= 64, "threads",
          "must be in [0, 64] (0: the cores, at most 8), got " + std::to_string(threads));
  return choices;
}

}  // namespace objmap::pipeline

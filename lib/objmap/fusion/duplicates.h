#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "objmap/fusion/object_map.h"

// Suspected duplicates, without ground truth: pairs of confirmed objects of one class
// (segmentation::canonical_class) whose oriented boxes overlap or whose surfaces touch, each with
// the merge pass's verdict on the pair (ObjectMap::merge_verdict): which of its rules kept the two
// apart. One physical object kept as two map objects shows up here; so do two objects of one class
// that really touch (two chairs pushed together, stacked books): the figures say which is likelier.
namespace objmap::fusion {

struct DuplicateOptions {
  // Surfaces closer than this touch: 2 object voxels (the clouds are voxel means 1 cm apart, and
  // depth noise of 1-2 cm at 2-3 m moves a re-seen surface by a voxel or two).
  double touch_distance_m = 0.02;
  // The box overlap is sampled on a regular grid of this many points per axis of the smaller box
  // (cell centres): 20 → 8000 points, the share exact to about 1/20 of a box side's share at worst,
  // far better where faces do not cut the cells' centres in a row.
  int obb_samples_per_axis = 20;
  // Boxes that overlap by less than this share (of the smaller) and whose surfaces do not touch are
  // no suspects: PCA boxes of neighbours graze each other's corners (a few per cent).
  double min_obb_overlap = 0.1;
  void check() const;  // throws InputError naming the bad field
};

struct DuplicatePair {
  int a = -1, b = -1;      // object ids, a < b
  std::string class_name;  // the canonical class of both
  // Share of the smaller box's volume (by the sample grid) inside the larger box, in [0, 1]: 1 for
  // a fragment whose box lies within the whole's, whatever their sizes (an IoU would be small for
  // a small fragment of a large object).
  double obb_overlap = 0.0;
  double surface_distance_m = 0.0;  // shortest distance between the two clouds' points
  // Share of the smaller cloud's points (fewer points) within touch_distance_m of the larger cloud.
  double touching_share = 0.0;
  MergeVerdict merge;  // why the merge pass did not join them (merge.refused)
};

struct DuplicateReport {
  std::vector<DuplicatePair> pairs;  // ascending (a, b)
  std::size_t pairs_checked = 0;     // same-class pairs of confirmed objects looked at
};

// Every pair of confirmed records of one canonical class with obb_overlap >= min_obb_overlap (and
// > 0) or surface_distance_m <= touch_distance_m. `records` are those of `map` after its merge pass
// (ObjectMap::records: ids are the map's); the verdict is taken from `map`, and the surface
// contact of two clouds from its contact cache when it has one (ObjectMap::set_contact_cache).
// No output, no IO.
DuplicateReport find_duplicates(const std::vector<ObjectRecord>& records, const ObjectMap& map,
                                const DuplicateOptions& options = {});

// One line on why the merge pass kept the pair apart, with the figures and the rule's threshold,
// e.g. "seen together in 9 of 12 keyframes (> 30%)"; "would merge" for MergeRefusal::kNone; "no
// merge pass ..." when options.final_merge is false (the paper's method: nothing joins them).
std::string describe_refusal(const MergeVerdict& verdict, const ObjectMapOptions& options);

// Share of the volume of box `small` inside box `large`, sampled on n×n×n cell centres of `small`.
double obb_containment(const Obb& small, const Obb& large, int samples_per_axis);

}  // namespace objmap::fusion

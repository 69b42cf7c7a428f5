#pragma once
#include <optional>
#include <vector>

#include "objmap/core/types.h"

// The extent of one instance (docs/fusion.md, "The extent of one instance"): an object of the map
// wider than its class allows (segmentation/class_sizes.h) is not one instance. A detector gives
// one mask over two or three chairs packed along a table, the tracker gives that mask one id, and
// their surfaces fuse into one object 1-1.5 m wide. Its surface, seen from above, is then two
// masses with a gap or a thin neck between them along its long axis: the cut goes through the
// emptiest place there, each side at least as wide as the smallest instance of the class.
namespace objmap::fusion {

struct OversizeOptions {
  bool enabled = true;       // off: no object is split for its size (`--method paper`)
  double margin = 0.15;      // wider than the class's max_m × (1 + margin) is too wide
  double percentile = 0.02;  // the extent spans the [q, 1 − q] quantiles of the surface
  double bin_m = 0.02;       // the surface's profile along the long axis, in bins of this
  int smooth_bins = 1;       // ... averaged over ±this many bins
  double valley_ratio =
      0.5;  // two instances: the cut bin's count at most this × either side's mean
  double min_side_share = 0.25;  // ... and each side at least this share of the surface
  // One instance: the side cut off is a flat strip when its heights span at most the larger of
  // these (m; share of the kept side's span); else nothing is cut.
  double flat_m = 0.03;
  double flat_share = 0.25;
  // Parts of one instance (ObjectMap::join_parts): two objects of one class, rarely seen in the
  // same keyframes, whose union is no wider than the class allows, at most join_gap_m apart, and
  // either the smaller's surface at least join_min_inside within the larger's footprint (grown by
  // join_grow_m: a chair's back seen over a table, its legs seen below), or with join_continuous
  // both one surface where they meet (continuous_parts: a couch seen from two places one frame in
  // 18 apart, each part its nearer half), or one track id in common.
  bool join_parts = true;
  double join_gap_m = 0.10;
  double join_grow_m = 0.03;
  double join_min_inside = 0.8;
  bool join_continuous = true;
  // continuous_parts: a gap where two parts meet is a band bin_m wide holding at most this × the
  // sparser side's mean per bin_m (an empty band between two objects; a couch's middle, seen
  // aslant from both sides, holds 0.4-0.5 of it).
  double join_valley_ratio = 0.2;
  // Named for its size (ObjectMap::split_oversize): an object wider than its voted class allows
  // that is one instance (nothing beyond the cut to trim) takes the name of another class of its
  // votes that admits its extent, when that class holds at least rename_min_vote × the voted
  // class's score (a monitor the detector called "laptop" and "tv monitor" about as often).
  bool rename = true;
  double rename_min_vote = 0.3;
  // Its foot (ObjectMap::join_parts): an object left too wide for every class it was called (no
  // name above fits) whose middle lies under the footprint (grown by join_grow_m) of a larger
  // confirmed object of another class, at most under_gap_m below it, their union no wider than
  // that class allows, is that object's part (a monitor's foot called mouse and cell phone: its
  // neck, thin and rarely seen, leaves ~10 cm between them).
  bool join_under = true;
  double under_gap_m = 0.15;
  void check() const;  // throws InputError naming the bad field
};

// Where an object is cut. `axis` is horizontal (perpendicular to up), unit, in the world frame; a
// point p lies on side 0 when axis · p < cut, else on side 1.
struct OversizeCut {
  Vec3 axis = Vec3::UnitX();
  double cut = 0.0;
  double extent_m = 0.0;  // the object's horizontal extent along `axis` (quantiles)
  double limit_m = 0.0;   // what its class allows (max_m × (1 + margin))
  // Two instances: the cut lies in a valley of the profile (at most valley_ratio × the mean
  // density of either side) and each side holds at least min_side_share of the surface. Else the
  // object is one instance with something attached (a strip of the table its box masks held):
  // `keep` is the side with more of the surface, the other is not the object.
  bool apart = false;
  int keep = 0;
};

// The horizontal extent of `surface` (points in the world frame; `up` unit) along its long axis
// (the principal axis of the points projected on the horizontal plane), between the percentile
// quantiles.
double horizontal_extent(const std::vector<Vec3>& surface, const Vec3& up, double percentile,
                         Vec3* axis = nullptr);

// The cut of an object whose surface is wider than max_m × (1 + margin) along its long axis:
// the least dense place of its profile (bins of bin_m, smoothed) where both sides span at least
// min_m (half the extent when the extent is under 2 × min_m); ties: the place nearest the middle.
// nullopt when the object is not too wide (or has fewer than 10 points), and when it is one
// instance whose part beyond the cut is not a flat strip (OversizeOptions::flat_m) — unless
// `tall_beyond` is given: then that cut is returned too, with *tall_beyond true, for the caller to
// trim only when the part beyond is another instance's (ObjectMap::cut_oversize).
std::optional<OversizeCut> plan_oversize_cut(const std::vector<Vec3>& surface, const Vec3& up,
                                             double min_m, double max_m,
                                             const OversizeOptions& options,
                                             bool* tall_beyond = nullptr);

// A surface seen from above: its long horizontal axis, the horizontal axis across it, and its
// extents along those and up between the percentile quantiles.
struct Footprint {
  Vec3 axes[3];  // long, across, up (unit)
  double lo[3] = {0.0, 0.0, 0.0};
  double hi[3] = {0.0, 0.0, 0.0};
};
Footprint footprint(const std::vector<Vec3>& surface, const Vec3& up, double percentile);

// How two surfaces of one class fit as parts of one instance, in the frame of `large`'s
// footprint: the share of `small` inside that footprint (grown by grow_m across and along), the
// clearance between their boxes there, and the horizontal extent of both together.
struct PartsFit {
  double inside_share = 0.0;
  double gap_m = 0.0;
  double union_extent_m = 0.0;
};
PartsFit fit_parts(const std::vector<Vec3>& small, const std::vector<Vec3>& large,
                   const Footprint& large_footprint, const Vec3& up, double percentile,
                   double grow_m);

// Whether two surfaces are one where they meet: along the long horizontal axis of both together,
// no band bin_m wide between the two parts' medians (slid in steps of bin_m / 2) holds at most
// join_valley_ratio × the sparser side's mean per bin_m while each side holds min_side_share of
// the points. Two chairs side by side have an empty band between them; the halves of a couch,
// each seen from its own side, overlap in the middle and have none.
bool continuous_parts(const std::vector<Vec3>& a, const std::vector<Vec3>& b, const Vec3& up,
                      const OversizeOptions& options);

}  // namespace objmap::fusion

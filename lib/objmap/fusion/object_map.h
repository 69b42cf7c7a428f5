#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/filters/outlier.h"
#include "objmap/fusion/oversize.h"
#include "objmap/fusion/visibility.h"
#include "objmap/fusion/voxel_map.h"
#include "objmap/geometry/bounds.h"

// The object map (paper §3.2-3.3): each instance observation (its back-projected points) is
// associated with an existing object or starts a new one; objects keep their points in a voxel set
// (memory bounded by the object's surface), a score-weighted class vote and the provenance of every
// observation. A final pass merges objects that the same criteria say are one (ID-switch repair).
namespace objmap::segmentation {
class ClassSizes;
}

namespace objmap::fusion {

// One instance in one keyframe: what fuse() hands to the object map.
struct Observation {
  double timestamp = 0.0;               // rgb timestamp of the keyframe
  std::optional<int> track_id;          // tracking id, when the segmentation/tracker gave one
  std::string class_name;               // detector class, e.g. "teddy bear"
  double score = 1.0;                   // detector confidence in [0, 1]
  PointCloud points_in_world;           // back-projected instance pixels (colours optional)
  std::optional<int> keyframe_index;    // index of the keyframe, for the pose correction
  std::optional<Vec3> centroid_in_cam;  // the observation's centroid in the camera frame (ditto)
  std::optional<Pose> world_from_cam;   // the keyframe's pose: views are counted with it
};

// How M (eq 21) compares two voxel sets A (the observation, or the smaller object in the merge
// pass) and B (the object).
enum class OverlapMeasure {
  // The paper's IoU |A∩B| / |A∪B|. Between one partial view and an object fused from many views it
  // is bounded by |A|/|B| (a view of a cabinet shows ~half of it: M ≤ 0.5 even when every point
  // of the view lies on the object), so well-fused objects stop matching their own new views.
  kIou,
  // |A∩B| / |A| with |A| ≤ |B| (A = the observation in add_frame(); the smaller object in
  // merge_pass()):
  // the share of A that lies on B. 1 for any partial view of the object, whatever the object's
  // size; small for a neighbour (only A's boundary touches it). The default: it measured best
  // (docs/fusion.md, "Object map").
  kContainment,
};
const char* to_string(OverlapMeasure measure);
// "iou" or "containment"; throws InputError(where, ...) otherwise.
OverlapMeasure parse_overlap_measure(const std::string& text, const std::string& where);

// How the centroid distance D enters P (eq 22).
enum class DistanceScore {
  // f(D) = max(0, 1 − D / (2·G)): 1 at D = 0, 1/2 at the gate G, 0 at twice the gate (default).
  kLinear,
  // The paper's gate (eq 17): f(D) = 1 when D < G, else 0, so that "the centroid within 0.1 m"
  // is one criterion of its own, as the track ID is.
  kGate,
};
const char* to_string(DistanceScore score);
// "linear" or "gate"; throws InputError(where, ...) otherwise.
DistanceScore parse_distance_score(const std::string& text, const std::string& where);

// What confirms an object (min_observations of them).
enum class Confirmation {
  kViews,  // observations from distinct viewpoints (count_views; the default)
  // The paper (§3.2): the keyframes in which the object's track ID was seen: the most of any of its
  // track IDs (distinct keyframes of the object's observations with that ID); observations without
  // an ID count together as one more "ID".
  kIdKeyframes,
};
const char* to_string(Confirmation confirmation);
// "views" or "id_keyframes"; throws InputError(where, ...) otherwise.
Confirmation parse_confirmation(const std::string& text, const std::string& where);

// Association score (eq 22): P = w_id·P_ID + w_d·f(D) + w_m·M, a match when P > K.
//   P_ID ∈ {0, 1}: the observation's track id is one of the object's track ids.
//   D (eq 17): distance between the observation's and the object's centroids (voxel-weighted).
//   f(D) = max(0, 1 − D / (2·G)): 1 at D = 0, 1/2 at the gate G, 0 at twice the gate, where
//     G = max(distance_gate_m, gate_radius_factor × r) and r is the object's RMS radius (of its
//     voxels about its centroid; the larger of the two objects in the merge pass): partial views of
//     a large object (a chair, a cabinet) have centroids tens of cm apart, so a fixed 0.1 m gate
//     splits them; for a small object (r < 0.2 m) G is the paper's gate.
//   M (eq 21): overlap_measure of the voxel sets. With overlap_tolerance_voxels = 1 a voxel of A
//     counts as shared when B has a voxel in its 3×3×3 neighbourhood (depth noise of ±1–2 cm at
//     2–3 m moves a re-observed surface by a voxel or two, so exact 1 cm coincidence is fragile).
// The defaults are chosen so that the paper's single-criterion rules become the combined rule:
//   w_m·0.8 = K: overlap above the paper's 0.8 alone is a match (re-seen object, new id);
//   w_id < K and w_d < K: neither an id alone (id switches, reused ids) nor nearness alone (two
//     objects side by side) is a match;
//   w_id + w_d·f(G) = K: the same id and D below the gate is a match;
//   no id: nearness needs overlap too (D = 0: M > 0.4; D = G: M > 0.6).
// Weights sum to 1, so P ∈ [0, 1].
// The merge pass (ID-switch repair) uses the same P between two objects, but by default only for
// objects of the same voted class (merge_require_same_class) and with the containment of the
// smaller object in the larger at least merge_min_overlap: fragments of one object (one view
// contained in the whole) join, two distinct objects side by side (two cups 5 cm apart, stacked
// books, a mouse by a keyboard) share only their touching boundary and stay two.
struct ObjectMapOptions {
  double voxel_m = 0.01;            // object voxel sets and the overlap M, at the map resolution
  double distance_gate_m = 0.1;     // the paper's centroid gate (eq 17); f(gate) = 1/2
  double gate_radius_factor = 0.5;  // G = max(distance_gate_m, this × object RMS radius); 0: fixed
  OverlapMeasure overlap_measure = OverlapMeasure::kContainment;  // M of eq 21 (see above)
  int overlap_tolerance_voxels = 1;      // 0: exact voxel coincidence; 1: 3×3×3 neighbourhood
  double weight_id = 0.3;                // w_id
  double weight_distance = 0.2;          // w_d
  double weight_overlap = 0.5;           // w_m
  double match_threshold = 0.4;          // K (eq 22): match when P > K
  double merge_threshold = 0.4;          // K for the final merge pass between two objects
  bool merge_require_same_class = true;  // the merge pass joins only objects of one voted class
  double merge_min_overlap = 0.5;        // ... and only when M (containment of the smaller) >= this
  // Two instances of one keyframe are two objects: an object takes at most one observation per
  // timestamp (add_frame() skips objects that already have one), and the merge pass never joins two
  // objects that were both observed in more than this share of the smaller one's keyframes (e.g.
  // two books stacked, seen together in every frame; a fragment of an ID switch is seen in other
  // keyframes than its object). 1: no such rule.
  bool one_observation_per_frame = true;
  double merge_max_shared_frames = 0.3;
  // Class confusion (after the same-class merges): an object whose voxels lie almost all on
  // another object of another class that has several times its views is that object, named
  // otherwise by the detector in some frames (a keyboard boxed as "book", a monitor's screen as
  // "laptop"). With one observation per object and frame, the odd name's observations cannot
  // join the object in the frames where it was also named rightly, so they keep an object of their
  // own — one more object for every few frames of such confusion, and more of them the more
  // frames are fused. It joins the larger; the class vote decides the name. Two distinct objects
  // share only their touching boundary (containment far below 0.9), and an object on a larger one
  // (a cup on a table) is seen about as often as it.
  bool merge_class_confusions = true;
  double confusion_min_containment = 0.9;  // share of the smaller's voxels on the larger's
  double confusion_min_view_ratio = 2.0;   // the larger has at least this many times the views
  double confusion_min_support = 0.1;  // the larger's voxels that count: in >= this share of its
                                       // observations (its surface, not a bleed of a few views)
  // Fragments (after the class confusions): an object whose surface lies inside the oriented box
  // of a larger object of its voted class (the PCA box of the larger's surface voxels, grown by
  // one voxel), seen with several times fewer views and in few of the same keyframes
  // (merge_max_shared_frames), is a part of it that its views did not share voxels with: the far
  // side of a chair's back seen over a table on a walk round it, its top above the table's edge.
  // Two objects of one class seen apart in the same frames stay two (the shared frames), and so
  // do objects side by side (their surfaces lie outside each other's box).
  bool merge_fragments_in_box = true;
  double fragment_min_inside = 0.8;      // share of the smaller's surface voxels inside the box
  double fragment_min_view_ratio = 2.0;  // the larger has at least this many times the views
  int min_observations = 3;  // an object is confirmed once it has this many views (below)
  // Confirmation counts views, not observations, so that more frames of the same scene do not
  // confirm more objects: an observation is a new view of its object when its camera moved at
  // least view_min_translation_m or turned at least view_min_rotation_deg since the object's last
  // view (the keyframe selection's motion rule, applied per object). A detector's false positive
  // that lasts three consecutive frames of a 30 Hz video is then one view, as it is among motion
  // keyframes. Observations without a pose each count as a view. 0 and 0: every observation is a
  // view (the paper's count).
  double view_min_translation_m = 0.05;
  double view_min_rotation_deg = 5.0;
  // Confirmation by the detected share (fusion/visibility.h), on top of min_observations: after
  // judge_visibility(), an object is confirmed only when it was detected in at least this share of
  // the keyframes that had its place in view (or detected it). A false positive or a fragment
  // seen in a few of the hundreds of keyframes that saw its place drops out, however dense the
  // frames; a count of views grows with them. 0: no such rule (the paper).
  // The bar is the higher of min_detected_share and detected_share_of_median × the median share
  // of the objects with enough views: a detector's recall differs by recording (about nine in
  // ten on the synthetic walk-through, one in eight for small objects in fr1_rpy's boxes), and a
  // false positive is what this detector found far less often than it finds objects here.
  double min_detected_share = 0.05;
  double detected_share_of_median = 0.25;
  int min_points = 10;  // observations with fewer points (after depth checks) are ignored
  // Bleed: in one keyframe, an instance whose voxels lie (bleed_min_inside of them, within one
  // voxel) on those of another instance of its class with bleed_min_ratio times its voxels is that
  // instance's surface again — a far chair's mask that bled onto the near chair in front of it,
  // its own pixels beyond the depth range — and is ignored: with one observation per object and
  // frame it could only start a fragment. Two objects side by side share their boundary only; a
  // mask over two objects is not a few percent of the other's.
  bool drop_bleed = true;
  double bleed_min_inside = 0.8;
  double bleed_min_ratio = 5.0;
  // Spanning: an instance of which at least span_min_share lies on each of two objects of its
  // class, both confirmed by their views already, apart (the smaller less than span_min_share on
  // the larger: not an object and its fragment) and seen as two in the same keyframes (more than
  // merge_max_shared_frames of the smaller's: not two halves of one object seen by turns), is one
  // mask over two objects side by side
  // (chairs packed round a table whose masks touch): fused into either it would give that object
  // the other's voxels and, in the merge pass, the other object itself. It is ignored.
  bool drop_spanning = true;
  double span_min_share = 0.25;
  // Split (after the merge passes, before judge_visibility()): an object whose surface (voxels
  // seen in >= 10% of its observations) falls into separate clusters of coarse cells
  // (split_cell_voxels voxels a side, 26-connected: clusters at least one cell apart), two or more
  // of them large (split_min_share of the surface voxels each), is two objects when its
  // observations see those clusters apart: at most split_max_joint of the observations covering
  // the less covered cluster (split_cover_share of an observation's cells on it) cover the other
  // too. Chairs side by side that a tracker's ID swap joined are seen one per observation; a
  // chair whose thin legs are a cluster apart from its seat is seen with its legs in the same
  // observations, and stays one. Each part takes the observations that lie mostly on it (its
  // provenance, track ids, frames, class votes, views), and every part must have
  // min_observations views, or nothing is split. Small clusters go to the part nearest them.
  bool split_clusters = true;
  int split_cell_voxels = 4;
  double split_min_share = 0.2;
  double split_cover_share = 0.1;
  double split_max_joint = 0.2;
  // Oversize (split_oversize(), once the up is known): an object wider than its class allows
  // (segmentation/class_sizes.h) is cut in two at the emptiest place along its long axis, again
  // until no part is (fusion/oversize.h).
  OversizeOptions oversize;
  bool require_same_class = false;  // only match observations to objects of the voted class
  // The paper's method (`objmap fuse --method paper`, docs/fusion.md "The paper's method") needs
  // these; the defaults are objmap's.
  DistanceScore distance_score = DistanceScore::kLinear;  // f(D) of eq 22 (above)
  Confirmation confirmation = Confirmation::kViews;       // what min_observations counts
  // add_frame(): true: the best (observation, object) pair of the keyframe first (above); false:
  // each observation in turn, in the order given, takes its best object (the paper).
  bool best_first = true;
  bool final_merge = true;   // merge_pass() joins objects of one class (false: the paper, none)
  bool keep_points = false;  // each object keeps its observations' points (RecordOptions below)
  void check() const;        // throws InputError naming the bad field
};

// Sets the paper's association and confirmation rules (§3.2; `objmap fuse --method paper`) and
// leaves the other fields: eq 17 as a criterion of its own (DistanceScore::kGate, the fixed 0.1 m
// gate), eq 21 the IoU of the exact voxel sets, eq 22 with w = (0.5, 0.5, 0.5) and K = 0.4 — the
// same track ID alone (0.5 > K) or a centroid within 0.1 m alone (0.5 > K) joins, the overlap
// alone only above the paper's 0.8 (0.5 · 0.8 = K); each instance in turn, any number per
// keyframe, no final merge or class-confusion pass; confirmed once the object's ID was seen in 3
// keyframes; keep_points for the paper's filters (RecordOptions::outlier_on_points,
// voxel_nearest_centre).
void set_paper_rules(ObjectMapOptions& options);

// Why an observation joined its object (or started it): one entry of an object's provenance.
struct ObservationLink {
  double timestamp = 0.0;
  std::optional<int> track_id;
  std::string class_name;
  double score = 0.0;
  std::optional<int> keyframe_index;
  std::optional<Vec3> centroid_in_cam;
  std::optional<Pose> world_from_cam;
  Vec3 centroid_in_world = Vec3::Zero();  // the observation's voxel-weighted centroid
  std::size_t points = 0;                 // points of the observation
  bool created = false;                   // it started the object (the scores below are then 0)
  double p_id = 0.0;                      // P_ID
  double distance_m = 0.0;                // D
  double overlap = 0.0;                   // M
  double score_p = 0.0;                   // P
};

// A merge of the final pass: `absorbed` joined `into` with these scores.
struct MergeLink {
  int into = -1;
  int absorbed = -1;
  double p_id = 0.0, distance_m = 0.0, overlap = 0.0, score_p = 0.0;
  bool class_confusion = false;  // joined by the class-confusion rule (overlap = containment)
  bool fragment = false;  // joined by the fragment rule (overlap = share inside the larger's box)
  bool part = false;  // join_parts(): parts of one instance (overlap = share inside the footprint)
};

// A split of split_pass(): object `from` kept one part (the one with most observations), the
// others became the objects `parts`.
struct SplitLink {
  int from = -1;
  std::vector<int> parts;
  std::size_t large_clusters = 0;  // clusters with split_min_share of the surface voxels
};

// split_oversize: an object too wide for its voted class, one instance, named after another class
// of its votes that admits its extent (OversizeOptions::rename).
struct ClassRename {
  int id = -1;
  std::string from, to;
  double extent_m = 0.0;  // its horizontal extent (OversizeCut::extent_m)
};

// The rule of the merge pass that keeps two objects apart: the first that refuses, in the pass's
// order (class, shared keyframes, P, M).
enum class MergeRefusal {
  kNone,          // no rule refuses: the pass would join them
  kClass,         // different voted classes (merge_require_same_class or require_same_class)
  kSharedFrames,  // both labelled their class in > merge_max_shared_frames of the smaller's frames
  kScore,         // P <= merge_threshold
  kOverlap,       // M (containment of the smaller in the larger) < merge_min_overlap
};
// "none", "class", "shared_frames", "score", "overlap".
const char* to_string(MergeRefusal refusal);

// The merge pass's rules evaluated for two live objects (ObjectMap::merge_verdict).
struct MergeVerdict {
  int a = -1, b = -1;  // object ids, a < b
  MergeRefusal refused = MergeRefusal::kNone;
  // P_ID, D, M, P of eq 22 between the two (the smaller against the larger), each computed
  // whichever rule refused.
  double p_id = 0.0, distance_m = 0.0, overlap = 0.0, score_p = 0.0;
  int shared_frames = 0;   // keyframes in which both took an observation labelled with the class
  int smaller_frames = 0;  // keyframes of the object with fewer (the share's denominator)
};

struct ClassVote {
  double score_sum = 0.0;  // Σ detector score of the observations with this class
  int count = 0;           // number of those observations
};

// One object as exported (objects.json, objects/<id>_<class>.ply).
struct ObjectRecord {
  int id = -1;
  std::string class_name;  // the score-weighted vote
  std::map<std::string, ClassVote> class_histogram;
  double mean_score = 0.0;       // mean detector score of its observations
  Vec3 centroid = Vec3::Zero();  // mean of the filtered points: the paper's position
  // Centre of the box spanned by the 1st and 99th percentiles of the filtered points along each
  // world axis: the estimate of the centre of the object's box. The point mean is biased toward
  // the seen side (only the surface facing the camera is fused) and toward the parts with most
  // surface (a chair's seat and back, not its legs); the extent is not, as long as the views cover
  // the object's outline; the percentiles ignore the last stray points. The 1st/99th, not the
  // 5th/95th: thin parts such as chair legs fall below the 5th percentile (docs/fusion.md,
  // "Records").
  Vec3 position = Vec3::Zero();
  Aabb aabb;                        // of the filtered points
  Obb obb;                          // PCA box of the filtered points
  std::size_t points_raw = 0;       // points of all its observations (before filtering)
  std::size_t points_voxel = 0;     // after the voxel filter and min_voxel_support (voxels kept;
                                    // after eq 18 too with outlier_on_points)
  std::size_t points_filtered = 0;  // after the outlier filter (eq 18): the cloud
  // Points of the cloud that are the strip of the table or floor it rests on
  // (geometry::support_strip), left out of `position` and `obb` (the scene step; 0 before it).
  std::size_t points_support = 0;
  double outlier_threshold = 0.0;  // t of eq 18 for this object
  int observations = 0;
  int views = 0;            // observations from distinct viewpoints (above)
  bool confirmed = false;   // min_observations views (or ID keyframes, ObjectMapOptions) and the
                            // detected share
  int frames_detected = 0;  // keyframes with an observation of it
  int frames_in_view = -1;  // keyframes that had its place in view or detected it; -1: not judged
  double first_seen = 0.0, last_seen = 0.0;  // timestamps
  std::vector<int> track_ids;                // ascending
  std::vector<ObservationLink> provenance;   // by timestamp, then insertion order
  std::vector<MergeLink> merges;             // objects absorbed by the final pass
  PointCloud cloud;                          // filtered points (voxel means, mean colours)
};

struct RecordOptions {
  double position_percentile = 0.01;  // ObjectRecord::position: centre of [q, 1 − q] per axis
  bool position_is_centroid = false;  // ... or the centroid (eq 16, the paper's position)
  // The scene step (pipeline/fuse_scene.h) gives `position` and `obb` without the strip of the
  // support (geometry::support_strip) when this is set and position_is_centroid is not.
  bool position_without_support = true;
  geometry::SupportStripOptions support_strip;
  bool confirmed_only = true;  // leave out objects with < min_observations
  bool outlier_filter = true;  // apply eq 18 to each object's voxel cloud
  // Before eq 18: keep only voxels that were in at least max(1, this × observations) of the
  // object's observations. A voxel of the object's surface is in every view that sees it; a voxel
  // of the background that a mask boundary bled onto (dilated masks, box masks) is in one or two
  // views only, yet such voxels accumulate into dense strips (floor, wall) that eq 18 keeps.
  // 0: keep every voxel (the paper).
  double min_voxel_support = 0.1;
  filters::OutlierOptions outlier;  // K, k, threads
  // The paper's filters (§3.3), both need ObjectMapOptions::keep_points. outlier_on_points: eq 18
  // on the object's back-projected points, then the voxel filter (false: the voxel filter, then
  // eq 18 on one point per voxel). voxel_nearest_centre: the voxel filter keeps, per voxel, the
  // point nearest the voxel's centre, with its colour (false: the mean of the voxel's points).
  bool outlier_on_points = false;
  bool voxel_nearest_centre = false;
};

// How many of an object's observations (its provenance, in time order) are views by the rule of
// options.view_min_translation_m / view_min_rotation_deg: the first, and each one whose camera
// moved or turned that much from the last view; an observation without a pose is a view.
int count_views(const std::vector<ObservationLink>& provenance, const ObjectMapOptions& options);

// The keyframes (distinct timestamps) in which the most-seen track ID of `provenance` was observed;
// the observations without an ID count as one more ID (Confirmation::kIdKeyframes).
int count_id_keyframes(const std::vector<ObservationLink>& provenance);

// The voxel filter of the paper (§3.3) on `cloud`: per voxel of `voxel_m` (keys as
// VoxelMap::key_of) the point nearest the voxel's centre (ties: the earlier point), with its
// colour, sorted by voxel key. `keep(key)`, when given, says which voxels are kept.
PointCloud voxel_nearest_centre(const PointCloud& cloud, double voxel_m,
                                const std::function<bool(VoxelKey)>& keep = {});

// What add_frame() did with an observation.
struct AddResult {
  int object_id = -1;  // -1: ignored (fewer than min_points points, or bleed)
  bool created = false;
  bool bleed = false;     // ignored as another instance's surface (ObjectMapOptions::drop_bleed)
  bool spanning = false;  // ignored as a mask over two objects (ObjectMapOptions::drop_spanning)
  double p_id = 0.0, distance_m = 0.0, overlap = 0.0, score_p = 0.0;
};

class RecordCache;
class PairCache;
class ContactCache;

class ObjectMap {
 public:
  explicit ObjectMap(const ObjectMapOptions& options = {});
  ~ObjectMap();
  ObjectMap(ObjectMap&&) noexcept;
  ObjectMap& operator=(ObjectMap&&) noexcept;
  // A deep copy (objmap follow finishes a copy of the live map at each publish).
  ObjectMap(const ObjectMap& other);
  ObjectMap& operator=(const ObjectMap& other);

  // Associates the observations of one keyframe together (all with the same timestamp) by eq 22,
  // and fuses each into its object or starts an object with it: the
  // (observation, object) pair with the highest P > K is fused first, then the best among the
  // rest, and so on (with one_observation_per_frame an object takes one observation of the frame),
  // so that an observation's object does not depend on which instance the segmentation listed
  // first. Ties: the earlier observation, then the lower id. The observations that match nothing
  // start objects, in their order. Results in the order of `observations`.
  std::vector<AddResult> add_frame(const std::vector<Observation>& observations);

  // records() reuses the filtered clouds `cache` holds for objects whose content has not changed
  // and puts the ones it makes there (objmap follow's publishes; copies of this map share it).
  // Not with ObjectMapOptions::keep_points. Null: none.
  void set_record_cache(std::shared_ptr<RecordCache> cache) { record_cache_ = std::move(cache); }
  // merge_pass() takes the pair rule's scores of two objects from `cache` when both are as they
  // were when it scored them, and puts the ones it makes there. Null: none.
  void set_pair_cache(std::shared_ptr<PairCache> cache) { pair_cache_ = std::move(cache); }
  // The duplicate check of this map's records (find_duplicates) takes the surface contact of two
  // clouds from `cache` when both are as they were, and puts the ones it makes there. Null: none.
  void set_contact_cache(std::shared_ptr<ContactCache> cache) { contact_cache_ = std::move(cache); }
  ContactCache* contact_cache() const { return contact_cache_.get(); }

  // The final merge pass (ID-switch repair): repeatedly joins the pair of objects with the highest
  // P > merge_threshold (P_ID = the two share a track id; D and M between the two objects), the
  // higher id into the lower; then the class-confusion and fragment merges; all again until none
  // joins anything. Returns the merges made. Calling it again finds nothing new.
  std::vector<MergeLink> merge_pass();

  // Splits the objects whose surface forms clusters that their observations see apart
  // (ObjectMapOptions::split_clusters; none when off). Call after merge_pass() and before
  // judge_visibility(). Returns the splits, ascending original id.
  std::vector<SplitLink> split_pass();

  // Splits every confirmed-by-views object wider than its class allows (`sizes`; `up` the world's
  // up, unit) in two at the emptiest place along its long axis (plan_oversize_cut), and each part
  // again while it is too wide: one mask over two chairs that the tracker gave one id, or two
  // objects a merge joined. Each part takes the voxels on its side and the observations whose
  // cells lie mostly on it. Call after split_pass(); when it splits anything, judge_visibility()
  // again. Returns the splits (SplitLink::large_clusters 0), in the order made. An object too wide
  // that is one instance is named after another class of its votes that admits it
  // (OversizeOptions::rename; appended to `renamed`).
  std::vector<SplitLink> split_oversize(const Vec3& up, const segmentation::ClassSizes& sizes,
                                        std::vector<ClassRename>* renamed = nullptr);
  // Once the up is known, after split_oversize: joins the objects of one class that are parts of
  // one instance (OversizeOptions::join_parts: a chair's back seen over a table, its legs seen
  // below it, when a mask over two chairs took its other views), the smaller footprint into the
  // larger, a confirmed object, the best fit first; the joined object is judged in view again.
  // Then an object split_oversize left too wide for every class it was called joins the larger
  // object of another class it lies under (OversizeOptions::join_under: a monitor's foot).
  // Returns the joins.
  std::vector<MergeLink> join_parts(const Vec3& up, const segmentation::ClassSizes& sizes);

  // The rules of merge_pass() for live objects `a` and `b` as they are now, every score computed
  // (the pass stops at the first refusal): after the pass, why two objects stayed apart. Throws
  // InputError for an id that is not a live object.
  MergeVerdict merge_verdict(int a, int b) const;

  // Live objects (not absorbed by a merge), ascending id.
  std::size_t size() const;
  std::size_t confirmed_count() const;
  // Live objects with enough views that the detected share leaves out (judge_visibility()).
  std::size_t below_share_count() const;
  // The detected share an object needs after judge_visibility() (0 before, or with the rule off).
  double detected_share_bar() const { return share_bar_; }
  // The id an object id ended up in after merges (itself when never absorbed; -1 if unknown).
  int resolve(int object_id) const;
  // The id the observation of `timestamp` that joined `object_id` ended up in after merges and
  // splits (resolve(object_id) when no split moved it).
  int resolve(int object_id, double timestamp) const;

  // For every live object, the keyframes of `log` that had its place in view (fusion/visibility.h;
  // its sample: evenly spaced voxels seen in >= 10% of its observations; its range: the farthest
  // camera of its observations), so that confirmation can ask for min_detected_share. Call after
  // merge_pass(); objects made or merged later are not judged (the share rule passes them).
  // `only_unjudged`: only the objects made since the last call (split_oversize's parts); the bar
  // is made again from every object.
  void judge_visibility(const ViewLog& log, const VisibilityOptions& options,
                        bool only_unjudged = false);

  // The object records, ascending id, each with its filtered cloud.
  std::vector<ObjectRecord> records(const RecordOptions& options = {}) const;
  // The records of the objects `ids` only (those live and, with confirmed_only, confirmed).
  std::vector<ObjectRecord> records(const RecordOptions& options, const std::set<int>& ids) const;

  // Voxel-weighted centroid of object `object_id` as it is now (for tests and the pose correction).
  Vec3 centroid(int object_id) const;

  const ObjectMapOptions& options() const { return options_; }

 private:
  struct Object;
  struct Scores {
    double p_id = 0.0, distance_m = 0.0, overlap = 0.0, score_p = 0.0;
  };
  // A = a voxel set with its centroid, RMS radius and voxel bounds; B = an object.
  Scores score(bool same_id, const Vec3& centroid_a, double radius_a, const VoxelMap& a,
               const Eigen::Vector3i& a_lo, const Eigen::Vector3i& a_hi, const Object& b,
               double threshold) const;
  static std::string voted_class(const Object& object);
  // |A ∩ B| of eq 21: voxels of `a` that `b` has (overlap_tolerance_voxels 0) or has within one
  // voxel (1).
  std::size_t shared_voxels(const VoxelMap& a, const Object& b) const;
  // The merge pass's rules for live objects a (the lower id) and b; `full`: every score computed
  // (merge_verdict), else it stops at the first refusal and scores P against merge_threshold only
  // as far as it decides (merge_pass).
  MergeVerdict judge_pair(const Object& a, const Object& b, bool full) const;
  // An observation's voxel set at the map resolution, its bounds and centroid (add_frame() step 1).
  struct Prepared;
  bool prepare(const Observation& obs, Prepared& out) const;
  // May `object` take `obs` (alive, class, one per frame), and with which scores; false when P <=
  // `threshold` or the object is not a candidate.
  bool candidate(const Observation& obs, const Prepared& prep, const Object& object,
                 double threshold, Scores& s) const;
  // add_frame(): the observations that are bleed onto another of the frame (drop_bleed).
  std::vector<bool> bleed(const std::vector<Observation>& observations,
                          const std::vector<std::unique_ptr<Prepared>>& prep,
                          const std::vector<bool>& open) const;
  // add_frame(): does the observation lie on two confirmed objects of its class (drop_spanning)?
  bool spans_two(const Observation& obs, const Prepared& prep) const;
  // add_frame() with best_first false: each observation in turn takes its best object.
  std::vector<AddResult> add_frame_in_turn(const std::vector<Observation>& observations);
  // What confirms `object`: its views or its ID's keyframes (ObjectMapOptions::confirmation).
  int confirmation_count(const Object& object) const;
  // Confirmed: confirmation_count >= min_observations and, when judged, the detected share.
  bool confirmed(const Object& object) const;
  // records(): the object's filtered cloud in `r` (points_voxel, points_filtered, cloud, t).
  void filter_record(const Object& object, const RecordOptions& options, ObjectRecord& r) const;
  // A 64-bit hash of what filter_record reads of `object` under `options` (record_cache_'s key).
  std::uint64_t record_content(const Object& object, const RecordOptions& options) const;
  // A 64-bit hash of everything judge_pair reads of `object` (pair_cache_'s key).
  static std::uint64_t pair_content(const Object& object);
  // add_frame(): fuses the observation into `target` (nullptr: a new object).
  AddResult fuse(const Observation& obs, const Prepared& prep, Object* target, const Scores& s);
  // Joins `absorbed` into `into` (voxels, votes, provenance, merges); `absorbed` dies.
  void absorb(Object& into, Object& absorbed, const MergeLink& link);
  // The share of a's voxels within reach of b's supported voxels (class confusion).
  double supported_share(const Object& a, const Object& b) const;
  // supported_share(a, b) through the pair cache (by the two objects' pair_content), when set.
  double cached_supported_share(const Object& a, const Object& b) const;
  // The pair rule of merge_pass() (highest P first), its merges appended to `made`.
  void merge_scored_pairs(std::vector<MergeLink>& made);
  // The class-confusion merges (ObjectMapOptions::merge_class_confusions), appended to `made`.
  void merge_class_confusions(std::vector<MergeLink>& made);
  // The fragment merges (ObjectMapOptions::merge_fragments_in_box), appended to `made`.
  void merge_fragments_in_box(std::vector<MergeLink>& made);
  // split_pass() for objects_[index]: true and `link` when it was split.
  bool split_object(std::size_t index, SplitLink& link);
  // Puts `parts` of objects_[index] in its place: the part with most observations keeps its id
  // and merges, the others are new objects (link.parts).
  void install_parts(std::size_t index, std::vector<std::unique_ptr<Object>> parts,
                     SplitLink& link);
  // split_oversize() for objects_[index] with its class's size: true and `link` when it was cut;
  // false, with *one_wide_m its extent, when it is too wide but one instance with nothing to trim.
  bool cut_oversize(std::size_t index, const Vec3& up, double min_m, double max_m, SplitLink& link,
                    double* one_wide_m);
  // The class of o's votes, other than its voted one, that admits `extent_m` with the most score
  // of at least rename_min_vote × the voted class's; "" when none.
  std::string name_for_size(const Object& o, double extent_m,
                            const segmentation::ClassSizes& sizes) const;
  // Half or more of `part` (surface points of `o`) lies over the footprint of another confirmed
  // object of o's class (cut_oversize: the part beyond a cut is that instance's).
  bool on_another_instance(const Object& o, const std::vector<Vec3>& part, const Vec3& up) const;
  // join_parts' second step (OversizeOptions::join_under): each object too wide for every class
  // it was called joins the confirmed object of another class, larger (its upright box's volume),
  // that it lies under, the nearest; appended to `made`.
  void join_under(const Vec3& up, const segmentation::ClassSizes& sizes,
                  std::vector<MergeLink>& made);
  // The parts of `object` by split_object's plan: observation j to part obs_part[j], voxel (its
  // cell) to part voxel_part(key).
  std::vector<std::unique_ptr<Object>> make_parts(Object& object, const std::vector<int>& obs_part,
                                                  int parts,
                                                  const std::function<int(VoxelKey)>& voxel_part);
  // The mean positions of the voxels of `object` seen in >= `share` of its observations (all of
  // them when none is), in key order. Made once per content (Object::memo).
  std::shared_ptr<const std::vector<Vec3>> surface_points(const Object& object, double share) const;

  ObjectMapOptions options_;
  std::shared_ptr<RecordCache> record_cache_;    // set_record_cache; shared by copies
  std::shared_ptr<PairCache> pair_cache_;        // set_pair_cache; shared by copies
  std::shared_ptr<ContactCache> contact_cache_;  // set_contact_cache; shared by copies
  double share_bar_ = 0.0;  // judge_visibility(): the detected share an object needs
  std::vector<std::unique_ptr<Object>>
      objects_;  // index = id; absorbed objects stay (alive = false)
};

// The two class-coloured maps: `semantic` = every voxel of the dense map, voxels that belong to a
// confirmed object painted with the object's class colour (palette.h), the others in their mean
// colour; `objects_only` = the records' filtered clouds painted with their class colour, by id. A
// voxel claimed by two objects goes to the one with more observations (then the lower id).
struct SemanticMaps {
  PointCloud semantic;
  PointCloud objects_only;
  std::size_t voxels_painted = 0;
};
SemanticMaps make_semantic_maps(const VoxelMap& dense, const std::vector<ObjectRecord>& records);

// The confirmed record each voxel (of `voxel_m`, keys as VoxelMap::key_of) holds a point of, as
// record index + 1; a voxel claimed by two goes to the one with more observations, then the lower
// id. The semantic maps' rule (make_semantic_maps, and fuse's map_semantic.ply).
geometry::VoxelHashTable<std::uint32_t> voxel_owners(const std::vector<ObjectRecord>& records,
                                                     double voxel_m);

}  // namespace objmap::fusion

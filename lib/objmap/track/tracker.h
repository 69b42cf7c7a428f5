#pragma once
#include <cstddef>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/segmentation/types.h"
#include "objmap/track/appearance.h"
#include "objmap/track/kalman.h"

// DeepSORT (Wojke, Bewley, Paulus, "Simple Online and Realtime Tracking with a Deep Association
// Metric", ICIP 2017), the tracker of the paper's first contribution: a Kalman filter per track,
// Mahalanobis gating, an appearance gallery per track with cosine distance, the matching cascade
// by time since update, IoU matching for tentative and just-lost tracks, Hungarian assignment and
// the tentative -> confirmed -> deleted life cycle. Defaults are deep_sort's (deep_sort_app.py,
// tracker.py, track.py).
namespace objmap::track {

struct TrackerOptions {
  KalmanOptions kalman;  // box motion model (noise weights 1/20, 1/160)
  AppearanceOptions appearance;
  // Use the appearance descriptor (cosine distance, gated by Mahalanobis) in the cascade. Off:
  // the cascade's cost is the squared Mahalanobis distance itself (DeepSORT with lambda = 1), used
  // when there are no images (a stream of boxes).
  bool use_appearance = true;
  double max_cosine_distance = 0.2;  // cascade threshold on the cosine distance (deep_sort_app 0.2)
  // lambda of DeepSORT's eq 5 with appearance on: cascade cost = lambda x squared Mahalanobis
  // distance + (1 - lambda) x cosine distance, a pair admissible when both pass their gate.
  // DeepSORT uses 0 (appearance decides, motion only gates).
  double lambda = 0.0;
  double gating_threshold = kChi2Inv95Dof4;  // squared Mahalanobis gate, chi-square 95% 4 dof
  double max_iou_distance = 0.7;  // IoU stage: 1 - IoU must be <= this (IoU >= 0.3; DeepSORT 0.7)
  int max_age = 30;  // a confirmed track is deleted after more than this many missed frames
                     // and is re-found by the cascade after up to max_age - 1 (DeepSORT 30)
  int n_init = 3;    // a tentative track is confirmed after this many consecutive hits (DeepSORT 3)
  int nn_budget = 100;  // appearance gallery: the newest descriptors kept per track (DeepSORT 100)
  // A detection only joins a track of the same class (the track's majority class). DeepSORT has no
  // classes; off by default because detectors flip classes from frame to frame (teddy bear /
  // person, mouse / cup) and each flip would then break the track: on the synthetic scene
  // (docs/cli.md, "Tracking") turning it on lowers IDF1 from 0.81 to 0.76. The track's class is the
  // majority vote of its detections either way.
  bool same_class_only = false;
  // Detections below this score are not tracked (kept in the output without a track id).
  // deep_sort_app uses 0.8 for its own Faster R-CNN scores; objmap's inputs are already
  // thresholded by the detector, so the default keeps them all.
  double min_score = 0.0;
  double min_height_px = 0.0;  // boxes lower than this are not tracked (deep_sort_app 0)

  // 3D gate (objmap's addition to DeepSORT; it knows depth and poses): a detection with a 3D
  // position (Detection::point_in_world) may join a track with one only when the two are within
  //   radius = max(gate_3d_m, gate_3d_speed_mps x seconds since the track's last 3D position)
  // in every stage (cascade and IoU). Stops ID swaps between similar boxes at different depths.
  // Either side without a 3D position: no 3D gate for that pair.
  bool use_gate_3d = false;
  // Base radius, metres. The robust centroid of a static object moves with the view (another side,
  // the mask's bleed, depth noise, pose error): measured on the synthetic scene and fr1_rpy
  // (docs/benchmarks.md, "The tracker's 3D gate"), 0.3 m keeps the true pairs and separates
  // objects a box apart in depth.
  double gate_3d_m = 0.3;
  // Speed bound of an object, m/s: a track lost for longer may have moved (a person walking, a cup
  // carried). 0.5 m/s: the radius grows beyond the base after 0.6 s without a 3D update.
  double gate_3d_speed_mps = 0.5;
  // The gate passes when the detection is within the radius of ANY of the track's last this many
  // 3D positions (each with its own elapsed time). 1 = the last position only. More lets a track
  // come back to an earlier position after one outlier (a box mask that took what stands behind
  // the object for a frame); measured, it changes little (docs/benchmarks.md, "The tracker's 3D
  // gate").
  int gate_3d_history = 1;

  void check() const;  // throws InputError naming the bad field
};

// One detection given to the tracker for a frame.
struct Detection {
  segmentation::Box box;  // pixels (x, y, w, h), w and h > 0
  std::string class_name;
  double score = 1.0;
  std::optional<Descriptor> descriptor;  // required when use_appearance
  // Robust 3D centroid of the instance in the world frame (metres), for the 3D gate; none when the
  // frame has no pose or the instance no valid depth.
  std::optional<Vec3> point_in_world;
};

enum class TrackState { kTentative, kConfirmed, kDeleted };

struct Track {
  int id = 0;      // internal id, 1, 2, ... in order of creation (tentative ones included)
  Gaussian state;  // Kalman state (cx, cy, a, h and velocities)
  TrackState track_state = TrackState::kTentative;
  int hits = 0;               // associated detections so far
  int age = 0;                // frames since creation
  int time_since_update = 0;  // frames since the last associated detection
  std::map<std::string, int> class_votes;
  std::deque<Descriptor> gallery;       // confirmed tracks' appearance samples (<= nn_budget)
  std::vector<Descriptor> new_samples;  // descriptors since the last gallery update
  // 3D positions of its latest detections that had one (newest last, <= gate_3d_history), and the
  // time of each (step's timestamp_s).
  std::deque<std::pair<double, Vec3>> points_in_world;
  std::string class_name() const;  // the majority class (ties: the smaller name)
  segmentation::Box predicted_box() const { return to_box(state.mean); }
};

// Where one detection went in a frame.
struct Association {
  int track_id = 0;        // internal track id; 0 = not tracked (score or height below the minimum)
  int hit = 0;             // 1-based hit number of that track (>= n_init: the track is confirmed)
  bool confirmed = false;  // the track is confirmed after this update (DeepSORT reports it)
};

// The online tracker: call step() once per frame, in time order.
class Tracker {
 public:
  explicit Tracker(const TrackerOptions& options = {});

  // Predicts every track one frame ahead, associates the detections, updates, creates and deletes
  // tracks. Returns one Association per detection. timestamp_s (the frame's time, seconds) is used
  // only by the 3D gate's growth with time (gate_3d_speed_mps).
  std::vector<Association> step(const std::vector<Detection>& detections, double timestamp_s = 0);

  const std::vector<Track>& tracks() const { return tracks_; }  // live tracks (not deleted)
  const TrackerOptions& options() const { return options_; }

 private:
  using Matches = std::vector<std::pair<int, int>>;  // (track index, detection index)
  void match(const std::vector<Detection>& detections, double timestamp_s, Matches& matches,
             std::vector<int>& unmatched_tracks, std::vector<int>& unmatched_detections) const;
  TrackerOptions options_;
  KalmanFilter kalman_;
  std::vector<Track> tracks_;
  int next_id_ = 1;
};

// Intersection over union of two boxes (0 when either is empty).
double box_iou(const segmentation::Box& a, const segmentation::Box& b);

}  // namespace objmap::track

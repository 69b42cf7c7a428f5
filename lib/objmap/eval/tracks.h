#pragma once
#include <cstddef>
#include <string>

#include "objmap/segmentation/types.h"

// Multi-object tracking metrics of a tracked segmentation against a ground-truth one
// (`objmap eval tracks`): CLEAR-MOT (Bernardin & Stiefelhagen 2008) — MOTA, MOTP, ID switches,
// fragmentations, mostly tracked / partially tracked / mostly lost — and the identity metrics of
// Ristani et al. 2016 (IDF1, IDP, IDR, from a global min-cost bipartite matching of trajectories).
// Conventions follow py-motmetrics. A ground-truth object is an instance's track_id; a hypothesis
// is an estimated instance with a track_id (estimated instances without one are not output of the
// tracker and are ignored, but counted).
namespace objmap::eval {

struct TrackEvalOptions {
  double min_iou = 0.5;         // a (gt, hypothesis) pair can match when IoU >= this; mask IoU
                                // when both have a mask of the same size, else box IoU
  bool same_class = false;      // also require the same class to match
  double mostly_tracked = 0.8;  // MT: matched in >= this share of the frames the object is in
  double mostly_lost = 0.2;     // ML: matched in <= this share
  double max_diff_s = 1e-4;     // a gt and an estimated frame are the same when their
                                // timestamps differ by at most this
  void check() const;           // throws InputError naming the bad field
};

struct TrackEvalResult {
  std::size_t frames = 0;                // ground-truth frames (the evaluated time steps)
  std::size_t est_frames_unmatched = 0;  // estimated frames with no ground-truth frame (ignored)
  std::size_t gt_instances = 0;          // ground-truth detections (num_objects)
  std::size_t est_instances = 0;         // hypotheses (estimated instances with a track id)
  std::size_t est_untracked = 0;         // estimated instances without track id (ignored)
  std::size_t matches = 0;               // true positives
  std::size_t misses = 0;                // false negatives
  std::size_t false_positives = 0;
  std::size_t id_switches = 0;     // a gt object matched to another hypothesis than last time
  std::size_t fragmentations = 0;  // tracked -> untracked transitions inside an object's span
  std::size_t gt_tracks = 0, est_tracks = 0;
  std::size_t mostly_tracked = 0, partially_tracked = 0, mostly_lost = 0;
  double mota = 0;  // 1 - (misses + false_positives + id_switches) / gt_instances (can be < 0)
  double motp = 0;  // mean IoU of the matched pairs, in [0, 1] (higher is better)
  std::size_t idtp = 0, idfp = 0, idfn = 0;
  double idf1 = 0, idp = 0, idr = 0;  // 2 IDTP / (2 IDTP + IDFP + IDFN), IDTP / (IDTP + IDFP), ..
  std::string gt_source, est_source;
};

// Frames are matched by timestamp; a ground-truth frame without an estimated frame has no
// hypothesis. Throws InputError when the ground truth has no frame or an instance without
// track_id.
TrackEvalResult evaluate_tracks(const segmentation::Segmentation& gt,
                                const segmentation::Segmentation& est,
                                const TrackEvalOptions& options = {});

// {"mota":..,"motp":..,"idf1":..,"idp":..,"idr":..,"id_switches":N,"fragmentations":N,
//  "matches":N,"misses":N,"false_positives":N,"gt_instances":N,"est_instances":N,
//  "est_untracked":N,"frames":N,"est_frames_unmatched":N,"gt_tracks":N,"est_tracks":N,
//  "mostly_tracked":N,"partially_tracked":N,"mostly_lost":N,"idtp":N,"idfp":N,"idfn":N,
//  "min_iou":..,"same_class":bool,"gt":..,"est":..} — deterministic.
std::string tracks_eval_json(const TrackEvalResult& result, const TrackEvalOptions& options);

// IoU of two instances as the metric uses it (mask IoU when both have same-size masks, else box).
double instance_iou(const segmentation::Instance& a, const segmentation::Instance& b);

}  // namespace objmap::eval

#include "objmap/track/tracker.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "objmap/core/error.h"
#include "objmap/track/assignment.h"

namespace objmap::track {

namespace {

constexpr double kInfiniteCost = 1e5;  // DeepSORT's INFTY_COST: a pair that may not match

using CostFn = std::function<Eigen::MatrixXd(const std::vector<int>& track_indices,
                                             const std::vector<int>& detection_indices)>;

// DeepSORT's min_cost_matching: costs above max_distance are capped just above it, the Hungarian
// method assigns, and pairs above max_distance are dropped. Appends to `matches`; returns the
// detections left unmatched (the tracks left are those of track_indices not in `matches`).
std::vector<int> min_cost_matching(const CostFn& cost_fn, double max_distance,
                                   const std::vector<int>& track_indices,
                                   const std::vector<int>& detection_indices,
                                   std::vector<std::pair<int, int>>& matches) {
  if (track_indices.empty() || detection_indices.empty()) return detection_indices;
  Eigen::MatrixXd cost = cost_fn(track_indices, detection_indices);
  cost = cost.cwiseMin(max_distance + 1e-5);
  const std::vector<int> row_to_col = solve_assignment(cost);
  std::vector<char> detection_matched(detection_indices.size(), 0);
  for (std::size_t r = 0; r < row_to_col.size(); ++r) {
    const int c = row_to_col[r];
    if (c < 0 || cost(r, c) > max_distance) continue;
    matches.emplace_back(track_indices[r], detection_indices[c]);
    detection_matched[c] = 1;
  }
  std::vector<int> unmatched;
  for (std::size_t c = 0; c < detection_indices.size(); ++c)
    if (!detection_matched[c]) unmatched.push_back(detection_indices[c]);
  return unmatched;
}

}  // namespace

void TrackerOptions::check() const {
  kalman.check();
  appearance.check();
  require(
      std::isfinite(max_cosine_distance) && max_cosine_distance >= 0 && max_cosine_distance <= 2,
      "TrackerOptions.max_cosine_distance",
      "must be in [0, 2], got " + std::to_string(max_cosine_distance));
  require(std::isfinite(lambda) && lambda >= 0 && lambda <= 1, "TrackerOptions.lambda",
          "must be in [0, 1], got " + std::to_string(lambda));
  require(std::isfinite(gating_threshold) && gating_threshold > 0,
          "TrackerOptions.gating_threshold",
          "must be > 0, got " + std::to_string(gating_threshold));
  require(std::isfinite(max_iou_distance) && max_iou_distance >= 0 && max_iou_distance <= 1,
          "TrackerOptions.max_iou_distance",
          "must be in [0, 1], got " + std::to_string(max_iou_distance));
  require(max_age >= 1, "TrackerOptions.max_age", "must be >= 1, got " + std::to_string(max_age));
  require(n_init >= 1, "TrackerOptions.n_init", "must be >= 1, got " + std::to_string(n_init));
  require(nn_budget >= 1, "TrackerOptions.nn_budget",
          "must be >= 1, got " + std::to_string(nn_budget));
  require(std::isfinite(min_score), "TrackerOptions.min_score", "must be finite");
  require(std::isfinite(min_height_px) && min_height_px >= 0, "TrackerOptions.min_height_px",
          "must be >= 0, got " + std::to_string(min_height_px));
  require(std::isfinite(gate_3d_m) && gate_3d_m > 0, "TrackerOptions.gate_3d_m",
          "must be > 0 metres, got " + std::to_string(gate_3d_m));
  require(std::isfinite(gate_3d_speed_mps) && gate_3d_speed_mps >= 0,
          "TrackerOptions.gate_3d_speed_mps",
          "must be >= 0 m/s, got " + std::to_string(gate_3d_speed_mps));
  require(gate_3d_history >= 1, "TrackerOptions.gate_3d_history",
          "must be >= 1, got " + std::to_string(gate_3d_history));
}

std::string Track::class_name() const {
  std::string best;
  int best_votes = -1;
  for (const auto& [name, votes] : class_votes)  // std::map: names in order, so ties -> smaller
    if (votes > best_votes) {
      best = name;
      best_votes = votes;
    }
  return best;
}

double box_iou(const segmentation::Box& a, const segmentation::Box& b) {
  const double iw = std::min(a.x + a.w, b.x + b.w) - std::max(a.x, b.x);
  const double ih = std::min(a.y + a.h, b.y + b.h) - std::max(a.y, b.y);
  if (iw <= 0 || ih <= 0) return 0.0;
  const double inter = iw * ih;
  const double uni = a.w * a.h + b.w * b.h - inter;
  return uni > 0 ? inter / uni : 0.0;
}

Tracker::Tracker(const TrackerOptions& options) : options_(options), kalman_(options.kalman) {
  options_.check();
}

void Tracker::match(const std::vector<Detection>& detections, double timestamp_s, Matches& matches,
                    std::vector<int>& unmatched_tracks,
                    std::vector<int>& unmatched_detections) const {
  // Class and 3D gates: a pair that fails either may not match in any stage.
  const auto pair_ok = [&](const Track& t, const Detection& d) {
    if (options_.same_class_only && t.class_name() != d.class_name) return false;
    if (!options_.use_gate_3d || t.points_in_world.empty() || !d.point_in_world) return true;
    for (const auto& [time_s, point] : t.points_in_world) {
      const double elapsed_s = std::max(0.0, timestamp_s - time_s);
      const double radius_m = std::max(options_.gate_3d_m, options_.gate_3d_speed_mps * elapsed_s);
      if ((*d.point_in_world - point).norm() <= radius_m) return true;
    }
    return false;
  };

  // Cascade cost (DeepSORT eqs 1-3, 5): appearance = smallest cosine distance to the track's
  // gallery, inadmissible when the squared Mahalanobis distance exceeds the chi-square gate.
  // Without appearance the Mahalanobis distance itself is the cost.
  const CostFn gated_metric = [&](const std::vector<int>& ti, const std::vector<int>& di) {
    Eigen::MatrixXd cost(ti.size(), di.size());
    std::vector<BoxMeasurement> zs;
    for (int d : di) zs.push_back(to_measurement(detections[d].box));
    for (std::size_t r = 0; r < ti.size(); ++r) {
      const Track& t = tracks_[ti[r]];
      const std::vector<double> maha = kalman_.gating_distance(t.state, zs);
      for (std::size_t c = 0; c < di.size(); ++c) {
        const Detection& d = detections[di[c]];
        double value = maha[c];
        bool admissible = maha[c] <= options_.gating_threshold && pair_ok(t, d);
        if (options_.use_appearance) {
          double cosine = 1.0;
          for (const Descriptor& sample : t.gallery)
            cosine = std::min(cosine, cosine_distance(sample, *d.descriptor));
          admissible = admissible && cosine <= options_.max_cosine_distance;
          value = options_.lambda * maha[c] + (1.0 - options_.lambda) * cosine;
        }
        if (!admissible) value = kInfiniteCost;
        cost(r, c) = value;
      }
    }
    return cost;
  };
  // IoU cost: 1 - IoU of the predicted box; only for tracks updated in the previous frame.
  const CostFn iou_cost = [&](const std::vector<int>& ti, const std::vector<int>& di) {
    Eigen::MatrixXd cost(ti.size(), di.size());
    for (std::size_t r = 0; r < ti.size(); ++r) {
      const Track& t = tracks_[ti[r]];
      const segmentation::Box predicted = t.predicted_box();
      for (std::size_t c = 0; c < di.size(); ++c) {
        const Detection& d = detections[di[c]];
        cost(r, c) = t.time_since_update > 1 || !pair_ok(t, d) ? kInfiniteCost
                                                               : 1.0 - box_iou(predicted, d.box);
      }
    }
    return cost;
  };

  std::vector<int> confirmed, unconfirmed;
  for (int i = 0; i < static_cast<int>(tracks_.size()); ++i)
    (tracks_[i].track_state == TrackState::kConfirmed ? confirmed : unconfirmed).push_back(i);

  // 1. Matching cascade over the confirmed tracks: the most recently seen first (time since
  //    update 1, 2, ..., max_age), each level a Hungarian assignment on what is left.
  std::vector<int> detections_left;
  for (int d = 0; d < static_cast<int>(detections.size()); ++d) detections_left.push_back(d);
  // Every admissible pair passes the threshold (the gates decided admissibility above).
  const double cascade_threshold = options_.use_appearance
                                       ? options_.lambda * options_.gating_threshold +
                                             (1.0 - options_.lambda) * options_.max_cosine_distance
                                       : options_.gating_threshold;
  for (int level = 0; level < options_.max_age && !detections_left.empty(); ++level) {
    std::vector<int> level_tracks;
    for (int t : confirmed)
      if (tracks_[t].time_since_update == 1 + level) level_tracks.push_back(t);
    detections_left =
        min_cost_matching(gated_metric, cascade_threshold, level_tracks, detections_left, matches);
  }
  std::vector<char> track_matched(tracks_.size(), 0);
  for (const auto& m : matches) track_matched[m.first] = 1;

  // 2. IoU matching of the tentative tracks and of the confirmed ones missed only in this frame.
  std::vector<int> iou_candidates = unconfirmed;
  for (int t : confirmed)
    if (!track_matched[t] && tracks_[t].time_since_update == 1) iou_candidates.push_back(t);
  std::sort(iou_candidates.begin(), iou_candidates.end());
  detections_left = min_cost_matching(iou_cost, options_.max_iou_distance, iou_candidates,
                                      detections_left, matches);
  for (const auto& m : matches) track_matched[m.first] = 1;

  unmatched_tracks.clear();
  for (int t = 0; t < static_cast<int>(tracks_.size()); ++t)
    if (!track_matched[t]) unmatched_tracks.push_back(t);
  unmatched_detections = detections_left;
}

std::vector<Association> Tracker::step(const std::vector<Detection>& all_detections,
                                       double timestamp_s) {
  // Detections that are tracked at all (score and height), with their index in the input.
  std::vector<Detection> detections;
  std::vector<int> input_index;
  for (std::size_t i = 0; i < all_detections.size(); ++i) {
    const Detection& d = all_detections[i];
    if (d.score < options_.min_score || d.box.h < options_.min_height_px || d.box.w <= 0 ||
        d.box.h <= 0)
      continue;
    require(!options_.use_appearance || d.descriptor.has_value(), "Tracker::step",
            "a detection has no appearance descriptor; expected one per detection when "
            "use_appearance is on");
    detections.push_back(d);
    input_index.push_back(static_cast<int>(i));
  }

  // Predict every track one frame ahead (eq 1).
  for (Track& t : tracks_) {
    kalman_.predict(t.state);
    ++t.age;
    ++t.time_since_update;
  }

  Matches matches;
  std::vector<int> unmatched_tracks, unmatched_detections;
  match(detections, timestamp_s, matches, unmatched_tracks, unmatched_detections);

  std::vector<Association> out(all_detections.size());
  const auto add_hit = [&](Track& t, const Detection& d, int detection) {
    ++t.hits;
    t.time_since_update = 0;
    ++t.class_votes[d.class_name];
    if (d.descriptor) t.new_samples.push_back(*d.descriptor);
    if (d.point_in_world) {
      t.points_in_world.emplace_back(timestamp_s, *d.point_in_world);
      while (static_cast<int>(t.points_in_world.size()) > options_.gate_3d_history)
        t.points_in_world.pop_front();
    }
    if (t.track_state == TrackState::kTentative && t.hits >= options_.n_init)
      t.track_state = TrackState::kConfirmed;
    Association& a = out[input_index[detection]];
    a.track_id = t.id;
    a.hit = t.hits;
    a.confirmed = t.track_state == TrackState::kConfirmed;
  };
  // Update the matched tracks with their detection.
  std::sort(matches.begin(), matches.end());
  for (const auto& [t, d] : matches) {
    kalman_.update(tracks_[t].state, to_measurement(detections[d].box));
    add_hit(tracks_[t], detections[d], d);
  }
  // Missed tracks: a tentative one is deleted at once, a confirmed one after max_age misses.
  for (int t : unmatched_tracks) {
    Track& track = tracks_[t];
    if (track.track_state == TrackState::kTentative || track.time_since_update > options_.max_age)
      track.track_state = TrackState::kDeleted;
  }
  // A new tentative track for every unmatched detection.
  for (int d : unmatched_detections) {
    Track t;
    t.id = next_id_++;
    t.state = kalman_.initiate(to_measurement(detections[d].box));
    t.age = 1;
    tracks_.push_back(std::move(t));
    add_hit(tracks_.back(), detections[d], d);
  }
  tracks_.erase(
      std::remove_if(tracks_.begin(), tracks_.end(),
                     [](const Track& t) { return t.track_state == TrackState::kDeleted; }),
      tracks_.end());
  // The appearance gallery of the confirmed tracks takes the new samples (newest nn_budget kept).
  for (Track& t : tracks_) {
    if (t.track_state != TrackState::kConfirmed) continue;
    for (Descriptor& s : t.new_samples) t.gallery.push_back(std::move(s));
    t.new_samples.clear();
    while (static_cast<int>(t.gallery.size()) > options_.nn_budget) t.gallery.pop_front();
  }
  return out;
}

}  // namespace objmap::track

#include "objmap/eval/tracks.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/track/assignment.h"  // the Hungarian method
#include "objmap/track/tracker.h"     // box_iou

namespace objmap::eval {

namespace {

using segmentation::Instance;
using segmentation::Mask;
using track::box_iou;

// A mask with its pixel count and tight pixel bounds [u0, u1) x [v0, v1), for fast IoU.
struct MaskInfo {
  const Mask* mask = nullptr;
  std::size_t area = 0;
  int u0 = 0, v0 = 0, u1 = 0, v1 = 0;
};

MaskInfo mask_info(const Instance& instance) {
  MaskInfo m;
  if (!instance.mask || instance.mask->empty()) return m;
  m.mask = &*instance.mask;
  m.u0 = m.mask->width, m.v0 = m.mask->height;
  for (int v = 0; v < m.mask->height; ++v)
    for (int u = 0; u < m.mask->width; ++u)
      if (m.mask->at(u, v)) {
        ++m.area;
        m.u0 = std::min(m.u0, u), m.u1 = std::max(m.u1, u + 1);
        m.v0 = std::min(m.v0, v), m.v1 = std::max(m.v1, v + 1);
      }
  return m;
}

double mask_iou(const MaskInfo& a, const MaskInfo& b) {
  const int u0 = std::max(a.u0, b.u0), u1 = std::min(a.u1, b.u1);
  const int v0 = std::max(a.v0, b.v0), v1 = std::min(a.v1, b.v1);
  std::size_t inter = 0;
  for (int v = v0; v < v1; ++v)
    for (int u = u0; u < u1; ++u) inter += a.mask->at(u, v) & b.mask->at(u, v);
  const std::size_t uni = a.area + b.area - inter;
  return uni > 0 ? static_cast<double>(inter) / static_cast<double>(uni) : 0.0;
}

bool same_size_masks(const MaskInfo& a, const MaskInfo& b) {
  return a.mask && b.mask && a.mask->width == b.mask->width && a.mask->height == b.mask->height;
}

double iou(const Instance& a, const MaskInfo& ma, const Instance& b, const MaskInfo& mb) {
  return same_size_masks(ma, mb) ? mask_iou(ma, mb) : box_iou(a.bbox, b.bbox);
}

}  // namespace

void TrackEvalOptions::check() const {
  require(std::isfinite(min_iou) && min_iou > 0 && min_iou <= 1, "TrackEvalOptions.min_iou",
          "must be in (0, 1], got " + std::to_string(min_iou));
  require(mostly_lost >= 0 && mostly_lost < mostly_tracked && mostly_tracked <= 1,
          "TrackEvalOptions.mostly_tracked", "expected 0 <= mostly_lost < mostly_tracked <= 1");
  require(std::isfinite(max_diff_s) && max_diff_s >= 0, "TrackEvalOptions.max_diff_s",
          "must be >= 0");
}

double instance_iou(const Instance& a, const Instance& b) {
  return iou(a, mask_info(a), b, mask_info(b));
}

namespace {

// The estimated frame of each ground-truth frame (by timestamp, both sorted); counts the
// estimated frames left over.
std::vector<const segmentation::FrameSegmentation*> estimated_frames(
    const segmentation::Segmentation& gt, const segmentation::Segmentation& est,
    const TrackEvalOptions& options, TrackEvalResult& r) {
  std::vector<const segmentation::FrameSegmentation*> est_of(gt.frames.size(), nullptr);
  std::size_t matched_est = 0;
  for (std::size_t g = 0, e = 0; g < gt.frames.size(); ++g) {
    while (e < est.frames.size() &&
           est.frames[e].timestamp < gt.frames[g].timestamp - options.max_diff_s)
      ++e;
    if (e < est.frames.size() &&
        std::abs(est.frames[e].timestamp - gt.frames[g].timestamp) <= options.max_diff_s) {
      est_of[g] = &est.frames[e++];
      ++matched_est;
    }
  }
  r.est_frames_unmatched = est.frames.size() - matched_est;
  return est_of;
}

struct GtTrack {
  std::size_t present = 0, matched = 0, fragments = 0;
  bool tracked_before = false, gap_open = false;
};

// What the frames add up for the summary.
struct TrackCounts {
  std::map<int, int> last_match;  // gt id -> hypothesis id it was last matched to
  std::map<int, GtTrack> gt_tracks;
  std::set<int> est_ids;
  std::map<int, std::size_t> gt_count, est_count;
  std::map<std::pair<int, int>, std::size_t> overlap;  // (gt id, hyp id) -> frames with IoU >= min
  double iou_sum = 0.0;
};

// One frame's ground-truth instances and tracked hypotheses, with their masks.
struct FrameInstances {
  std::vector<const Instance*> gts, hyps;
  std::vector<MaskInfo> gm, hm;
};

FrameInstances frame_instances(const segmentation::FrameSegmentation& gframe,
                               const segmentation::FrameSegmentation* est_frame,
                               const std::string& gt_where, TrackEvalResult& r) {
  FrameInstances fi;
  for (const Instance& inst : gframe.instances) {
    require(inst.track_id.has_value(), gframe.source.empty() ? gt_where : gframe.source,
            "a ground-truth instance has no track_id; expected the true object id in every "
            "instance");
    fi.gts.push_back(&inst);
  }
  if (est_frame)
    for (const Instance& inst : est_frame->instances) {
      if (inst.track_id)
        fi.hyps.push_back(&inst);
      else
        ++r.est_untracked;
    }
  r.gt_instances += fi.gts.size();
  r.est_instances += fi.hyps.size();
  for (const Instance* i : fi.gts) fi.gm.push_back(mask_info(*i));
  for (const Instance* i : fi.hyps) fi.hm.push_back(mask_info(*i));
  return fi;
}

struct FramePairs {
  Eigen::MatrixXd iou;                // gt x hypothesis
  std::vector<std::vector<char>> ok;  // admissible
};

// IoU of every pair; a pair is admissible at IoU >= min_iou (and the same class, if asked).
FramePairs pair_ious(const FrameInstances& fi, const TrackEvalOptions& options,
                     TrackCounts& counts) {
  const auto& gts = fi.gts;
  const auto& hyps = fi.hyps;
  FramePairs pairs;
  pairs.iou = Eigen::MatrixXd::Zero(gts.size(), hyps.size());
  pairs.ok.assign(gts.size(), std::vector<char>(hyps.size(), 0));
  for (std::size_t i = 0; i < gts.size(); ++i)
    for (std::size_t j = 0; j < hyps.size(); ++j) {
      if (options.same_class && gts[i]->class_name != hyps[j]->class_name) continue;
      if (box_iou(gts[i]->bbox, hyps[j]->bbox) <= 0 && !same_size_masks(fi.gm[i], fi.hm[j]))
        continue;
      pairs.iou(i, j) = iou(*gts[i], fi.gm[i], *hyps[j], fi.hm[j]);
      pairs.ok[i][j] = pairs.iou(i, j) >= options.min_iou;
      if (pairs.ok[i][j]) ++counts.overlap[{*gts[i]->track_id, *hyps[j]->track_id}];
    }
  for (const Instance* i : gts) ++counts.gt_count[*i->track_id];
  for (const Instance* j : hyps) {
    ++counts.est_count[*j->track_id];
    counts.est_ids.insert(*j->track_id);
  }
  return pairs;
}

struct FrameMatch {
  std::vector<int> gt_to_hyp, hyp_to_gt;  // -1: unmatched
};

// Keep last frame's correspondences that are still admissible (CLEAR-MOT).
FrameMatch keep_last_matches(const FrameInstances& fi, const FramePairs& pairs,
                             const TrackCounts& counts) {
  const auto& gts = fi.gts;
  const auto& hyps = fi.hyps;
  FrameMatch m{std::vector<int>(gts.size(), -1), std::vector<int>(hyps.size(), -1)};
  for (std::size_t i = 0; i < gts.size(); ++i) {
    const auto last = counts.last_match.find(*gts[i]->track_id);
    if (last == counts.last_match.end()) continue;
    for (std::size_t j = 0; j < hyps.size(); ++j)
      if (m.hyp_to_gt[j] < 0 && *hyps[j]->track_id == last->second && pairs.ok[i][j]) {
        m.gt_to_hyp[i] = static_cast<int>(j);
        m.hyp_to_gt[j] = static_cast<int>(i);
        break;
      }
  }
  return m;
}

// The rest by minimum total 1 - IoU over the admissible pairs (Hungarian method); a gt object
// matched to another hypothesis than last time is an identity switch.
void match_the_rest(const FrameInstances& fi, const FramePairs& pairs, const TrackCounts& counts,
                    FrameMatch& m, TrackEvalResult& r) {
  std::vector<int> free_g, free_h;
  for (std::size_t i = 0; i < fi.gts.size(); ++i)
    if (m.gt_to_hyp[i] < 0) free_g.push_back(static_cast<int>(i));
  for (std::size_t j = 0; j < fi.hyps.size(); ++j)
    if (m.hyp_to_gt[j] < 0) free_h.push_back(static_cast<int>(j));
  if (free_g.empty() || free_h.empty()) return;
  constexpr double kForbidden = 1e6;
  Eigen::MatrixXd cost(free_g.size(), free_h.size());
  for (std::size_t a = 0; a < free_g.size(); ++a)
    for (std::size_t b = 0; b < free_h.size(); ++b)
      cost(a, b) =
          pairs.ok[free_g[a]][free_h[b]] ? 1.0 - pairs.iou(free_g[a], free_h[b]) : kForbidden;
  const std::vector<int> assigned = track::solve_assignment(cost);
  for (std::size_t a = 0; a < free_g.size(); ++a) {
    if (assigned[a] < 0 || cost(a, assigned[a]) >= kForbidden) continue;
    const int i = free_g[a], j = free_h[assigned[a]];
    m.gt_to_hyp[i] = j;
    m.hyp_to_gt[j] = i;
    const int gid = *fi.gts[i]->track_id, hid = *fi.hyps[j]->track_id;
    const auto last = counts.last_match.find(gid);
    if (last != counts.last_match.end() && last->second != hid) ++r.id_switches;
  }
}

// Count matches, misses, false positives and the fragments of each gt track.
void count_frame(const FrameInstances& fi, const FramePairs& pairs, const FrameMatch& m,
                 TrackCounts& counts, TrackEvalResult& r) {
  for (std::size_t i = 0; i < fi.gts.size(); ++i) {
    GtTrack& t = counts.gt_tracks[*fi.gts[i]->track_id];
    ++t.present;
    if (m.gt_to_hyp[i] >= 0) {
      ++r.matches;
      ++t.matched;
      counts.iou_sum += pairs.iou(i, m.gt_to_hyp[i]);
      counts.last_match[*fi.gts[i]->track_id] = *fi.hyps[m.gt_to_hyp[i]]->track_id;
      if (t.gap_open) ++t.fragments;  // resumed after an interruption
      t.tracked_before = true;
      t.gap_open = false;
    } else {
      ++r.misses;
      if (t.tracked_before) t.gap_open = true;
    }
  }
  for (std::size_t j = 0; j < fi.hyps.size(); ++j)
    if (m.hyp_to_gt[j] < 0) ++r.false_positives;
}

// CLEAR-MOT summary: MOTA, MOTP, mostly tracked / partially tracked / mostly lost.
void clear_mot_summary(const TrackCounts& counts, const TrackEvalOptions& options,
                       TrackEvalResult& r) {
  r.gt_tracks = counts.gt_tracks.size();
  r.est_tracks = counts.est_ids.size();
  for (const auto& [id, t] : counts.gt_tracks) {
    r.fragmentations += t.fragments;
    const double ratio = static_cast<double>(t.matched) / static_cast<double>(t.present);
    if (ratio >= options.mostly_tracked)
      ++r.mostly_tracked;
    else if (ratio <= options.mostly_lost)
      ++r.mostly_lost;
    else
      ++r.partially_tracked;
  }
  r.mota = r.gt_instances == 0
               ? 0.0
               : 1.0 - static_cast<double>(r.misses + r.false_positives + r.id_switches) /
                           static_cast<double>(r.gt_instances);
  r.motp = r.matches == 0 ? 0.0 : counts.iou_sum / static_cast<double>(r.matches);
}

// Identity metrics: the one-to-one trajectory matching that maximises the frames where a gt
// object and its hypothesis overlap (IDTP) — the min-cost bipartite matching of Ristani et al.,
// since IDFN + IDFP = (gt + hypotheses) - 2 IDTP.
void identity_metrics(const TrackCounts& counts, TrackEvalResult& r) {
  std::vector<int> gt_ids, hyp_ids;
  for (const auto& [id, n] : counts.gt_count) gt_ids.push_back(id);
  for (const auto& [id, n] : counts.est_count) hyp_ids.push_back(id);
  if (!gt_ids.empty() && !hyp_ids.empty()) {
    std::map<int, int> hyp_index;
    for (std::size_t j = 0; j < hyp_ids.size(); ++j) hyp_index[hyp_ids[j]] = static_cast<int>(j);
    std::map<int, int> gt_index;
    for (std::size_t i = 0; i < gt_ids.size(); ++i) gt_index[gt_ids[i]] = static_cast<int>(i);
    Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(gt_ids.size(), hyp_ids.size());
    for (const auto& [pair, n] : counts.overlap)
      cost(gt_index[pair.first], hyp_index[pair.second]) = -static_cast<double>(n);
    const std::vector<int> assigned = track::solve_assignment(cost);
    for (std::size_t i = 0; i < assigned.size(); ++i)
      if (assigned[i] >= 0) r.idtp += static_cast<std::size_t>(-cost(i, assigned[i]));
  }
  r.idfn = r.gt_instances - r.idtp;
  r.idfp = r.est_instances - r.idtp;
  const double denominator = static_cast<double>(r.gt_instances + r.est_instances);
  r.idf1 = denominator > 0 ? 2.0 * static_cast<double>(r.idtp) / denominator : 0.0;
  r.idp =
      r.est_instances ? static_cast<double>(r.idtp) / static_cast<double>(r.est_instances) : 0.0;
  r.idr = r.gt_instances ? static_cast<double>(r.idtp) / static_cast<double>(r.gt_instances) : 0.0;
}

}  // namespace

TrackEvalResult evaluate_tracks(const segmentation::Segmentation& gt,
                                const segmentation::Segmentation& est,
                                const TrackEvalOptions& options) {
  options.check();
  TrackEvalResult r;
  r.gt_source = gt.source;
  r.est_source = est.source;
  const std::string gt_where = gt.source.empty() ? "ground truth" : gt.source;
  require(!gt.frames.empty(), gt_where, "no frame; expected a ground-truth segmentation");
  r.frames = gt.frames.size();

  // 1. The estimated frame of each ground-truth frame (by timestamp).
  const std::vector<const segmentation::FrameSegmentation*> est_of =
      estimated_frames(gt, est, options, r);

  // 2. Per frame: the instances, their IoU, the CLEAR-MOT correspondences and their counts.
  TrackCounts counts;
  for (std::size_t f = 0; f < gt.frames.size(); ++f) {
    const FrameInstances instances = frame_instances(gt.frames[f], est_of[f], gt_where, r);
    const FramePairs pairs = pair_ious(instances, options, counts);
    FrameMatch match = keep_last_matches(instances, pairs, counts);
    match_the_rest(instances, pairs, counts, match, r);
    count_frame(instances, pairs, match, counts, r);
  }

  // 3. CLEAR-MOT summary.
  clear_mot_summary(counts, options, r);

  // 4. Identity metrics.
  identity_metrics(counts, r);
  return r;
}

std::string tracks_eval_json(const TrackEvalResult& r, const TrackEvalOptions& options) {
  nlohmann::ordered_json out;
  out["mota"] = r.mota;
  out["motp"] = r.motp;
  out["idf1"] = r.idf1;
  out["idp"] = r.idp;
  out["idr"] = r.idr;
  out["id_switches"] = r.id_switches;
  out["fragmentations"] = r.fragmentations;
  out["matches"] = r.matches;
  out["misses"] = r.misses;
  out["false_positives"] = r.false_positives;
  out["gt_instances"] = r.gt_instances;
  out["est_instances"] = r.est_instances;
  out["est_untracked"] = r.est_untracked;
  out["frames"] = r.frames;
  out["est_frames_unmatched"] = r.est_frames_unmatched;
  out["gt_tracks"] = r.gt_tracks;
  out["est_tracks"] = r.est_tracks;
  out["mostly_tracked"] = r.mostly_tracked;
  out["partially_tracked"] = r.partially_tracked;
  out["mostly_lost"] = r.mostly_lost;
  out["idtp"] = r.idtp;
  out["idfp"] = r.idfp;
  out["idfn"] = r.idfn;
  out["min_iou"] = options.min_iou;
  out["same_class"] = options.same_class;
  out["gt"] = r.gt_source;
  out["est"] = r.est_source;
  return out.dump(2) + "\n";
}

}  // namespace objmap::eval

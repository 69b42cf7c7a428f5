#include "objmap/eval/associate.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

#include "objmap/core/error.h"
#include "objmap/core/format.h"

namespace objmap::eval {

void AssociateOptions::check() const {
  require(std::isfinite(max_diff_s) && max_diff_s > 0.0, "AssociateOptions.max_diff_s",
          "is " + number_text(max_diff_s) + "; expected a finite number of seconds > 0");
  require(std::isfinite(offset_s), "AssociateOptions.offset_s",
          "is " + number_text(offset_s) + "; expected a finite number of seconds");
}

std::vector<StampMatch> associate(const std::vector<double>& gt_stamps,
                                  const std::vector<double>& est_stamps,
                                  const AssociateOptions& options) {
  options.check();
  // The estimate's stamps in increasing order, so that the candidates of one gt stamp are a range.
  std::vector<std::size_t> est_order(est_stamps.size());
  std::iota(est_order.begin(), est_order.end(), std::size_t{0});
  std::stable_sort(est_order.begin(), est_order.end(),
                   [&](std::size_t a, std::size_t b) { return est_stamps[a] < est_stamps[b]; });

  // 1. Candidates: |a − (b + offset)| < max_diff, computed in the same floating-point steps as
  //    associate.py. The range is searched with twice the tolerance and then filtered exactly.
  struct Candidate {
    double diff, gt_stamp, est_stamp;
    std::size_t gt_index, est_index;
  };
  std::vector<Candidate> candidates;
  for (std::size_t g = 0; g < gt_stamps.size(); ++g) {
    const double a = gt_stamps[g];
    const double low = a - options.offset_s - 2.0 * options.max_diff_s;
    const double high = a - options.offset_s + 2.0 * options.max_diff_s;
    auto it = std::lower_bound(est_order.begin(), est_order.end(), low,
                               [&](std::size_t e, double t) { return est_stamps[e] < t; });
    for (; it != est_order.end() && est_stamps[*it] <= high; ++it) {
      const double b = est_stamps[*it];
      const double diff = std::abs(a - (b + options.offset_s));
      if (diff < options.max_diff_s) candidates.push_back({diff, a, b, g, *it});
    }
  }
  // 2. Greedy one-to-one by increasing difference (Python sorts the tuples (diff, a, b)).
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return std::tie(x.diff, x.gt_stamp, x.est_stamp, x.gt_index, x.est_index) <
           std::tie(y.diff, y.gt_stamp, y.est_stamp, y.gt_index, y.est_index);
  });
  std::vector<bool> gt_used(gt_stamps.size(), false), est_used(est_stamps.size(), false);
  std::vector<StampMatch> matches;
  for (const Candidate& c : candidates) {
    if (gt_used[c.gt_index] || est_used[c.est_index]) continue;
    gt_used[c.gt_index] = est_used[c.est_index] = true;
    matches.push_back({c.gt_index, c.est_index});
  }
  // 3. Sorted by time (gt stamp, then est stamp), as matches.sort().
  std::sort(matches.begin(), matches.end(), [&](const StampMatch& x, const StampMatch& y) {
    return std::make_pair(gt_stamps[x.gt_index], est_stamps[x.est_index]) <
           std::make_pair(gt_stamps[y.gt_index], est_stamps[y.est_index]);
  });
  return matches;
}

namespace {
std::vector<double> stamps_of(const Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const StampedPose& p : trajectory.poses) stamps.push_back(p.timestamp);
  return stamps;
}

std::string span_of(const Trajectory& trajectory) {
  if (trajectory.empty()) return "no poses";
  return std::to_string(trajectory.size()) + " poses, " +
         fixed_text(trajectory.poses.front().timestamp, 4) + " .. " +
         fixed_text(trajectory.poses.back().timestamp, 4) + " s";
}
}  // namespace

std::vector<StampMatch> associate(const Trajectory& gt, const Trajectory& est,
                                  const AssociateOptions& options) {
  return associate(stamps_of(gt), stamps_of(est), options);
}

void require_plausible_positions(const Trajectory& trajectory,
                                 const std::vector<std::size_t>& indices) {
  for (std::size_t i : indices) {
    const StampedPose& p = trajectory.poses[i];
    // The largest coordinate (the norm itself would overflow for such a pose).
    const double distance = p.world_from_cam.translation().cwiseAbs().maxCoeff();
    if (distance <= kMaxPositionM) continue;
    const std::string file =
        trajectory.source.empty() ? std::string("trajectory") : trajectory.source;
    throw InputError(p.line ? file + ":" + std::to_string(p.line) : file,
                     "the pose at " + number_text(p.timestamp) + " has a coordinate of " +
                         number_text(distance) + " m; expected positions in metres within " +
                         number_text(kMaxPositionM) + " m (its squares overflow the evaluation)");
  }
}

void require_pairs(const std::vector<StampMatch>& matches, std::size_t min_pairs,
                   const Trajectory& gt, const Trajectory& est, const AssociateOptions& options) {
  if (matches.size() >= min_pairs) return;
  const std::string what = matches.empty()
                               ? std::string("no pose pairs")
                               : "only " + std::to_string(matches.size()) +
                                     (matches.size() == 1 ? " pose pair" : " pose pairs");
  throw InputError(est.source.empty() ? std::string("estimate") : est.source,
                   what + " within max_diff " + number_text(options.max_diff_s) +
                       " s of the ground truth (estimate: " + span_of(est) + "; ground truth " +
                       (gt.source.empty() ? std::string() : gt.source + ": ") + span_of(gt) +
                       "; offset " + number_text(options.offset_s) + " s); expected at least " +
                       std::to_string(min_pairs) +
                       " — are they the same sequence, is --offset right?");
}

}  // namespace objmap::eval

#include "objmap/eval/rpe.h"

#include <algorithm>
#include <cmath>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/eval/associate.h"

namespace objmap::eval {

namespace {

constexpr double kPi = 3.14159265358979323846;

// The script's ominus(a, b) = a⁻¹ b.
Pose ominus(const Pose& a, const Pose& b) { return a.inverse(Eigen::Isometry) * b; }

double distance_of(const Pose& transform) { return transform.translation().norm(); }

// "an invitation to 3-d vision, p 27": arccos((trace R − 1) / 2), clamped to [-1, 1].
double angle_of(const Pose& transform) {
  return std::acos(std::min(1.0, std::max(-1.0, (transform.linear().trace() - 1.0) / 2.0)));
}

std::vector<double> stamps_of(const Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const StampedPose& p : trajectory.poses) stamps.push_back(p.timestamp);
  return stamps;
}

// The value of each estimate pose along which delta is measured (the script's index_est).
std::vector<double> index_along(const Trajectory& est, DeltaUnit unit) {
  std::vector<double> index;
  index.reserve(est.size());
  if (unit == DeltaUnit::kSeconds) return stamps_of(est);
  if (unit == DeltaUnit::kFrames) {
    for (std::size_t i = 0; i < est.size(); ++i) index.push_back(static_cast<double>(i));
    return index;
  }
  // Travelled distance or accumulated rotation: running sums over the motions
  // ominus(pose[i+1], pose[i]) (distances_along_trajectory / rotations_along_trajectory).
  const double factor = unit == DeltaUnit::kDegrees ? 180.0 / kPi : 1.0;
  double sum = 0.0;
  index.push_back(0.0);
  for (std::size_t i = 0; i + 1 < est.size(); ++i) {
    const Pose motion = ominus(est.poses[i + 1].world_from_cam, est.poses[i].world_from_cam);
    sum += unit == DeltaUnit::kMetres ? distance_of(motion) : angle_of(motion) * factor;
    index.push_back(sum);
  }
  return index;
}

double median_interval(const std::vector<double>& stamps) {
  std::vector<double> intervals;
  for (std::size_t i = 1; i < stamps.size(); ++i) intervals.push_back(stamps[i] - stamps[i - 1]);
  return compute_stats(intervals).median;
}

}  // namespace

DeltaUnit parse_delta_unit(const std::string& text) {
  if (text == "s") return DeltaUnit::kSeconds;
  if (text == "m") return DeltaUnit::kMetres;
  if (text == "rad") return DeltaUnit::kRadians;
  if (text == "deg") return DeltaUnit::kDegrees;
  if (text == "f") return DeltaUnit::kFrames;
  throw InputError("--delta-unit", "unknown unit '" + text +
                                       "'; expected s (seconds), m (metres travelled), rad or deg "
                                       "(rotation accumulated) or f (frames)");
}

std::string to_string(DeltaUnit unit) {
  switch (unit) {
    case DeltaUnit::kSeconds:
      return "s";
    case DeltaUnit::kMetres:
      return "m";
    case DeltaUnit::kRadians:
      return "rad";
    case DeltaUnit::kDegrees:
      return "deg";
    case DeltaUnit::kFrames:
      return "f";
  }
  return "?";
}

void RpeOptions::check() const {
  require(std::isfinite(delta) && delta > 0.0, "RpeOptions.delta",
          "is " + number_text(delta) + "; expected a finite number > 0 (in " +
              to_string(delta_unit) + ")");
  require(std::isfinite(offset_s), "RpeOptions.offset_s",
          "is " + number_text(offset_s) + "; expected a finite number of seconds");
  if (max_diff_s)
    require(std::isfinite(*max_diff_s) && *max_diff_s > 0.0, "RpeOptions.max_diff_s",
            "is " + number_text(*max_diff_s) + "; expected a finite number of seconds > 0");
}

std::size_t find_closest_index(const std::vector<double>& sorted, double value) {
  require(!sorted.empty(), "find_closest_index", "empty list; expected at least one value");
  std::size_t beginning = 0, end = sorted.size(), best = 0;
  double difference = std::abs(sorted[0] - value);
  while (beginning < end) {
    const std::size_t middle = (end + beginning) / 2;
    if (std::abs(sorted[middle] - value) < difference) {
      difference = std::abs(sorted[middle] - value);
      best = middle;
    }
    if (value == sorted[middle]) return middle;
    if (sorted[middle] > value)
      end = middle;
    else
      beginning = middle + 1;
  }
  return best;
}

RpeResult evaluate_rpe(const Trajectory& gt, const Trajectory& est, const RpeOptions& options) {
  options.check();
  const auto name = [](const Trajectory& t, const char* fallback) {
    return t.source.empty() ? std::string(fallback) : t.source;
  };
  require(est.size() >= 2, name(est, "estimate"),
          std::to_string(est.size()) + " pose; expected at least 2 for relative poses");
  require(gt.size() >= 2, name(gt, "ground truth"),
          std::to_string(gt.size()) + " pose; expected at least 2 for relative poses");
  const std::vector<double> stamps_gt = stamps_of(gt);
  const std::vector<double> stamps_est = stamps_of(est);
  const auto all = [](const Trajectory& t) {
    std::vector<std::size_t> i(t.size());
    for (std::size_t k = 0; k < i.size(); ++k) i[k] = k;
    return i;
  };
  require_plausible_positions(gt, all(gt));
  require_plausible_positions(est, all(est));

  RpeResult result;
  result.gt_source = gt.source;
  result.est_source = est.source;
  result.max_diff_s = options.max_diff_s ? *options.max_diff_s : 2.0 * median_interval(stamps_gt);

  // 1. Pairs (i, j): j is the estimate pose closest to i's index + delta; the script drops the
  //    pairs whose j is the estimate's last pose.
  const std::vector<double> index_est = index_along(est, options.delta_unit);
  std::vector<std::pair<std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const std::size_t j = find_closest_index(index_est, index_est[i] + options.delta);
    if (j != est.size() - 1) candidates.emplace_back(i, j);
  }

  // 2. Each end matched to the nearest ground-truth stamp, within max_diff; 3. the error.
  std::vector<double> translational, rotational_deg;
  for (const auto& [i, j] : candidates) {
    const double t_i = stamps_est[i] + options.offset_s;
    const double t_j = stamps_est[j] + options.offset_s;
    const std::size_t g_i = find_closest_index(stamps_gt, t_i);
    const std::size_t g_j = find_closest_index(stamps_gt, t_j);
    if (std::abs(stamps_gt[g_i] - t_i) > result.max_diff_s ||
        std::abs(stamps_gt[g_j] - t_j) > result.max_diff_s)
      continue;
    const Pose est_motion = ominus(est.poses[j].world_from_cam, est.poses[i].world_from_cam);
    const Pose gt_motion = ominus(gt.poses[g_j].world_from_cam, gt.poses[g_i].world_from_cam);
    const Pose error = ominus(est_motion, gt_motion);
    RpePair pair;
    pair.est_index_i = i;
    pair.est_index_j = j;
    pair.gt_index_i = g_i;
    pair.gt_index_j = g_j;
    pair.translational_m = distance_of(error);
    pair.rotational_rad = angle_of(error);
    result.pairs.push_back(pair);
    translational.push_back(pair.translational_m);
    rotational_deg.push_back(pair.rotational_rad * 180.0 / kPi);
  }
  if (result.pairs.size() < 2)
    throw InputError(
        name(est, "estimate"),
        (result.pairs.empty() ? std::string("no pose pairs")
                              : "only " + std::to_string(result.pairs.size()) + " pose pair") +
            " within max_diff " + number_text(result.max_diff_s) + " s of a ground-truth stamp (" +
            std::to_string(candidates.size()) + " pairs at delta " + number_text(options.delta) +
            " " + to_string(options.delta_unit) + ", ground truth " + name(gt, "(unnamed)") +
            ", offset " + number_text(options.offset_s) +
            " s); expected at least 2 — are they the same sequence, is delta too large?");
  result.translational_m = compute_stats(translational);
  result.rotational_deg = compute_stats(rotational_deg);
  return result;
}

}  // namespace objmap::eval

#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/trajectory.h"
#include "objmap/eval/stats.h"

// Relative pose error as the TUM RGB-D benchmark's evaluate_rpe.py with --fixed_delta:
//  - for each estimate pose i, j is the estimate pose whose index (unit f), time (s), travelled
//    distance (m) or accumulated rotation (rad, deg) is closest to i's plus delta; the pair is
//    dropped when j is the last pose of the estimate (as the script does);
//  - each end is matched to the nearest ground-truth stamp (of t_est + offset); the pair is dropped
//    when either match is more than max_diff away (the script: 2 × the median ground-truth
//    interval);
//  - error E = (est_i⁻¹ est_j) · (gt_i⁻¹ gt_j)⁻¹, i.e. the script's
//    ominus(ominus(est_j, est_i), ominus(gt_j, gt_i)) with ominus(a, b) = a⁻¹ b;
//    translational error ‖t(E)‖ (metres), rotational error arccos((tr R(E) − 1) / 2).
namespace objmap::eval {

enum class DeltaUnit { kSeconds, kMetres, kRadians, kDegrees, kFrames };

// "s", "m", "rad", "deg", "f" (evaluate_rpe.py's names). Throws InputError("--delta-unit", ...) for
// any other text.
DeltaUnit parse_delta_unit(const std::string& text);
std::string to_string(DeltaUnit unit);

struct RpeOptions {
  double delta = 1.0;                          // evaluate_rpe.py --delta; finite, > 0
  DeltaUnit delta_unit = DeltaUnit::kSeconds;  // evaluate_rpe.py --delta_unit (default s)
  double offset_s = 0.0;                       // added to the estimate's stamps (--offset)
  std::optional<double> max_diff_s;  // largest |t_gt − (t_est + offset)| of a pair's ends;
                                     // unset: 2 × the median ground-truth interval (script)
  void check() const;                // throws InputError naming the bad field
};

// One compared pair of estimate poses (i, j) and the ground-truth poses matched to them.
struct RpePair {
  std::size_t est_index_i = 0, est_index_j = 0;
  std::size_t gt_index_i = 0, gt_index_j = 0;
  double translational_m = 0.0;
  double rotational_rad = 0.0;
};

struct RpeResult {
  std::string gt_source, est_source;  // the trajectories' files, for reports
  std::vector<RpePair> pairs;         // in the order of the estimate's poses i
  ErrorStats translational_m;         // statistics of the translational errors, metres
  ErrorStats rotational_deg;          // statistics of the rotational errors, degrees
  double max_diff_s = 0.0;  // the stamp tolerance used (options.max_diff_s or the script's)
};

// Throws InputError when either trajectory has fewer than 2 poses or fewer than 2 pairs remain
// ("no pose pairs within max_diff ...").
RpeResult evaluate_rpe(const Trajectory& gt, const Trajectory& est, const RpeOptions& options);

// evaluate_rpe.py's find_closest_index, literally (a binary search that keeps the closest value
// visited; on ties the first one visited). `sorted` must be increasing;
// an empty list is an InputError.
std::size_t find_closest_index(const std::vector<double>& sorted, double value);

}  // namespace objmap::eval

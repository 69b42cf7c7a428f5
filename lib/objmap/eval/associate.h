#pragma once
#include <cstddef>
#include <vector>

#include "objmap/core/trajectory.h"

// Timestamp association of two trajectories exactly as the TUM RGB-D benchmark's associate.py (used
// by evaluate_ate.py): every (gt, est) stamp pair with |t_gt − (t_est + offset)| < max_diff is a
// candidate; candidates are taken greedily by increasing difference (ties: earlier gt stamp, then
// earlier est stamp), each stamp at most once; the matches are returned sorted by gt stamp.
namespace objmap::eval {

struct AssociateOptions {
  double max_diff_s = 0.02;  // a pair needs |t_gt − (t_est + offset_s)| < max_diff_s; finite, > 0
  double offset_s = 0.0;     // added to every estimate stamp (associate.py --offset); finite
  void check() const;        // throws InputError naming the bad field
};

// One matched pair: indices into the two stamp lists (or the poses of the two trajectories).
struct StampMatch {
  std::size_t gt_index = 0;
  std::size_t est_index = 0;
};

// Stamps in any order (each list without duplicates, as associate.py's dict keys).
std::vector<StampMatch> associate(const std::vector<double>& gt_stamps,
                                  const std::vector<double>& est_stamps,
                                  const AssociateOptions& options);

std::vector<StampMatch> associate(const Trajectory& gt, const Trajectory& est,
                                  const AssociateOptions& options);

// A position with a coordinate beyond this is no camera trajectory in metres: its square
// overflows the alignment's sums (a pose at 1e300 gave an ATE of inf / nan).
constexpr double kMaxPositionM = 1e6;

// Throws InputError("<file>:<line>", ...) for the first pose of `trajectory` among `indices` whose
// position is farther than kMaxPositionM from the origin.
void require_plausible_positions(const Trajectory& trajectory,
                                 const std::vector<std::size_t>& indices);

// Throws InputError(est.source, "no pose pairs within max_diff ...") when `matches` has fewer than
// `min_pairs` pairs (evaluate_ate.py needs 2); the message gives both time spans and the offset.
void require_pairs(const std::vector<StampMatch>& matches, std::size_t min_pairs,
                   const Trajectory& gt, const Trajectory& est, const AssociateOptions& options);

}  // namespace objmap::eval

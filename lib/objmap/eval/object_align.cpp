// eval objects --align: the map brought into the reference's frame by a rigid transform, from the
// trajectories (eval ate's alignment) or from the objects themselves.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "objmap/core/error.h"
#include "objmap/eval/objects.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::eval {

std::vector<io::MappedObject> transform_objects(const std::vector<io::MappedObject>& objects,
                                                const Similarity& transform) {
  std::vector<io::MappedObject> out = objects;
  for (io::MappedObject& o : out) {
    o.centroid = transform * o.centroid;
    o.position = transform * o.position;
    o.obb.center = transform * o.obb.center;
    o.obb.rotation = transform.rotation * o.obb.rotation;
    o.obb.half_extent *= transform.scale;
    Aabb box{Vec3::Constant(std::numeric_limits<double>::infinity()),
             Vec3::Constant(-std::numeric_limits<double>::infinity())};
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? o.aabb.max.x() : o.aabb.min.x(),
                   (corner & 2) ? o.aabb.max.y() : o.aabb.min.y(),
                   (corner & 4) ? o.aabb.max.z() : o.aabb.min.z());
      box.min = box.min.cwiseMin(transform * p);
      box.max = box.max.cwiseMax(transform * p);
    }
    o.aabb = box;
  }
  return out;
}

ObjectAlignment align_by_trajectories(const Trajectory& gt, const Trajectory& est) {
  const AteResult ate = evaluate_ate(gt, est, AteOptions{});
  ObjectAlignment a;
  a.method = "trajectory";
  a.reference_from_map = ate.gt_from_est;
  a.pairs = ate.matches.size();
  a.rmse_m = ate.stats.rmse;
  a.gt_trajectory = gt.source;
  a.trajectory = est.source;
  return a;
}

namespace {

// A (map, reference) pair of objects of the same canonical class: a possible correspondence.
struct Candidate {
  std::size_t map = 0, ref = 0;
};

struct Points {
  std::vector<Vec3> map, ref;  // the objects' centroids
};

std::vector<Candidate> same_class_candidates(const std::vector<io::MappedObject>& map,
                                             const std::vector<ReferenceObject>& reference) {
  std::vector<std::string> map_class, ref_class;
  for (const auto& o : map) map_class.push_back(segmentation::canonical_class(o.class_name));
  for (const auto& r : reference) ref_class.push_back(segmentation::canonical_class(r.class_name));
  std::vector<Candidate> out;
  for (std::size_t i = 0; i < map.size(); ++i)
    for (std::size_t j = 0; j < reference.size(); ++j)
      if (map_class[i] == ref_class[j]) out.push_back({i, j});
  return out;
}

// How well a transform fits: the reference objects with a same-class map object within the gate
// (not one-to-one), and the sum of those nearest distances.
struct Fit {
  std::size_t inliers = 0;
  double distance_sum = 0.0;
  bool better_than(const Fit& other) const {
    return inliers != other.inliers ? inliers > other.inliers
                                    : distance_sum < other.distance_sum - 1e-12;
  }
};

Fit fit_of(const Similarity& t, const std::vector<Candidate>& candidates, const Points& points,
           double gate_m) {
  std::vector<double> nearest(points.ref.size(), std::numeric_limits<double>::infinity());
  for (const Candidate& c : candidates) {
    const double d = (t * points.map[c.map] - points.ref[c.ref]).norm();
    if (d <= gate_m) nearest[c.ref] = std::min(nearest[c.ref], d);
  }
  Fit fit;
  for (const double d : nearest)
    if (std::isfinite(d)) {
      ++fit.inliers;
      fit.distance_sum += d;
    }
  return fit;
}

// Two candidates can both be right: different objects on each side, and the distance between
// the two map objects equals the one between the two reference objects within `tolerance`.
bool consistent(const Candidate& a, const Candidate& b, const Points& p, double tolerance) {
  if (a.map == b.map || a.ref == b.ref) return false;
  const double dm = (p.map[a.map] - p.map[b.map]).norm();
  const double dr = (p.ref[a.ref] - p.ref[b.ref]).norm();
  return std::abs(dm - dr) <= tolerance;
}

// Steps 1-2 of align_by_objects: the best of the identity and the triples' transforms.
Similarity best_hypothesis(const std::vector<Candidate>& c, const Points& p, double gate_m) {
  Similarity best;
  Fit best_fit = fit_of(best, c, p, gate_m);
  std::size_t hypotheses = 0;
  const double tolerance = 2.0 * gate_m;
  for (std::size_t a = 0; a < c.size() && hypotheses < kMaxAlignHypotheses; ++a)
    for (std::size_t b = a + 1; b < c.size() && hypotheses < kMaxAlignHypotheses; ++b) {
      if (!consistent(c[a], c[b], p, tolerance)) continue;
      for (std::size_t k = b + 1; k < c.size() && hypotheses < kMaxAlignHypotheses; ++k) {
        if (!consistent(c[a], c[k], p, tolerance) || !consistent(c[b], c[k], p, tolerance))
          continue;
        const Vec3 &ra = p.ref[c[a].ref], &rb = p.ref[c[b].ref], &rk = p.ref[c[k].ref];
        if ((rb - ra).cross(rk - ra).norm() < 2e-6) continue;  // collinear: no rotation
        ++hypotheses;
        const Similarity t = align_points({p.map[c[a].map], p.map[c[b].map], p.map[c[k].map]},
                                          {ra, rb, rk}, /*with_scale=*/false);
        const Fit fit = fit_of(t, c, p, gate_m);
        if (fit.better_than(best_fit)) {
          best = t;
          best_fit = fit;
        }
      }
    }
  return best;
}

}  // namespace

ObjectAlignment align_by_objects(const std::vector<io::MappedObject>& map,
                                 const std::vector<ReferenceObject>& reference, double gate_m) {
  Points points;
  for (const auto& o : map) points.map.push_back(o.centroid);
  for (const auto& r : reference) points.ref.push_back(r.centroid);
  const std::vector<Candidate> candidates = same_class_candidates(map, reference);

  // Step 3: match within the gate, Umeyama on the pairs, until the pairs repeat.
  Similarity t = best_hypothesis(candidates, points, gate_m);
  std::vector<std::pair<std::size_t, std::size_t>> pairs, previous;
  for (int round = 0; round < 20; ++round) {
    pairs = match_by_class(transform_objects(map, t), reference, gate_m);
    if (pairs.size() < 3 || pairs == previous) break;
    std::vector<Vec3> source, target;
    for (const auto& [i, j] : pairs) {
      source.push_back(points.map[i]);
      target.push_back(points.ref[j]);
    }
    t = align_points(source, target, /*with_scale=*/false);
    previous = pairs;
  }
  if (pairs.size() < 3)
    throw InputError("--align objects",
                     "only " + std::to_string(pairs.size()) +
                         " objects of the map match a reference object of their class within "
                         "the gate after the best alignment found; expected at least 3 (is the "
                         "map of the same scene? a larger --gate, or --align trajectory)");
  ObjectAlignment a;
  a.method = "objects";
  a.reference_from_map = t;
  a.pairs = pairs.size();
  double sum_sq = 0.0;
  for (const auto& [i, j] : pairs) sum_sq += (t * points.map[i] - points.ref[j]).squaredNorm();
  a.rmse_m = std::sqrt(sum_sq / static_cast<double>(pairs.size()));
  return a;
}

}  // namespace objmap::eval

#include "objmap/change/register.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "objmap/change/dense_icp.h"
#include "objmap/core/error.h"

namespace objmap::change {

namespace {

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%g", v);
  return b;
}

Pose gravity_pose(const Visit& v) {
  Pose g = Pose::Identity();
  g.linear() = v.gravity_from_world;
  return g;
}

// An object of the coarse step: its class and position in its visit's gravity frame.
struct Landmark {
  const std::string* class_name;
  Vec3 p;
};

std::vector<Landmark> landmarks(const Visit& v) {
  std::vector<Landmark> out;
  for (const VisitObject& o : v.objects)
    if (!moves_by_itself(o.class_name))
      out.push_back({&o.class_name, v.gravity_from_world * o.position});
  return out;
}

// The after landmarks that have a same-class before landmark within `radius` once moved by
// `before_from_after` (one each, the nearest; a before landmark may serve once): their pairs.
std::vector<std::pair<int, int>> agreeing(const std::vector<Landmark>& before,
                                          const std::vector<Landmark>& after,
                                          const Pose& before_from_after, double radius,
                                          double* sum2) {
  std::vector<std::pair<int, int>> pairs;
  std::vector<bool> used(before.size(), false);
  double s = 0.0;
  for (std::size_t k = 0; k < after.size(); ++k) {
    const Vec3 p = before_from_after * after[k].p;
    int best = -1;
    double best_d2 = radius * radius;
    for (std::size_t i = 0; i < before.size(); ++i) {
      if (used[i] || !same_kind(*before[i].class_name, *after[k].class_name)) continue;
      const double d2 = (before[i].p - p).squaredNorm();
      if (d2 < best_d2) best_d2 = d2, best = static_cast<int>(i);
    }
    if (best < 0) continue;
    used[best] = true;
    s += best_d2;
    pairs.emplace_back(best, static_cast<int>(k));
  }
  if (sum2) *sum2 = s;
  return pairs;
}

// A candidate correspondence of two before landmarks (i, j) with two after landmarks (k, l) of the
// same classes and a compatible layout (horizontal span and height difference).
struct PairOfPairs {
  int i, j, k, l;
};

std::vector<PairOfPairs> candidate_pairs(const std::vector<Landmark>& a,
                                         const std::vector<Landmark>& b,
                                         const RegistrationOptions& o) {
  std::vector<PairOfPairs> out;
  const double tol = 2.0 * o.object_match_m;
  for (int i = 0; i < static_cast<int>(a.size()); ++i)
    for (int j = i + 1; j < static_cast<int>(a.size()); ++j) {
      const Vec3 da = a[j].p - a[i].p;
      const double span_a = da.head<2>().norm();
      if (span_a < o.min_pair_span_m) continue;
      for (int k = 0; k < static_cast<int>(b.size()); ++k) {
        if (!same_kind(*b[k].class_name, *a[i].class_name)) continue;
        for (int l = 0; l < static_cast<int>(b.size()); ++l) {
          if (l == k || !same_kind(*b[l].class_name, *a[j].class_name)) continue;
          const Vec3 db = b[l].p - b[k].p;
          if (std::abs(db.head<2>().norm() - span_a) > tol || std::abs(db.z() - da.z()) > tol)
            continue;
          out.push_back({i, j, k, l});
        }
      }
    }
  if (out.size() > o.max_hypotheses) {  // a fixed-seed sample: deterministic
    std::mt19937_64 rng(42);
    std::shuffle(out.begin(), out.end(), rng);
    out.resize(o.max_hypotheses);
  }
  return out;
}

struct Coarse {
  Pose gb_to_ga = Pose::Identity();  // gravity-before from gravity-after
  Vec3 centre_a = Vec3::Zero();      // the agreeing objects' centroid (gravity-before) ...
  Vec3 centre_b = Vec3::Zero();      // ... and theirs (gravity-after)
  double spread_m = 0.0;             // their largest horizontal distance from it
  int common = 0;
  double rms_m = 0.0;
  std::size_t hypotheses = 0;
};

// The least-squares refinement of a hypothesis on the objects that agree with it, with their
// centroids and spread.
Coarse refine(const std::vector<Landmark>& a, const std::vector<Landmark>& b, Coarse c,
              const RegistrationOptions& o) {
  for (int round = 0; round < 2; ++round) {  // twice: the pairs may change once
    const auto pairs = agreeing(a, b, c.gb_to_ga, o.object_match_m, nullptr);
    if (pairs.size() < 2) break;
    std::vector<Vec3> src, dst;
    for (const auto& [i, k] : pairs) src.push_back(b[k].p), dst.push_back(a[i].p);
    c.gb_to_ga = detail::fit_yaw_translation(src, dst);
  }
  double sum2 = 0.0;
  const auto pairs = agreeing(a, b, c.gb_to_ga, o.object_match_m, &sum2);
  c.common = static_cast<int>(pairs.size());
  c.rms_m = c.common ? std::sqrt(sum2 / c.common) : 0.0;
  for (const auto& [i, k] : pairs) c.centre_a += a[i].p, c.centre_b += b[k].p;
  if (!pairs.empty()) c.centre_a /= pairs.size(), c.centre_b /= pairs.size();
  for (const auto& [i, k] : pairs)
    c.spread_m = std::max(c.spread_m, (a[i].p - c.centre_a).head<2>().norm());
  return c;
}

// Step 1: every pair of pairs proposes a yaw and a translation; the hypotheses most same-class
// objects agree with (then the smallest squared distances) come first, refined by least squares
// on them; distinct ones only (yaw 3° and 10 cm apart), at most `max_candidates`.
std::vector<Coarse> coarse_from_objects(const Visit& before, const Visit& after,
                                        const RegistrationOptions& o, std::size_t max_candidates) {
  const std::vector<Landmark> a = landmarks(before), b = landmarks(after);
  const std::vector<PairOfPairs> candidates = candidate_pairs(a, b, o);
  struct Scored {
    int n;
    double sum2;
    Pose h;
  };
  std::vector<Scored> scored;
  for (const PairOfPairs& c : candidates) {
    const Pose h = detail::fit_yaw_translation({b[c.k].p, b[c.l].p}, {a[c.i].p, a[c.j].p});
    double sum2 = 0.0;
    const int n = static_cast<int>(agreeing(a, b, h, o.object_match_m, &sum2).size());
    scored.push_back({n, sum2, h});
  }
  std::stable_sort(scored.begin(), scored.end(), [](const Scored& x, const Scored& y) {
    return x.n != y.n ? x.n > y.n : x.sum2 < y.sum2;
  });
  std::vector<Coarse> out;
  for (const Scored& s : scored) {
    if (out.size() >= max_candidates) break;
    Coarse c;
    c.gb_to_ga = s.h;
    c = refine(a, b, c, o);
    const bool seen = std::any_of(out.begin(), out.end(), [&](const Coarse& d) {
      return std::abs(yaw_deg_of((d.gb_to_ga.linear().transpose() * c.gb_to_ga.linear()))) < 3.0 &&
             (d.gb_to_ga.translation() - c.gb_to_ga.translation()).norm() < 0.1;
    });
    if (!seen) out.push_back(c);
  }
  for (Coarse& c : out) c.hypotheses = candidates.size();
  std::stable_sort(out.begin(), out.end(),
                   [](const Coarse& x, const Coarse& y) { return x.common > y.common; });
  return out;
}

// The points within `radius` (horizontally) of `centre`: the place both visits' objects share.
std::vector<Vec3f> crop(const std::vector<Vec3f>& points, const Vec3& centre, double radius) {
  std::vector<Vec3f> out;
  const Eigen::Vector2f c = centre.head<2>().cast<float>();
  const float r2 = static_cast<float>(radius * radius);
  for (const Vec3f& p : points)
    if ((p.head<2>() - c).squaredNorm() <= r2) out.push_back(p);
  return out;
}

std::vector<Vec3f> in_gravity(const Visit& v, const RegistrationOptions& o) {
  std::vector<Vec3f> points = detail::thin_cloud(v.dense.points, o.icp_voxel_m, 0);
  const Eigen::Matrix3f g = v.gravity_from_world.cast<float>();
  for (Vec3f& p : points) p = g * p;
  return points;
}

Registration finish(const Visit& before, const Visit& after, const Pose& gb_to_ga,
                    const detail::DenseFit& fit) {
  Registration r;
  r.before_from_after = gravity_pose(before).inverse() * gb_to_ga * gravity_pose(after);
  r.yaw_deg = yaw_deg_of(gb_to_ga.linear());
  r.tilt_deg =
      std::acos(std::clamp((gb_to_ga.linear() * Vec3::UnitZ()).z(), -1.0, 1.0)) * 180.0 / M_PI;
  r.fitness = fit.fitness;
  r.fitness_both = fit.fitness_both;
  r.rms_m = fit.rms_m;
  r.icp_points = fit.source_points;
  r.sigma_translation_m = fit.sigma_translation_m;
  r.sigma_yaw_deg = fit.sigma_yaw_deg;
  return r;
}

// Registration::uncertainty_* from the objects that agree with `gb_to_ga` (gravity frames).
void object_uncertainty(const std::vector<Landmark>& a, const std::vector<Landmark>& b,
                        const Pose& gb_to_ga, const RegistrationOptions& o, Registration& r) {
  const auto pairs = agreeing(a, b, gb_to_ga, o.object_match_m, nullptr);
  const double n = static_cast<double>(pairs.size());
  r.uncertainty_at_objects_m = r.uncertainty_yaw_deg = std::numeric_limits<double>::infinity();
  if (pairs.size() < 2) return;
  Vec3 centre = Vec3::Zero();
  for (const auto& [i, k] : pairs) centre += a[i].p;
  centre /= n;
  double sum2 = 0.0, spread2 = 0.0;
  for (const auto& [i, k] : pairs) {
    sum2 += (a[i].p - gb_to_ga * b[k].p).squaredNorm();
    spread2 += (a[i].p - centre).head<2>().squaredNorm();
  }
  const double sigma = std::sqrt(sum2 / std::max(1.0, 3.0 * n - 4.0));
  const double spread = std::sqrt(spread2 / n);
  const double sigma_yaw = spread > 1e-6 ? sigma / (std::sqrt(n) * spread) : 0.0;
  r.uncertainty_yaw_deg =
      spread > 1e-6 ? sigma_yaw * 180.0 / M_PI : std::numeric_limits<double>::infinity();
  r.uncertainty_at_objects_m =
      std::sqrt(3.0 * sigma * sigma / n + sigma_yaw * sigma_yaw * spread * spread);
}

// Placements from single same-kind correspondences (before object i ↔ after object k) at 24
// yaws; the 3 whose thinned after map overlaps the before map most (within 10 cm).
std::vector<Coarse> sweep(const Visit& before, const Visit& after,
                          const std::vector<Vec3f>& before_points,
                          const std::vector<Vec3f>& after_points, const RegistrationOptions& o) {
  const std::vector<Landmark> a = landmarks(before), b = landmarks(after);
  std::vector<Coarse> candidates;
  std::vector<Pose> guesses;
  for (const Landmark& la : a)
    for (const Landmark& lb : b) {
      if (!same_kind(*la.class_name, *lb.class_name)) continue;
      for (int step = 0; step < 24; ++step) {
        Coarse c;
        c.gb_to_ga.linear() = Eigen::AngleAxisd(step * M_PI / 12.0, Vec3::UnitZ()).matrix();
        c.gb_to_ga.translation() = la.p - c.gb_to_ga.linear() * lb.p;
        c.centre_a = la.p;
        c.centre_b = lb.p;
        candidates.push_back(c);
        guesses.push_back(c.gb_to_ga);
      }
    }
  // Both ways (a small map inside a large one overlaps it well in one direction only).
  std::vector<Pose> inverses;
  for (const Pose& g : guesses) inverses.push_back(g.inverse());
  std::vector<double> shares = detail::overlap_shares(
      before_points, detail::thin_cloud(after_points, o.icp_voxel_m, 2000), guesses, 0.1);
  const std::vector<double> back = detail::overlap_shares(
      after_points, detail::thin_cloud(before_points, o.icp_voxel_m, 2000), inverses, 0.1);
  for (std::size_t i = 0; i < shares.size(); ++i) shares[i] = std::max(shares[i], back[i]);
  std::vector<std::size_t> order(candidates.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t x, std::size_t y) { return shares[x] > shares[y]; });
  std::vector<Coarse> out;
  for (std::size_t i = 0; i < std::min<std::size_t>(3, order.size()); ++i) {
    Coarse c = candidates[order[i]];
    c.hypotheses = candidates.size();
    out.push_back(c);
  }
  return out;
}

}  // namespace

void RegistrationOptions::check() const {
  const auto positive = [](double v, const char* name) {
    require(std::isfinite(v) && v > 0.0, std::string("RegistrationOptions.") + name,
            "must be > 0, got " + num(v));
  };
  positive(object_match_m, "object_match_m");
  positive(icp_voxel_m, "icp_voxel_m");
  positive(icp_max_correspondence_m, "icp_max_correspondence_m");
  positive(icp_final_correspondence_m, "icp_final_correspondence_m");
  positive(inlier_m, "inlier_m");
  positive(icp_crop_margin_m, "icp_crop_margin_m");
  require(std::isfinite(min_pair_span_m) && min_pair_span_m >= 0.0,
          "RegistrationOptions.min_pair_span_m", "must be >= 0, got " + num(min_pair_span_m));
  require(min_common_objects >= 2, "RegistrationOptions.min_common_objects",
          "must be >= 2 (two objects fix a yaw), got " + std::to_string(min_common_objects));
  require(max_hypotheses >= 1, "RegistrationOptions.max_hypotheses", "must be >= 1");
  require(icp_max_points >= 100, "RegistrationOptions.icp_max_points", "must be >= 100");
  require(icp_max_iterations >= 1 && icp_max_iterations <= 1000,
          "RegistrationOptions.icp_max_iterations", "must be in [1, 1000]");
  require(std::isfinite(min_fitness_few_objects) && min_fitness_few_objects >= 0.0 &&
              min_fitness_few_objects <= 1.0,
          "RegistrationOptions.min_fitness_few_objects",
          "must be in [0, 1], got " + num(min_fitness_few_objects));
  require(std::isfinite(min_fitness) && min_fitness >= 0.0 && min_fitness <= 1.0,
          "RegistrationOptions.min_fitness", "must be in [0, 1], got " + num(min_fitness));
}

bool same_kind(const std::string& a, const std::string& b) {
  if (a == b) return true;
  static const char* const kScreens[] = {"tv", "tv monitor", "tvmonitor", "monitor", "laptop"};
  const auto screen = [](const std::string& c) {
    return std::any_of(std::begin(kScreens), std::end(kScreens),
                       [&](const char* s) { return c == s; });
  };
  return screen(a) && screen(b);
}

double yaw_deg_of(const Eigen::Matrix3d& r) { return std::atan2(r(1, 0), r(0, 0)) * 180.0 / M_PI; }

Registration register_visits(const Visit& before, const Visit& after,
                             const RegistrationOptions& options) {
  options.check();
  // 1. Coarse: the objects, in the two gravity frames; a few distinct hypotheses.
  std::vector<Coarse> hypotheses = coarse_from_objects(before, after, options, 6);
  const int best_common = hypotheses.empty() ? 0 : hypotheses.front().common;
  const bool few = best_common < options.min_common_objects;
  const auto too_few = [&](const std::string& more) {
    Registration r;
    r.common_objects = best_common;
    r.hypotheses = hypotheses.empty() ? 0 : hypotheses.front().hypotheses;
    r.why = "too few common objects (" + std::to_string(best_common) + " agree on a placement, " +
            std::to_string(options.min_common_objects) + " needed" + more + ")";
    return r;
  };
  // 2. Refined: ICP of the dense maps, yaw + translation (and a last round for the tilt). Only
  // around the common objects: far surfaces (walls metres away) carry the depth camera's
  // quantisation steps, which differ between two visits' viewpoints and bias the yaw. Where
  // several placements fit the objects (two objects, two alike), a quick ICP of each picks the one
  // the dense maps agree with best.
  const std::vector<Vec3f> before_points = in_gravity(before, options);
  const std::vector<Vec3f> after_points = in_gravity(after, options);
  const auto align = [&](const Coarse& c, const RegistrationOptions& o) {
    const double radius = c.spread_m + o.icp_crop_margin_m;
    return detail::align_dense(crop(before_points, c.centre_a, radius),
                               crop(after_points, c.centre_b, radius), c.gb_to_ga, o, true);
  };
  // With few objects (two agree at best) the true placement may have only one: add the best
  // placements of a yaw sweep about single same-kind correspondences, ranked by dense overlap.
  // Fewer than min_common_objects: only with a dense fitness of min_fitness_few_objects.
  if (best_common <= 2) {
    std::vector<Coarse> swept = sweep(before, after, before_points, after_points, options);
    for (Coarse& c : swept) c.common = best_common;  // ranked with the tied ones below
    hypotheses.insert(hypotheses.end(), swept.begin(), swept.end());
  }
  if (hypotheses.empty()) return too_few("");
  const std::vector<Landmark> a_marks = landmarks(before), b_marks = landmarks(after);
  std::size_t chosen = 0;
  if (hypotheses.size() > 1 && hypotheses[1].common == best_common) {
    RegistrationOptions quick = options;
    quick.icp_max_points = std::min<std::size_t>(options.icp_max_points, 2000);
    quick.icp_max_iterations = std::min(options.icp_max_iterations, 15);
    quick.refine_tilt = false;
    double best_fitness = -1.0;
    for (std::size_t h = 0; h < hypotheses.size(); ++h) {
      if (hypotheses[h].common < best_common) continue;  // only those tied with the best
      const detail::DenseFit f = align(hypotheses[h], quick);
      // A placement no object agrees with any more is the dense maps' coincidence: not taken.
      if (agreeing(a_marks, b_marks, f.target_from_source, options.object_match_m, nullptr).empty())
        continue;
      if (f.fitness > best_fitness) best_fitness = f.fitness, chosen = h;
    }
  }
  const Coarse& coarse = hypotheses[chosen];
  const detail::DenseFit fit = align(coarse, options);
  // 3. Fitness and uncertainty; credible or not.
  Registration r = finish(before, after, fit.target_from_source, fit);
  double sum2 = 0.0;
  r.common_objects =
      static_cast<int>(agreeing(landmarks(before), landmarks(after), fit.target_from_source,
                                options.object_match_m, &sum2)
                           .size());
  r.coarse_rms_m = r.common_objects ? std::sqrt(sum2 / r.common_objects) : 0.0;
  object_uncertainty(landmarks(before), landmarks(after), fit.target_from_source, options, r);
  r.hypotheses = coarse.hypotheses;
  r.credible = (few ? r.fitness_both >= options.min_fitness_few_objects
                    : r.fitness >= options.min_fitness) &&
               r.common_objects >= 1;
  if (few && !r.credible)
    return too_few(", or one and both maps' ICP fitness " + num(options.min_fitness_few_objects) +
                   ": " + num(std::round(r.fitness_both * 1000) / 1000));
  if (r.common_objects < 1)
    r.why = "no object agrees with the placement the dense maps fit best (ICP fitness " +
            num(std::round(r.fitness * 1000) / 1000) + ")";
  else if (!r.credible)
    r.why = "ICP fitness " + num(std::round(r.fitness * 1000) / 1000) + " below " +
            num(options.min_fitness) + " (the dense maps do not overlap where the objects agree)";
  return r;
}

Registration score_registration(const Visit& before, const Visit& after,
                                const Pose& before_from_after, const RegistrationOptions& options) {
  options.check();
  const Pose gb_to_ga = gravity_pose(before) * before_from_after * gravity_pose(after).inverse();
  const std::vector<Vec3f> target = in_gravity(before, options);
  const std::vector<Vec3f> source = in_gravity(after, options);
  const detail::DenseFit fit = detail::align_dense(target, source, gb_to_ga, options, false);
  Registration r = finish(before, after, gb_to_ga, fit);
  r.before_from_after = before_from_after;  // exactly as given
  double sum2 = 0.0;
  r.common_objects = static_cast<int>(
      agreeing(landmarks(before), landmarks(after), gb_to_ga, options.object_match_m, &sum2)
          .size());
  r.coarse_rms_m = r.common_objects ? std::sqrt(sum2 / r.common_objects) : 0.0;
  object_uncertainty(landmarks(before), landmarks(after), gb_to_ga, options, r);
  r.source = "given";
  r.credible = true;
  return r;
}

}  // namespace objmap::change

#include "objmap/change/classify.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "objmap/core/error.h"
#include "objmap/geometry/voxel_key.h"

namespace objmap::change {

namespace {

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%g", v);
  return b;
}

// Occupied voxels of a dense map: a fine grid (1 cm) for "a surface at this point" and a coarse
// one (ClassifyOptions::voxel_m) for the lines of sight.
class Occupancy {
 public:
  Occupancy(const PointCloud& dense, double coarse_m, double fine_m)
      : inv_coarse_(static_cast<float>(1.0 / coarse_m)),
        inv_fine_(static_cast<float>(1.0 / fine_m)) {
    coarse_.reserve(dense.size() / 8 + 16);
    fine_.reserve(dense.size() + 16);
    for (const Vec3f& p : dense.points) {
      geometry::VoxelKey k;
      if (key(p, inv_coarse_, k)) coarse_[k] = 1;
      if (key(p, inv_fine_, k)) fine_[k] = 1;
    }
  }
  bool coarse(const Vec3& p) const {
    geometry::VoxelKey k;
    return key(p.cast<float>(), inv_coarse_, k) && coarse_.contains(k);
  }
  // A dense point in the fine voxel of p or one of its 26 neighbours (within 1–3.5 fine voxels).
  bool surface_at(const Vec3& p) const {
    Eigen::Vector3i ijk;
    Eigen::Vector3f offset;
    if (!geometry::voxel_coords(p.cast<float>(), inv_fine_, ijk, offset)) return false;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          if (fine_.contains(geometry::pack_voxel(ijk.x() + dx, ijk.y() + dy, ijk.z() + dz)))
            return true;
    return false;
  }

 private:
  static bool key(const Vec3f& p, float inv, geometry::VoxelKey& k) {
    Eigen::Vector3i ijk;
    Eigen::Vector3f offset;
    if (!geometry::voxel_coords(p, inv, ijk, offset)) return false;
    k = geometry::pack_voxel(ijk.x(), ijk.y(), ijk.z());
    return true;
  }
  float inv_coarse_, inv_fine_;
  geometry::VoxelHashTable<std::uint8_t> coarse_, fine_;
};

constexpr double kFineVoxelM = 0.01;

// Every n-th element so that at most `max` remain.
template <typename T>
std::vector<T> evenly(const std::vector<T>& v, std::size_t max) {
  if (v.size() <= max) return v;
  std::vector<T> out;
  const double step = static_cast<double>(v.size()) / static_cast<double>(max);
  for (std::size_t i = 0; i < max; ++i) out.push_back(v[static_cast<std::size_t>(i * step)]);
  return out;
}

// An occupied coarse voxel along the line from `from` in unit direction `dir` for t in [t0, t1],
// stepping a voxel (a surface is a layer of voxels: a step may cut a corner, not cross a wall).
bool occupied_along(const Occupancy& occ, const Vec3& from, const Vec3& dir, double t0, double t1,
                    double step) {
  for (double t = t0; t <= t1; t += step)
    if (occ.coarse(from + t * dir)) return true;
  return false;
}

PlaceEvidence evidence_with(const Occupancy& occ, const Visit& viewer,
                            const std::vector<Vec3>& points, const ClassifyOptions& o) {
  PlaceEvidence e;
  const std::vector<Pose> views = evenly(viewer.world_from_cam, o.max_views);
  const std::vector<Vec3> sample = evenly(points, o.max_points);
  const Camera& cam = viewer.camera;
  const double step = o.voxel_m, front_clear = 2.0 * o.voxel_m;
  for (const Pose& world_from_cam : views) {
    const Pose cam_from_world = world_from_cam.inverse();
    const Vec3 centre = world_from_cam.translation();
    bool any = false;
    for (const Vec3& p : sample) {
      // Frustum and range: the view had this point of the place in its image.
      const Vec3 q = cam_from_world * p;
      if (q.z() < o.min_range_m || q.z() > o.max_range_m) continue;
      const Eigen::Vector2d uv = cam.project(q);
      const double m = o.image_margin_px;
      if (uv.x() < m || uv.y() < m || uv.x() > cam.width - 1 - m || uv.y() > cam.height - 1 - m)
        continue;
      any = true;
      const double d = (p - centre).norm();
      const Vec3 dir = (p - centre) / d;
      // A surface in front of it: occluded, no evidence either way.
      if (occupied_along(occ, centre, dir, o.min_range_m, d - front_clear, step)) {
        ++e.occluded;
        continue;
      }
      if (occ.surface_at(p)) {  // the line ends on a surface at the point: something is there
        ++e.sightlines, ++e.surface;
      } else if (occupied_along(occ, centre, dir, d + kFineVoxelM, d + o.behind_m, step)) {
        ++e.sightlines, ++e.seen_through;  // it passed the point to a surface behind: empty
      }
    }
    e.views += any ? 1 : 0;
  }
  return e;
}

// Pairs of (before index, after index) of the candidates accepted by `accept`, greedily cheapest
// first (cost(i, k, distance); ties by index): each object at most once.
template <typename Accept, typename Cost>
std::vector<std::pair<int, int>> greedy_pairs(const std::vector<Vec3>& a,
                                              const std::vector<Vec3>& b, std::vector<bool>& used_a,
                                              std::vector<bool>& used_b, Accept accept, Cost cost) {
  struct Cand {
    double c;
    int i, k;
  };
  std::vector<Cand> cands;
  for (int i = 0; i < static_cast<int>(a.size()); ++i)
    for (int k = 0; k < static_cast<int>(b.size()); ++k) {
      const double d = (a[i] - b[k]).norm();
      if (!used_a[i] && !used_b[k] && accept(i, k, d)) cands.push_back({cost(i, k, d), i, k});
    }
  std::sort(cands.begin(), cands.end(), [](const Cand& x, const Cand& y) {
    return x.c != y.c ? x.c < y.c : (x.i != y.i ? x.i < y.i : x.k < y.k);
  });
  std::vector<std::pair<int, int>> out;
  for (const Cand& c : cands) {
    if (used_a[c.i] || used_b[c.k]) continue;
    used_a[c.i] = used_b[c.k] = true;
    out.emplace_back(c.i, c.k);
  }
  return out;
}

double by_distance(int, int, double d) { return d; }

std::vector<Vec3> points_of(const VisitObject& o, const Pose& to_world) {
  std::vector<Vec3> out;
  out.reserve(o.points.size() + 1);
  for (const Vec3f& p : o.points) out.push_back(to_world * p.cast<double>());
  if (out.empty()) out.push_back(to_world * o.position);
  return out;
}

// A lone object judged by what the other visit saw of its place.
void judge_lone(ObjectChange& c, const PlaceEvidence& e, bool before_side,
                const ClassifyOptions& o) {
  if (e.sightlines < o.min_sightlines) {
    c.status = before_side ? Status::kNotSeenAgain : Status::kNotSeenBefore;
    c.why = std::string("its place was not seen by the ") + (before_side ? "after" : "before") +
            " visit (" + std::to_string(e.sightlines) + " clear lines of sight, " +
            std::to_string(o.min_sightlines) + " needed)";
  } else if (e.surface_share() >= o.present_share) {
    c.status = Status::kUnchanged;
    c.why = "not detected by the " + std::string(before_side ? "after" : "before") +
            " visit, but its surface is there (" + num(std::round(100 * e.surface_share())) +
            "% of the lines of sight end on it)";
  } else if (1.0 - e.surface_share() < o.empty_share) {
    c.status = before_side ? Status::kNotSeenAgain : Status::kNotSeenBefore;
    c.why = "mixed evidence from the " + std::string(before_side ? "after" : "before") +
            " visit: " + num(std::round(100 * (1.0 - e.surface_share()))) +
            "% of the lines of sight pass through its place, " +
            num(std::round(100 * o.empty_share)) + "% needed to call it empty";
  } else {
    c.status = before_side ? Status::kRemoved : Status::kAdded;
    c.why = "its place was seen " +
            std::string(before_side ? "empty by the after" : "empty by the before") + " visit (" +
            num(std::round(100 * (1.0 - e.surface_share()))) +
            "% of the lines of sight pass through it)";
  }
}

}  // namespace

const char* status_name(Status s) {
  switch (s) {
    case Status::kUnchanged:
      return "unchanged";
    case Status::kMoved:
      return "moved";
    case Status::kRemoved:
      return "removed";
    case Status::kAdded:
      return "added";
    case Status::kChangedClass:
      return "changed_class";
    case Status::kNotSeenAgain:
      return "not_seen_again";
    case Status::kNotSeenBefore:
      return "not_seen_before";
  }
  return "unchanged";
}

int ChangeResult::count(Status s) const {
  return static_cast<int>(std::count_if(objects.begin(), objects.end(),
                                        [&](const ObjectChange& c) { return c.status == s; }));
}

void ClassifyOptions::check() const {
  const auto positive = [](double v, const char* name) {
    require(std::isfinite(v) && v > 0.0, std::string("ClassifyOptions.") + name,
            "must be > 0, got " + num(v));
  };
  positive(same_place_m, "same_place_m");
  positive(max_move_m, "max_move_m");
  positive(voxel_m, "voxel_m");
  positive(max_range_m, "max_range_m");
  positive(behind_m, "behind_m");
  require(std::isfinite(colour_weight_m) && colour_weight_m >= 0.0,
          "ClassifyOptions.colour_weight_m", "must be >= 0, got " + num(colour_weight_m));
  require(std::isfinite(same_place_share) && same_place_share >= 0.0,
          "ClassifyOptions.same_place_share", "must be >= 0, got " + num(same_place_share));
  require(std::isfinite(min_range_m) && min_range_m >= 0.0 && min_range_m < max_range_m,
          "ClassifyOptions.min_range_m", "must be in [0, max_range_m), got " + num(min_range_m));
  require(image_margin_px >= 0, "ClassifyOptions.image_margin_px", "must be >= 0");
  require(max_views >= 1 && max_points >= 1, "ClassifyOptions.max_views",
          "max_views and max_points must be >= 1");
  require(min_sightlines >= 1, "ClassifyOptions.min_sightlines", "must be >= 1");
  require(std::isfinite(changed_class_size_ratio) && changed_class_size_ratio >= 1.0,
          "ClassifyOptions.changed_class_size_ratio",
          "must be >= 1, got " + num(changed_class_size_ratio));
  require(std::isfinite(empty_share) && empty_share > 0.0 && empty_share <= 1.0,
          "ClassifyOptions.empty_share", "must be in (0, 1], got " + num(empty_share));
  require(std::isfinite(present_share) && present_share > 0.0 && present_share <= 1.0,
          "ClassifyOptions.present_share", "must be in (0, 1], got " + num(present_share));
}

PlaceEvidence place_evidence(const Visit& viewer, const std::vector<Vec3>& points_in_viewer,
                             const ClassifyOptions& options) {
  options.check();
  const Occupancy occ(viewer.dense, options.voxel_m, kFineVoxelM);
  return evidence_with(occ, viewer, points_in_viewer, options);
}

ChangeResult classify_changes(const Visit& before, const Visit& after,
                              const Pose& before_from_after, const ClassifyOptions& o) {
  o.check();
  ChangeResult result;
  // 0. Leave out what moves by itself; the rest of both maps in the before world.
  std::map<std::string, int> left_out;
  std::vector<const VisitObject*> a, b;
  for (const VisitObject& x : before.objects)
    moves_by_itself(x.class_name) ? void(++left_out[x.class_name]) : a.push_back(&x);
  for (const VisitObject& x : after.objects)
    moves_by_itself(x.class_name) ? void(++left_out[x.class_name]) : b.push_back(&x);
  result.left_out.assign(left_out.begin(), left_out.end());
  std::vector<Vec3> pa, pb;
  for (const VisitObject* x : a) pa.push_back(x->position);
  for (const VisitObject* x : b) pb.push_back(before_from_after * x->position);
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  const auto gate = [&](int i, int k) {
    return std::max(o.same_place_m,
                    o.same_place_share * std::max(a[i]->radius_m(), b[k]->radius_m()));
  };
  // 1. Same class at the same place: unchanged.
  const auto same = greedy_pairs(
      pa, pb, used_a, used_b,
      [&](int i, int k, double d) {
        return a[i]->class_name == b[k]->class_name && d <= gate(i, k);
      },
      by_distance);
  // 2. What each visit saw of the other's lone objects' places.
  // (Each visit's occupancy is built only when the other has an object left to judge.)
  const Pose after_from_before = before_from_after.inverse();
  std::vector<std::optional<PlaceEvidence>> ev_a(a.size()), ev_b(b.size());
  if (std::count(used_a.begin(), used_a.end(), false) > 0) {
    const Occupancy occ_b(after.dense, o.voxel_m, kFineVoxelM);
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!used_a[i]) ev_a[i] = evidence_with(occ_b, after, points_of(*a[i], after_from_before), o);
  }
  if (std::count(used_b.begin(), used_b.end(), false) > 0) {
    const Occupancy occ_a(before.dense, o.voxel_m, kFineVoxelM);
    for (std::size_t k = 0; k < b.size(); ++k)
      if (!used_b[k])
        ev_b[k] = evidence_with(occ_a, before, points_of(*b[k], before_from_after), o);
  }
  const auto still_there = [&](const std::optional<PlaceEvidence>& e) {
    return e && e->sightlines >= o.min_sightlines && e->surface_share() >= o.present_share;
  };
  // 3. Same class elsewhere: moved, unless its old place still holds its surface (then the other
  // is a second object) or the new place already held it.
  const auto moved = greedy_pairs(
      pa, pb, used_a, used_b,
      [&](int i, int k, double d) {
        return a[i]->class_name == b[k]->class_name && d <= o.max_move_m && !still_there(ev_a[i]) &&
               !still_there(ev_b[k]);
      },
      [&](int i, int k, double d) {
        if (!a[i]->colour || !b[k]->colour) return d;
        return d + o.colour_weight_m * (*a[i]->colour - *b[k]->colour).norm() / 255.0;
      });
  // 4. Another class at the same place, of a like size: changed class.
  const auto changed = greedy_pairs(
      pa, pb, used_a, used_b,
      [&](int i, int k, double d) {
        const double ra = a[i]->radius_m(), rb = b[k]->radius_m();
        return a[i]->class_name != b[k]->class_name && d <= gate(i, k) &&
               std::max(ra, rb) <= o.changed_class_size_ratio * std::min(ra, rb);
      },
      by_distance);
  // 5. The records: pairs, then lone objects judged by the evidence.
  const auto record = [&](int i, int k, Status s) {
    ObjectChange c;
    c.status = s;
    if (i >= 0) {
      c.before_id = a[i]->id, c.before_class = a[i]->class_name, c.before_position = pa[i];
      c.evidence_after = ev_a[i];
    }
    if (k >= 0) {
      c.after_id = b[k]->id, c.after_class = b[k]->class_name;
      c.after_position = b[k]->position, c.after_position_in_before = pb[k];
      c.evidence_before = ev_b[k];
    }
    if (i >= 0 && k >= 0) {
      c.distance_m = (pb[k] - pa[i]).norm();
      const std::string d = num(std::round(c.distance_m * 1000) / 1000) + " m";
      if (s == Status::kMoved) {
        c.displacement = pb[k] - pa[i];
        c.why = "the same class " + d + " away, its old place not holding it";
      } else if (s == Status::kChangedClass) {
        c.why = a[i]->class_name + " became " + b[k]->class_name + " at the same place (" + d + ")";
      } else {
        c.why = "the same class at the same place (" + d + ")";
      }
    }
    return c;
  };
  std::vector<std::pair<int, ObjectChange>> ordered;  // sort key: before index, else a.size()+k
  for (const auto& [i, k] : same) ordered.emplace_back(i, record(i, k, Status::kUnchanged));
  for (const auto& [i, k] : changed) ordered.emplace_back(i, record(i, k, Status::kChangedClass));
  for (const auto& [i, k] : moved) ordered.emplace_back(i, record(i, k, Status::kMoved));
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!used_a[i]) {
      ObjectChange c = record(static_cast<int>(i), -1, Status::kRemoved);
      judge_lone(c, *ev_a[i], true, o);
      ordered.emplace_back(static_cast<int>(i), c);
    }
  for (std::size_t k = 0; k < b.size(); ++k)
    if (!used_b[k]) {
      ObjectChange c = record(-1, static_cast<int>(k), Status::kAdded);
      judge_lone(c, *ev_b[k], false, o);
      ordered.emplace_back(static_cast<int>(a.size() + k), c);
    }
  std::stable_sort(ordered.begin(), ordered.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  for (auto& [key, c] : ordered) result.objects.push_back(std::move(c));
  return result;
}

}  // namespace objmap::change

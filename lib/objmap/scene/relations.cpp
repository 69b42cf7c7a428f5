// Relations between objects and surfaces: on, near, above, under; the surfaces' labels
// (docs/scene.md, "Relations" and "Labels").
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/scene/footprint.h"
#include "objmap/scene/near.h"
#include "objmap/scene/scene.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::scene {
namespace {

// Furniture: stands on the floor, not on a table or a desk, wherever it is seen.
bool furniture(const std::string& name) {
  const std::string c = segmentation::canonical_class(name);
  static const std::set<std::string> kClasses = {"chair", "couch",        "sofa",   "bed",
                                                 "bench", "dining table", "toilet", "refrigerator"};
  return kClasses.count(c) > 0;
}

// Classes that stand on the floor, not on a table: furniture and what walks or is set down beside
// it; what the floor rule looks for.
bool floor_standing(const std::string& name) {
  const std::string c = segmentation::canonical_class(name);
  static const std::set<std::string> kOthers = {"potted plant", "person", "suitcase", "dog", "cat"};
  return furniture(c) || kOthers.count(c) > 0;
}

bool seat_class(const std::string& name) {
  const std::string c = segmentation::canonical_class(name);
  return c == "chair" || c == "couch" || c == "sofa" || c == "bench" || c == "bed" || c == "toilet";
}

cv::Point2f xy_in_gravity(const Eigen::Matrix3d& gravity, const Vec3& p) {
  const Vec3 g = gravity * p;
  return {static_cast<float>(g.x()), static_cast<float>(g.y())};
}

std::vector<cv::Point2f> outline_xy(const Surface& s, const Eigen::Matrix3d& gravity) {
  std::vector<cv::Point2f> hull;
  for (const Vec3& q : s.outline) hull.push_back(xy_in_gravity(gravity, q));
  return hull;
}

// The share of the footprint `own` (a convex hull) that lies over the convex outline `under`.
double overlap_share(const std::vector<cv::Point2f>& own, const std::vector<cv::Point2f>& under) {
  if (own.size() < 3 || under.size() < 3) return 0.0;
  const double area = cv::contourArea(own);
  if (!(area > 0.0)) return 0.0;
  std::vector<cv::Point2f> common;
  return cv::intersectConvexConvex(own, under, common, /*handleNested=*/true) / area;
}

// Seen from above, `under` carries the footprint: it holds the footprint's centre (with
// outline_margin) or at least min_footprint_overlap of it.
bool carries(const std::vector<cv::Point2f>& under, const detail::Footprint& f,
             const RelationOptions& o) {
  return detail::inside_distance(under, f.centre) >= -o.outline_margin_m ||
         overlap_share(f.hull, under) >= o.min_footprint_overlap;
}

// How far two objects interpenetrate: the share of the smaller footprint over the other's times
// the share of the smaller height range inside the other's, in [0, 1] (0 for a book on a book: its
// heights start where the other's end).
double interpenetration(const detail::Footprint& a, const detail::Footprint& b) {
  if (a.hull.size() < 3 || b.hull.size() < 3) return 0.0;
  const double area_a = cv::contourArea(a.hull), area_b = cv::contourArea(b.hull);
  const double ground =
      area_a <= area_b ? overlap_share(a.hull, b.hull) : overlap_share(b.hull, a.hull);
  const double common = std::min(a.top, b.top) - std::max(a.bottom, b.bottom);
  const double shorter = std::min(a.top - a.bottom, b.top - b.bottom);
  if (!(common > 0.0) || !(shorter > 0.0)) return 0.0;
  return ground * std::min(1.0, common / shorter);
}

bool same_class(const SceneObject& a, const SceneObject& b) {
  return segmentation::canonical_class(a.class_name) == segmentation::canonical_class(b.class_name);
}

// Pairs of one class that interpenetrate by at least duplicate_overlap: suspected duplicates of
// one physical object (fusion/duplicates.h reports them from the boxes and surfaces too), listed
// on both.
void suspected_duplicates(const std::vector<SceneObject>& objects,
                          const std::vector<detail::Footprint>& feet, const RelationOptions& o,
                          std::vector<Relations>& relations) {
  for (std::size_t i = 0; i < objects.size(); ++i)
    for (std::size_t j = i + 1; j < objects.size(); ++j) {
      if (!same_class(objects[i], objects[j])) continue;
      const double overlap = interpenetration(feet[i], feet[j]);
      if (overlap < o.duplicate_overlap) continue;
      relations[i].duplicates.push_back({objects[j].id, overlap});
      relations[j].duplicates.push_back({objects[i].id, overlap});
    }
  for (auto& r : relations)
    std::sort(r.duplicates.begin(), r.duplicates.end(),
              [](const SuspectedDuplicate& a, const SuspectedDuplicate& b) { return a.id < b.id; });
}

bool listed_duplicate(const Relations& r, int id) {
  for (const SuspectedDuplicate& d : r.duplicates)
    if (d.id == id) return true;
  return false;
}

// `on`: the support (a surface that is no object's top, or another object) whose top lies
// within [bottom − on_below, bottom + on_above] of the object's bottom, nearest to it (ties: the
// higher), and whose outline holds the object's centre (seen from above, with outline_margin) or
// at least min_footprint_overlap of its footprint: the visible outline of a desk ends where the
// monitor at its back edge hides it, so the monitor's centre may lie beyond it. The
// nearest, not the highest: a mouse beside a keyboard whose box it bleeds into sits at the table's
// height, 3 cm below the keyboard's top; a book on a book sits at the lower book's top. An object's
// top is the outline of its points in the top band (a chair's backrest, not its seat), and a
// suspected duplicate of the object is no support of it.
std::optional<Support> support_of(std::size_t i, const std::vector<SceneObject>& objects,
                                  const std::vector<detail::Footprint>& feet,
                                  const std::vector<Surface>& surfaces,
                                  const Eigen::Matrix3d& gravity, const RelationOptions& o,
                                  const Relations& own) {
  const detail::Footprint& f = feet[i];
  std::optional<Support> best;
  double best_top = -std::numeric_limits<double>::infinity();
  const auto consider = [&](const std::string& kind, int id, const std::string& label, double top,
                            const std::vector<cv::Point2f>& hull) {
    const double gap = f.bottom - top;
    if (gap < -o.on_below_m || gap > o.on_above_m || !carries(hull, f, o)) return;
    if (best && (std::fabs(gap) > std::fabs(best->gap_m) ||
                 (std::fabs(gap) == std::fabs(best->gap_m) && top <= best_top)))
      return;
    best_top = top;
    best = Support{kind, id, label, gap};
  };
  for (const Surface& s : surfaces) {
    if (s.object) continue;  // an object's top: the object itself is the candidate below
    consider("surface", s.id, s.label, s.height_m, outline_xy(s, gravity));
  }
  const double own_area = f.hull.size() >= 3 ? cv::contourArea(f.hull) : 0.0;
  for (std::size_t j = 0; j < objects.size(); ++j) {
    if (j == i || feet[j].top_hull.size() < 3 || listed_duplicate(own, objects[j].id)) continue;
    // A support's top is not much smaller than what it carries, seen from above (a cup on a book,
    // a book on a book of its size; not a keyboard on a mouse, nor a bowl on a chair's backrest).
    if (cv::contourArea(feet[j].top_hull) < o.support_min_area_ratio * own_area) continue;
    consider("object", objects[j].id, objects[j].class_name, feet[j].top, feet[j].top_hull);
  }
  return best;
}

// The surfaces' labels (SurfaceOptions): the floor is the lowest patch of floor_min_area that is
// not an object's top, unless only small objects stand on it and it is no larger than a table can
// be (then the floor is unseen and it is a table); a table is a patch
// table_min_height..table_max_height above the floor, or, with the floor unseen, the patch under
// most small objects; an object's top is a seat (chairs, couches, beds) or a surface; the rest are
// surfaces.
void label_surfaces(std::vector<Surface>& surfaces, const std::vector<SceneObject>& objects,
                    const std::vector<Relations>& relations, const SurfaceOptions& o) {
  std::map<int, int> small_on, standing_on;  // surface id -> objects on it
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (relations[i].on && relations[i].on->kind == "surface")
      ++(floor_standing(objects[i].class_name) ? standing_on : small_on)[relations[i].on->id];
  const auto class_of = [&](int id) {
    for (const auto& obj : objects)
      if (obj.id == id) return obj.class_name;
    return std::string();
  };
  const auto floor_sized = [&](const Surface& s) {  // a floor piece by its size: no object's top
    return !s.object && s.area_m2 >= o.floor_min_area_m2;
  };
  Surface* floor = nullptr;
  for (Surface& s : surfaces) {
    s.label = "surface";
    s.label_rule = "a horizontal patch";
    if (s.object) {
      const bool seat = seat_class(class_of(*s.object));
      s.label = seat ? "seat" : "surface";
      s.label_rule = "the top of object " + std::to_string(*s.object);
      continue;
    }
    if (floor_sized(s) && (!floor || s.height_m < floor->height_m)) floor = &s;
  }
  // The floor: the largest of the large patches below table height over the lowest one (a floor
  // that the estimated up sees tilted, or that desks and chairs cut apart, leaves pieces a few cm
  // apart, and the lowest may be a small piece 13 cm below the rest); every large patch at its
  // level is floor too.
  if (floor) {
    const double lowest = floor->height_m;
    for (Surface& s : surfaces)
      if (floor_sized(s) && s.height_m - lowest < o.table_min_height_m &&
          s.area_m2 > floor->area_m2)
        floor = &s;
  }
  if (floor && small_on[floor->id] > 0 && standing_on[floor->id] == 0 &&
      floor->area_m2 <= o.table_max_area_m2)
    floor = nullptr;
  if (floor) {
    const std::string large = fixed_text(o.floor_min_area_m2, 2) + " m2";
    for (Surface& s : surfaces)
      if (floor_sized(s) && std::fabs(s.height_m - floor->height_m) <= o.merge_height_m) {
        s.label = "floor";
        s.label_rule = &s == floor ? "the largest patch of at least " + large + " less than " +
                                         fixed_text(o.table_min_height_m, 2) + " m above the lowest"
                                   : "a patch of at least " + large + " at the floor's level";
      }
    for (Surface& s : surfaces) {
      const double above = s.height_m - floor->height_m;
      if (!s.object && s.label != "floor" && s.area_m2 >= o.table_min_area_m2 &&
          above >= o.table_min_height_m && above <= o.table_max_height_m) {
        s.label = "table";
        s.label_rule = "a patch " + fixed_text(above, 2) + " m above the floor";
      }
    }
    return;
  }
  Surface* table = nullptr;
  for (Surface& s : surfaces)
    if (!s.object && small_on[s.id] > 0 && s.area_m2 <= o.table_max_area_m2 &&
        (!table || small_on[s.id] > small_on[table->id]))
      table = &s;
  if (table) {
    table->label = "table";
    table->label_rule = "the floor is not seen; the patch under most objects (" +
                        std::to_string(small_on[table->id]) + ")";
  }
}

// The floor's plane holds for the whole room: the floor under furniture is hidden by it, and a
// fridge or a couch against a wall may have no floor seen beside it. So furniture found on a table
// or on nothing, and any object found on nothing, stands on the floor when its bottom is within
// floor_gap_m above the floor's height (at most on_below_m below it), whichever floor piece was
// seen, anywhere: the nearest to its footprint. Furniture stands on the floor too when what is
// hidden of it is at most hidden_base_m (a chair seen from above over a table, its legs hidden;
// a chair pushed under a desk; a dining table seen by its top): a chair does not float. A chair
// seen from above has its seat, not in its mask, as a patch at its bottom that the table rule
// labels: the table a chair, couch, bench or bed was on becomes its seat when nothing else
// stands on it and a floor is seen.
void on_the_floor(const std::vector<SceneObject>& objects,
                  const std::vector<detail::Footprint>& feet, std::vector<Surface>& surfaces,
                  const Eigen::Matrix3d& gravity, const RelationOptions& o,
                  std::vector<Relations>& relations) {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::optional<Support>& on = relations[i].on;
    const detail::Footprint& f = feet[i];
    const bool is_furniture = furniture(objects[i].class_name);
    if (on && !(is_furniture && on->label == "table")) continue;
    const Surface* floor = nullptr;
    double floor_reach = -std::numeric_limits<double>::infinity();
    for (const Surface& s : surfaces) {
      if (s.label != "floor" || f.bottom - s.height_m < -o.on_below_m) continue;
      const std::vector<cv::Point2f> hull = outline_xy(s, gravity);
      double reach = detail::inside_distance(hull, f.centre);
      for (const cv::Point2f& p : f.hull) reach = std::max(reach, detail::inside_distance(hull, p));
      if (reach > floor_reach) {
        floor = &s;
        floor_reach = reach;
      }
    }
    if (!floor) continue;
    const double gap = f.bottom - floor->height_m;
    if (!is_furniture) {  // on nothing: the floor when it is at the floor's height
      if (gap <= o.floor_gap_m) relations[i].on = Support{"surface", floor->id, floor->label, gap};
      continue;
    }
    const auto carries_another = [&](int surface_id) {
      for (std::size_t j = 0; j < objects.size(); ++j)
        if (j != i && relations[j].on && relations[j].on->kind == "surface" &&
            relations[j].on->id == surface_id)
          return true;
      return false;
    };
    if (on && seat_class(objects[i].class_name) && !carries_another(on->id))
      for (Surface& s : surfaces)
        if (s.id == on->id) {
          s.object = objects[i].id;
          s.label = "seat";
          s.label_rule = "the seat of object " + std::to_string(objects[i].id) +
                         ", at its bottom (furniture stands on the floor)";
        }
    // On the floor when its bottom is near the floor's height, or when no more of it than a
    // chair's or a table's legs are hidden (seen from above, pushed under a desk): gap_m says how
    // much. Otherwise what it stands on is not seen (furniture does not stand on a table, nor on
    // its own seat).
    if (gap <= std::max(o.floor_gap_m, o.hidden_base_m))
      relations[i].on = Support{"surface", floor->id, floor->label, gap};
    else
      relations[i].on.reset();
  }
}

// A table top holds under what stands on it, seen or hidden: the visible outline of a desk ends
// where the monitors at its back edge hide it. An object on nothing whose bottom lies at the
// height of a table (within on_below_m / on_above_m) and whose footprint comes within
// hidden_reach_m of the table's outline stands on it. Furniture does not stand on a table.
void on_a_hidden_table(const std::vector<SceneObject>& objects,
                       const std::vector<detail::Footprint>& feet,
                       const std::vector<Surface>& surfaces, const Eigen::Matrix3d& gravity,
                       const RelationOptions& o, std::vector<Relations>& relations) {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const detail::Footprint& f = feet[i];
    if (relations[i].on || furniture(objects[i].class_name) || f.hull.size() < 3) continue;
    std::optional<Support> best;
    for (const Surface& s : surfaces) {
      if (s.label != "table") continue;
      const double gap = f.bottom - s.height_m;
      if (gap < -o.on_below_m || gap > o.on_above_m) continue;
      if (best && std::fabs(gap) >= std::fabs(best->gap_m)) continue;
      const std::vector<cv::Point2f> hull = outline_xy(s, gravity);
      double reach = detail::inside_distance(hull, f.centre);
      for (const cv::Point2f& p : f.hull) reach = std::max(reach, detail::inside_distance(hull, p));
      if (reach >= -o.hidden_reach_m) best = Support{"surface", s.id, s.label, gap};
    }
    if (best) relations[i].on = best;
  }
}

// `near` (near.cpp: the clearance against a reach scaled to the smaller object), `above`, `under`.
void near_above_under(const std::vector<SceneObject>& objects,
                      const std::vector<detail::Footprint>& feet,
                      const std::vector<Surface>& surfaces, const Eigen::Matrix3d& gravity,
                      const RelationOptions& o, std::vector<Relations>& relations) {
  detail::near_relations(objects, feet, surfaces, gravity, o, relations);
  for (std::size_t i = 0; i < objects.size(); ++i)
    for (std::size_t j = 0; j < objects.size(); ++j) {
      if (i == j || feet[j].hull.size() < 3 || feet[i].bottom < feet[j].top - o.stack_tolerance_m)
        continue;
      if (detail::inside_distance(feet[j].hull, feet[i].centre) < -o.outline_margin_m) continue;
      relations[i].above.push_back({objects[j].id, feet[i].bottom - feet[j].top});
      relations[j].under.push_back({objects[i].id, feet[i].bottom - feet[j].top});
    }
}

}  // namespace

void RelationOptions::check() const {
  require(on_below_m >= 0.0, "RelationOptions.on_below_m", "must be >= 0");
  require(on_above_m >= 0.0, "RelationOptions.on_above_m", "must be >= 0");
  require(outline_margin_m >= 0.0, "RelationOptions.outline_margin_m", "must be >= 0");
  require(min_footprint_overlap > 0.0 && min_footprint_overlap <= 1.0,
          "RelationOptions.min_footprint_overlap", "must be in (0, 1]");
  require(near_radius_m > 0.0, "RelationOptions.near_radius_m", "must be > 0");
  require(near_scale > 0.0, "RelationOptions.near_scale", "must be > 0");
  require(near_min_m >= 0.0, "RelationOptions.near_min_m", "must be >= 0");
  require(near_max_m >= near_min_m, "RelationOptions.near_max_m", "must be >= near_min_m");
  require(stack_tolerance_m >= 0.0, "RelationOptions.stack_tolerance_m", "must be >= 0");
  require(support_min_area_ratio >= 0.0, "RelationOptions.support_min_area_ratio", "must be >= 0");
  require(top_band_m >= 0.0, "RelationOptions.top_band_m", "must be >= 0");
  require(hidden_reach_m >= 0.0, "RelationOptions.hidden_reach_m", "must be >= 0");
  require(hidden_base_m >= 0.0, "RelationOptions.hidden_base_m", "must be >= 0");
  require(floor_gap_m >= 0.0, "RelationOptions.floor_gap_m", "must be >= 0");
  require(duplicate_overlap > 0.0 && duplicate_overlap <= 1.0, "RelationOptions.duplicate_overlap",
          "must be in (0, 1]");
}

void SceneOptions::check() const {
  up.check();
  surfaces.check();
  relations.check();
}

std::vector<Relations> relate_objects(const std::vector<SceneObject>& objects,
                                      std::vector<Surface>& surfaces, const Vec3& up,
                                      const SurfaceOptions& surface_options,
                                      const RelationOptions& options) {
  const Eigen::Matrix3d gravity = gravity_from_world(up);
  std::vector<detail::Footprint> feet;
  for (const auto& obj : objects)
    feet.push_back(detail::footprint(obj.cloud ? obj.cloud->points : std::vector<Vec3f>{}, gravity,
                                     obj.position, options.top_band_m));
  std::vector<Relations> relations(objects.size());
  suspected_duplicates(objects, feet, options, relations);
  for (std::size_t i = 0; i < objects.size(); ++i)
    relations[i].on = support_of(i, objects, feet, surfaces, gravity, options, relations[i]);
  label_surfaces(surfaces, objects, relations, surface_options);
  const auto refresh_labels = [&] {
    for (auto& r : relations)
      if (r.on && r.on->kind == "surface")
        for (const Surface& s : surfaces)
          if (s.id == r.on->id) r.on->label = s.label;
  };
  refresh_labels();
  on_the_floor(objects, feet, surfaces, gravity, options, relations);
  on_a_hidden_table(objects, feet, surfaces, gravity, options, relations);
  refresh_labels();  // a table that was a chair's seat
  near_above_under(objects, feet, surfaces, gravity, options, relations);
  return relations;
}

}  // namespace objmap::scene

#include "objmap/scene/query.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::scene {
namespace {

using Kind = io::SceneRelation::Kind;

const char* kGrammar =
    "expected CLASS [on|near|above|under CLASS|floor|table|seat|surface], e.g. \"cup on table\"";
const std::set<std::string> kSurfaceLabels = {"floor", "table", "seat", "surface"};
// `near` a surface in an objects.json without relations.near_surfaces: the object's position within
// this of its outline (the rule before fuse wrote them).
constexpr double kNearSurfaceM = 0.5;

// Singular forms to try for a (possibly plural) phrase: the last word changed.
std::vector<std::string> singulars(const std::string& phrase) {
  std::vector<std::string> out = {phrase};
  const auto space = phrase.rfind(' ');
  const std::string head = space == std::string::npos ? "" : phrase.substr(0, space + 1);
  const std::string w = space == std::string::npos ? phrase : phrase.substr(space + 1);
  const auto ends = [&](const std::string& s) {
    return w.size() > s.size() && w.compare(w.size() - s.size(), s.size(), s) == 0;
  };
  static const std::vector<std::pair<std::string, std::string>> kIrregular = {
      {"mice", "mouse"}, {"people", "person"}, {"knives", "knife"}, {"sheep", "sheep"}};
  for (const auto& [plural, single] : kIrregular)
    if (w == plural) out.push_back(head + single);
  if (ends("ies")) out.push_back(head + w.substr(0, w.size() - 3) + "y");
  if (ends("es")) out.push_back(head + w.substr(0, w.size() - 2));
  if (ends("s")) out.push_back(head + w.substr(0, w.size() - 1));
  return out;
}

std::string join(std::vector<std::string>::const_iterator begin,
                 std::vector<std::string>::const_iterator end) {
  std::string out;
  for (auto w = begin; w != end; ++w) out += (out.empty() ? "" : " ") + *w;
  return out;
}

}  // namespace

std::optional<std::string> class_named(const std::string& phrase,
                                       const std::set<std::string>& known) {
  for (const std::string& s : singulars(phrase))
    if (known.count(segmentation::canonical_class(s))) return segmentation::canonical_class(s);
  return std::nullopt;
}

namespace {

// The canonical class or surface label (second: true) that `phrase` names, if any.
std::optional<std::pair<std::string, bool>> lookup(const std::string& phrase, bool surface_ok,
                                                   const std::set<std::string>& known) {
  for (const std::string& s : singulars(phrase)) {
    if (surface_ok && kSurfaceLabels.count(s)) return std::make_pair(s, true);
    if (known.count(segmentation::canonical_class(s)))
      return std::make_pair(segmentation::canonical_class(s), false);
  }
  return std::nullopt;
}

// The subject (`surface_ok` false) or the target of a query. Throws naming the word not understood:
// the one after the longest beginning of `phrase` that names something ("cup beside table":
// 'beside'; "cup on table please": 'please'), else the phrase.
std::pair<std::string, bool> resolve_phrase(const std::vector<std::string>& phrase, bool surface_ok,
                                            const std::set<std::string>& known,
                                            const std::string& text) {
  require(!phrase.empty(), "query",
          "'" + text + "' has no " + (surface_ok ? "target" : "class") + "; " + kGrammar);
  if (auto found = lookup(join(phrase.begin(), phrase.end()), surface_ok, known)) return *found;
  for (auto end = phrase.end() - 1; end != phrase.begin(); --end) {
    const std::string head = join(phrase.begin(), end);
    if (!lookup(head, surface_ok, known)) continue;
    if (!surface_ok)
      throw InputError("query", "'" + *end + "' is not a relation (on|near|above|under) after '" +
                                    head + "'; " + kGrammar);
    throw InputError("query", "'" + *end + "' after '" + head +
                                  "' is not understood (one relation per query); " + kGrammar);
  }
  throw InputError("query", "'" + join(phrase.begin(), phrase.end()) +
                                "' is not a class of COCO-80 or of this map" +
                                std::string(surface_ok ? " nor floor|table|seat|surface" : "") +
                                "; " + kGrammar);
}

std::string describe_support(const MapObject& o, const MapScene& scene) {
  if (!o.on) return "on nothing found";
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  if (o.on->kind == Kind::kSurface)
    s << "on surface " << o.on->id << " (" << o.on->label << ")";
  else
    s << "on object " << o.on->id << " (" << o.on->label << ")";
  s << ", gap " << o.on->gap_m << " m";
  (void)scene;
  return s.str();
}

// The surfaces under an object, following `on` through objects (a cup on a book on the table).
std::vector<const MapSurface*> supporting_surfaces(const MapObject& o, const MapScene& scene) {
  std::vector<const MapSurface*> out;
  const MapObject* cur = &o;
  for (int hop = 0; hop < 8 && cur && cur->on; ++hop) {
    if (cur->on->kind == Kind::kSurface) {
      if (const MapSurface* s = scene.surface(cur->on->id)) out.push_back(s);
      break;
    }
    cur = scene.object(cur->on->id);
  }
  return out;
}

bool label_matches(const MapSurface& s, const std::string& target) {
  return target == "surface" || s.label == target;
}

// Horizontal distance from `p` to the surface's outline (0 inside), and its height above it.
std::pair<double, double> relative_to(const MapSurface& s, const Vec3& p, const MapScene& scene) {
  std::vector<cv::Point2f> hull;
  for (const Vec3& q : s.outline) {
    const Vec3 g = scene.gravity_from_world * q;
    hull.emplace_back(static_cast<float>(g.x()), static_cast<float>(g.y()));
  }
  const Vec3 g = scene.gravity_from_world * p;
  double outside = 0.0;
  if (hull.size() >= 3)
    outside = std::max(
        0.0, -cv::pointPolygonTest(
                 hull, cv::Point2f(static_cast<float>(g.x()), static_cast<float>(g.y())), true));
  return {outside, g.z() - s.height_m};
}

std::optional<QueryMatch> match_surface(const MapObject& o, const Query& q, const MapScene& scene) {
  const auto under_it = supporting_surfaces(o, scene);
  for (const MapSurface* s : under_it)
    if (label_matches(*s, q.target) &&
        (q.relation == "on" || q.relation == "above" || q.relation == "near"))
      return QueryMatch{&o, describe_support(o, scene), o.on ? o.on->gap_m : 0.0, std::nullopt};
  std::ostringstream why;
  why.setf(std::ios::fixed);
  why.precision(3);
  if (q.relation == "near" && o.near_surfaces)  // fuse's `near` (docs/scene.md), nearest first
    for (const auto& [id, gap] : *o.near_surfaces)
      if (const MapSurface* s = scene.surface(id); s && label_matches(*s, q.target)) {
        why << "near surface " << s->id << " (" << s->label << "), " << gap << " m";
        return QueryMatch{&o, why.str(), gap, std::nullopt};
      }
  for (const MapSurface& s : scene.surfaces) {
    if (!label_matches(s, q.target)) continue;
    const auto [outside, height] = relative_to(s, o.position, scene);
    if (q.relation == "near" && !o.near_surfaces && outside <= kNearSurfaceM) {
      why << outside << " m beside surface " << s.id << " (" << s.label << ")";
      return QueryMatch{&o, why.str(), outside, std::nullopt};
    }
    if ((q.relation == "under" && outside == 0.0 && height < 0.0) ||
        (q.relation == "above" && outside == 0.0 && height > 0.0)) {
      why << std::fabs(height) << " m " << q.relation << " surface " << s.id << " (" << s.label
          << ")";
      return QueryMatch{&o, why.str(), std::fabs(height), std::nullopt};
    }
  }
  return std::nullopt;
}

std::optional<QueryMatch> match_object(const MapObject& o, const Query& q, const MapScene& scene) {
  const auto is_target = [&](int id) {
    const MapObject* t = scene.object(id);
    return t && segmentation::canonical_class(t->class_name) == q.target;
  };
  std::ostringstream why;
  why.setf(std::ios::fixed);
  why.precision(3);
  if (q.relation == "on" && o.on) {
    const MapSurface* s = o.on->kind == Kind::kSurface ? scene.surface(o.on->id) : nullptr;
    if ((o.on->kind == Kind::kObject && is_target(o.on->id)) ||
        (s && s->object && is_target(*s->object)))
      return QueryMatch{&o, describe_support(o, scene), o.on->gap_m, std::nullopt};
  }
  const std::vector<std::pair<int, double>>* list = q.relation == "near"    ? &o.near
                                                    : q.relation == "above" ? &o.above
                                                    : q.relation == "under" ? &o.under
                                                                            : nullptr;
  if (list)
    for (const auto& [id, d] : *list)
      if (is_target(id)) {
        why << q.relation << " object " << id << " (" << q.target << "), " << d << " m";
        return QueryMatch{&o, why.str(), d, std::nullopt};
      }
  return std::nullopt;
}

std::optional<QueryMatch> match(const MapObject& o, const Query& q, const MapScene& scene) {
  std::optional<QueryMatch> m;
  if (q.relation.empty())
    m = QueryMatch{&o, describe_support(o, scene), o.on ? o.on->gap_m : 0.0, std::nullopt};
  else
    m = q.target_is_surface ? match_surface(o, q, scene) : match_object(o, q, scene);
  if (m) {  // whatever the relation: the surface it stands on
    const auto surfaces = supporting_surfaces(o, scene);
    m->surface = surfaces.empty() ? std::nullopt : std::optional<int>(surfaces[0]->id);
  }
  return m;
}

}  // namespace

Query parse_query(const std::string& text, const MapScene& scene) {
  Query q;
  q.text = text;
  std::vector<std::string> words;
  std::istringstream in(segmentation::canonical_class(text));
  for (std::string w; in >> w;)
    if (w != "the" && w != "a" && w != "an") words.push_back(w);
  require(!words.empty(), "query", std::string("empty; ") + kGrammar);
  std::set<std::string> known(segmentation::coco80_names().begin(),
                              segmentation::coco80_names().end());
  for (const auto& o : scene.objects) known.insert(segmentation::canonical_class(o.class_name));
  const auto resolve = [&](const std::vector<std::string>& phrase, bool surface_ok) {
    return resolve_phrase(phrase, surface_ok, known, text);
  };
  const auto rel = std::find_if(words.begin(), words.end(), [](const std::string& w) {
    return w == "on" || w == "near" || w == "above" || w == "under";
  });
  q.subject = resolve({words.begin(), rel}, false).first;
  if (rel != words.end()) {
    q.relation = *rel;
    const auto [target, is_surface] = resolve({rel + 1, words.end()}, true);
    q.target = target;
    q.target_is_surface = is_surface;
  }
  return q;
}

QueryResult run_query(const Query& q, const MapScene& scene) {
  QueryResult result;
  const auto of_subject = [&](const MapObject& o) {
    return segmentation::canonical_class(o.class_name) == q.subject;
  };
  for (const auto& o : scene.objects)
    if (of_subject(o))
      if (auto m = match(o, q, scene)) result.matches.push_back(*m);
  // Closest first: a gap of -8 mm (the bottom hidden below the support's top) is no closer than
  // one of +5 mm.
  std::stable_sort(result.matches.begin(), result.matches.end(),
                   [](const QueryMatch& a, const QueryMatch& b) {
                     return std::fabs(a.distance_m) < std::fabs(b.distance_m);
                   });
  if (!result.matches.empty()) return result;
  for (const auto& o : scene.objects)
    if (of_subject(o)) result.candidates.push_back(*match(o, Query{}, scene));
  if (result.candidates.empty() && !q.relation.empty())
    for (const auto& o : scene.objects)
      if (auto m = match(o, q, scene)) result.candidates.push_back(*m);
  return result;
}

}  // namespace objmap::scene

#include "objmap/sim/second_visit.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"
#include "objmap/sim/random.h"
#include "objmap/sim/support.h"

namespace objmap::sim {

namespace {

struct Rect {
  double x0, y0, x1, y1;
};

// Horizontal radius of an object's box (its footprint's half diagonal).
double footprint_radius(const SceneObject& o) { return o.obb.half_extent.head<2>().norm(); }

// A free spot on a table for `o`: inside a table top by its radius + 2 cm, 3 cm clear of every
// other object in `others` (index into scene.objects, -1 = none), at least `min_from` from `from`.
bool free_spot(const SceneObject& o, const std::vector<Rect>& tables,
               const std::vector<const SceneObject*>& others, const Vec3& from, double min_from,
               Rng& rng, Vec3* spot) {
  const double r = footprint_radius(o);
  for (int attempt = 0; attempt < 500 && !tables.empty(); ++attempt) {
    const Rect& t = tables[std::min<std::size_t>(
        tables.size() - 1, static_cast<std::size_t>(rng.uniform() * tables.size()))];
    const double x = rng.uniform(t.x0 + r + 0.02, t.x1 - r - 0.02);
    const double y = rng.uniform(t.y0 + r + 0.02, t.y1 - r - 0.02);
    if (!(x > t.x0 && x < t.x1 && y > t.y0 && y < t.y1)) continue;  // the object is too large
    const Vec3 p(x, y, o.obb.center.z());
    if ((p - from).head<2>().norm() < min_from) continue;
    bool clear = true;
    for (const SceneObject* other : others)
      if (other != &o &&
          (other->obb.center - p).head<2>().norm() < r + footprint_radius(*other) + 0.03)
        clear = false;
    if (clear) {
      *spot = p;
      return true;
    }
  }
  return false;
}

// Moves `o` so that its box centre is over `spot` (same height).
void place_at(SceneObject& o, const Vec3& spot) {
  o.world_from_object.translation() +=
      Vec3(spot.x() - o.obb.center.x(), spot.y() - o.obb.center.y(), 0.0);
  o.finalize(64);
}

std::vector<Rect> table_tops(const SceneSupport& support) {
  std::vector<Rect> out;
  for (const SupportSurface& s : support.surfaces) {
    if (s.label != "table" || s.outline.empty()) continue;
    Rect r{1e9, 1e9, -1e9, -1e9};
    for (const Vec3& c : s.outline)
      r = {std::min(r.x0, c.x()), std::min(r.y0, c.y()), std::max(r.x1, c.x()),
           std::max(r.y1, c.y())};
    out.push_back(r);
  }
  return out;
}

// Objects standing on a table top that hold nothing up: the ones that may move or go.
std::vector<int> movable(const Scene& scene, const SceneSupport& support) {
  std::vector<int> out;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const auto& on = support.on[i];
    if (!on || on->kind != SupportRelation::Kind::kSurface || on->label != "table") continue;
    bool holds = false;
    for (const auto& other : support.on)
      if (other && other->kind == SupportRelation::Kind::kObject &&
          other->id == scene.objects[i].id)
        holds = true;
    if (!holds) out.push_back(static_cast<int>(i));
  }
  return out;
}

}  // namespace

void SecondVisitOptions::check() const {
  if (!enabled) return;
  require(move >= 0 && move <= 50, "--move", "must be in [0, 50], got " + std::to_string(move));
  require(remove >= 0 && remove <= 50, "--remove",
          "must be in [0, 50], got " + std::to_string(remove));
  require(add >= 0 && add <= 50, "--add", "must be in [0, 50], got " + std::to_string(add));
  require(std::isfinite(min_move_m) && min_move_m >= 0.0, "SecondVisitOptions.min_move_m",
          "must be >= 0");
  require(std::isfinite(max_shift_m) && max_shift_m >= 0.0, "SecondVisitOptions.max_shift_m",
          "must be >= 0");
}

void read_first_visit(const std::filesystem::path& folder, SecondVisitOptions& options,
                      std::string& preset) {
  const std::filesystem::path file = folder / "synth.json";
  const nlohmann::json doc = io::read_json_file(
      file, "cannot open; expected the synth.json of a folder written by objmap synth");
  require(doc.is_object() && doc.contains("preset") && doc["preset"].is_string(),
          file.string() + ": preset", "missing or not a string; expected what objmap synth writes");
  require(doc.contains("seed") && doc["seed"].is_number_unsigned(), file.string() + ": seed",
          "missing or not a whole number; expected what objmap synth writes");
  preset = doc["preset"].get<std::string>();
  options.first_seed = doc["seed"].get<std::uint64_t>();
  options.first_visit = folder;
}

void transform_scene(Scene& scene, const Pose& after_from_before) {
  for (auto* list : {&scene.structure, &scene.objects})
    for (SceneObject& o : *list) {
      o.world_from_object = after_from_before * o.world_from_object;
      o.finalize(list == &scene.structure ? 16 : 64);
    }
  scene.light_dir_world = after_from_before.linear() * scene.light_dir_world;
}

SecondVisit make_second_visit(Scene& scene, const SecondVisitOptions& options, std::uint64_t seed) {
  options.check();
  SecondVisit visit;
  Rng rng(derive_seed(seed, 0, 0x5EC0D));
  const SceneSupport support = scene_support(scene);
  const std::vector<Rect> tables = table_tops(support);
  std::vector<int> candidates = movable(scene, support);
  for (std::size_t i = candidates.size(); i > 1; --i)  // Fisher-Yates, our own Rng: portable
    std::swap(candidates[i - 1], candidates[rng.uniform_int(static_cast<int>(i))]);
  std::vector<std::string> status(scene.objects.size(), "unchanged");
  std::vector<Vec3> before(scene.objects.size());
  for (std::size_t i = 0; i < scene.objects.size(); ++i) before[i] = scene.objects[i].obb.center;
  // A moved or added object keeps clear of the objects there now and of the places the first
  // visit's objects held: no change lands on another's old place, so each has one answer.
  const std::vector<SceneObject> first_visit = scene.objects;
  const auto present = [&] {
    std::vector<const SceneObject*> out;
    for (std::size_t i = 0; i < scene.objects.size(); ++i)
      if (i >= status.size() || status[i] != "removed") out.push_back(&scene.objects[i]);
    for (const SceneObject& ghost : first_visit) out.push_back(&ghost);
    return out;
  };
  // 1. Moves, then removals, from the shuffled candidates.
  std::size_t next = 0;
  for (int m = 0; m < options.move && next < candidates.size(); ++next) {
    SceneObject& o = scene.objects[candidates[next]];
    Vec3 spot;
    if (!free_spot(o, tables, present(), o.obb.center, options.min_move_m, rng, &spot)) continue;
    place_at(o, spot);
    status[candidates[next]] = "moved";
    ++m;
  }
  for (int r = 0; r < options.remove && next < candidates.size(); ++next, ++r)
    status[candidates[next]] = "removed";
  // 2. Additions: a copy of a table-top object's kind, with a new id, at a free spot.
  int next_id = 0;
  for (const SceneObject& o : scene.objects) next_id = std::max(next_id, o.id);
  const std::size_t first_count = scene.objects.size();
  for (int a = 0; a < options.add && !candidates.empty(); ++a) {
    // A random kind first; where it finds no free place, the next ones in turn.
    const int first = rng.uniform_int(static_cast<int>(candidates.size()));
    for (std::size_t t = 0; t < candidates.size(); ++t) {
      SceneObject copy = scene.objects[candidates[(first + t) % candidates.size()]];
      Vec3 spot;
      if (!free_spot(copy, tables, present(), Vec3::Constant(1e9), 0.0, rng, &spot)) continue;
      copy.id = ++next_id;
      // Another instance of that kind: a colour of its own (a green no cup, bottle or book of the
      // presets wears), so that it is not a twin of the object it was copied from.
      for (Part& part : copy.parts) {
        part.material.base = {40, static_cast<std::uint8_t>(rng.uniform(190, 220)), 60};
        part.material.seed = static_cast<std::uint32_t>(rng.next());
      }
      place_at(copy, spot);
      scene.objects.push_back(copy);
      status.push_back("added");
      break;
    }
  }
  // 3. The new world frame: a yaw about up and a shift; the orbit's start moves on.
  const double yaw = rng.uniform(-M_PI, M_PI);
  visit.after_from_before.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).matrix();
  visit.after_from_before.translation() =
      Vec3(rng.uniform(-options.max_shift_m, options.max_shift_m),
           rng.uniform(-options.max_shift_m, options.max_shift_m), rng.uniform(-0.3, 0.3));
  visit.start_angle_offset_deg = rng.uniform(60.0, 300.0);
  // 4. The record; the removed objects leave the scene.
  std::vector<SceneObject> kept;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    ObjectChangeGt c;
    c.status = status[i];
    c.class_name = o.class_name;
    if (i < first_count) c.before_id = o.id, c.before_position = before[i];
    if (status[i] != "removed") {
      c.after_id = o.id;
      c.after_position = visit.after_from_before * o.obb.center;
      kept.push_back(o);
    }
    visit.changes.push_back(c);
  }
  scene.objects = std::move(kept);
  return visit;
}

std::string changes_gt_json(const SecondVisit& visit, const SecondVisitOptions& options) {
  using json = nlohmann::ordered_json;
  const auto vec = [](const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); };
  const Pose before_from_after = visit.after_from_before.inverse();
  json m = json::array();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.push_back(before_from_after.matrix()(r, c));
  json objects = json::array();
  for (const ObjectChangeGt& c : visit.changes)
    objects.push_back({{"status", c.status},
                       {"class", c.class_name},
                       {"before_id", c.before_id ? json(c.before_id) : json(nullptr)},
                       {"after_id", c.after_id ? json(c.after_id) : json(nullptr)},
                       {"before_position", c.before_id ? vec(c.before_position) : json(nullptr)},
                       {"after_position", c.after_id ? vec(c.after_position) : json(nullptr)}});
  json doc = {
      {"schema_version", 1},
      {"generator", "objmap synth --second-visit-of"},
      {"first_visit", options.first_visit.string()},
      {"first_seed", options.first_seed},
      {"before_from_after", m},
      {"yaw_deg", std::atan2(before_from_after.linear()(1, 0), before_from_after.linear()(0, 0)) *
                      180.0 / M_PI},
      {"positions", "box centres; before in the first visit's world, after in this one's"},
      {"objects", objects}};
  return doc.dump(2) + "\n";
}

}  // namespace objmap::sim

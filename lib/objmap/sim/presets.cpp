#include "objmap/sim/presets.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "objmap/core/error.h"
#include "objmap/sim/random.h"

namespace objmap::sim {

namespace {

constexpr double kDeg = M_PI / 180.0;

Pose at(double x, double y, double z, double yaw_deg = 0.0) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_deg * kDeg, Vec3::UnitZ()).matrix();
  p.translation() = Vec3(x, y, z);
  return p;
}

Part part(Shape shape, const Vec3& half, const Pose& object_from_part, const Material& m) {
  Part p;
  p.shape = shape;
  p.half_extent = half;
  p.object_from_part = object_from_part;
  p.material = m;
  return p;
}

// Builds objects with a running id and varied materials.
class Builder {
 public:
  Builder(Scene* scene, std::uint64_t seed) : scene_(scene), rng_(derive_seed(seed, 0, 0x5CE4E)) {}

  Rng& rng() { return rng_; }
  // Caps the position and yaw jitter of the objects made from now on (objects placed at an edge).
  void limit_jitter(double max_jitter_m, double max_yaw_jitter_deg) {
    jitter_limit_m_ = max_jitter_m;
    yaw_jitter_limit_deg_ = max_yaw_jitter_deg;
  }

  Material mat(Rgb base, Rgb accent, Pattern pattern, double scale_m, double grain = 0.06) {
    Material m;
    m.base = vary(base);
    m.accent = vary(accent);
    m.pattern = pattern;
    m.scale_m = scale_m;
    m.grain = grain;
    m.seed = static_cast<std::uint32_t>(rng_.next());
    return m;
  }

  // A ground-truth object standing at (x, y) on a surface at height z; position jittered by up to
  // `jitter_m` and the yaw by up to `yaw_jitter_deg`.
  SceneObject& object(const std::string& cls, double x, double y, double z, double yaw_deg,
                      double jitter_m = 0.02, double yaw_jitter_deg = 12.0) {
    jitter_m = std::min(jitter_m, jitter_limit_m_);
    yaw_jitter_deg = std::min(yaw_jitter_deg, yaw_jitter_limit_deg_);
    SceneObject o;
    o.id = static_cast<int>(scene_->objects.size()) + 1;
    o.class_name = cls;
    o.world_from_object =
        at(x + rng_.uniform(-jitter_m, jitter_m), y + rng_.uniform(-jitter_m, jitter_m), z,
           yaw_deg + rng_.uniform(-yaw_jitter_deg, yaw_jitter_deg));
    scene_->objects.push_back(o);
    return scene_->objects.back();
  }

  SceneObject& structure(const std::string& cls, const Pose& world_from_object) {
    SceneObject o;
    o.id = 0;
    o.class_name = cls;
    o.world_from_object = world_from_object;
    scene_->structure.push_back(o);
    return scene_->structure.back();
  }

 private:
  Rgb vary(Rgb c) {
    auto v = [&](std::uint8_t x) {
      return static_cast<std::uint8_t>(std::clamp(x + rng_.uniform_int(31) - 15, 0, 255));
    };
    return {v(c.r), v(c.g), v(c.b)};
  }
  Scene* scene_;
  Rng rng_;
  double jitter_limit_m_ = std::numeric_limits<double>::infinity();
  double yaw_jitter_limit_deg_ = std::numeric_limits<double>::infinity();
};

// The room: one box seen from inside, floor at z = 0.
void add_room(Builder& b, double half_x, double half_y, double height) {
  auto& room = b.structure("room", at(0, 0, height / 2));
  Part box = part(Shape::kBox, Vec3(half_x, half_y, height / 2), Pose::Identity(), Material{});
  const Rgb wall_colours[4] = {{200, 205, 190}, {190, 200, 215}, {215, 200, 185}, {205, 195, 205}};
  for (int k = 0; k < 4; ++k) {  // -x, +x, -y, +y walls
    const Rgb c = wall_colours[k];
    const Rgb dark{static_cast<std::uint8_t>(c.r - 45), static_cast<std::uint8_t>(c.g - 45),
                   static_cast<std::uint8_t>(c.b - 45)};
    box.face_materials.push_back(b.mat(c, dark, Pattern::kNoise, 0.12, 0.1));
  }
  box.face_materials.push_back(b.mat({150, 120, 90}, {110, 85, 60}, Pattern::kChecker, 0.4, 0.15));
  box.face_materials.push_back(b.mat({235, 235, 230}, {220, 220, 215}, Pattern::kNoise, 0.3));
  room.parts.push_back(box);
}

constexpr double kTableHeight = 0.75;  // top surface

// A table: top and four legs, each its own structure object so that the renderer culls them apart.
void add_table(Builder& b, double x, double y, double half_x, double half_y) {
  const Material top = b.mat({160, 110, 65}, {120, 75, 40}, Pattern::kNoise, 0.05, 0.1);
  const Material leg = b.mat({70, 60, 55}, {50, 45, 40}, Pattern::kSolid, 0.05);
  b.structure("table", at(x, y, 0))
      .parts.push_back(
          part(Shape::kBox, Vec3(half_x, half_y, 0.02), at(0, 0, kTableHeight - 0.02), top));
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0})
      b.structure("table", at(x, y, 0))
          .parts.push_back(
              part(Shape::kBox, Vec3(0.025, 0.025, (kTableHeight - 0.04) / 2),
                   at(sx * (half_x - 0.06), sy * (half_y - 0.06), (kTableHeight - 0.04) / 2), leg));
}

void add_chair(Builder& b, double x, double y, double yaw_deg) {
  // Faces +x of its frame before the yaw: seat, back on the -x side, four legs.
  auto& o = b.object("chair", x, y, 0.0, yaw_deg, 0.03, 10.0);
  const Material wood = b.mat({95, 60, 35}, {60, 35, 20}, Pattern::kNoise, 0.04, 0.1);
  const Material cushion = b.mat({40, 70, 130}, {25, 45, 95}, Pattern::kChecker, 0.05, 0.08);
  o.parts.push_back(part(Shape::kBox, Vec3(0.22, 0.22, 0.025), at(0, 0, 0.45), cushion));
  o.parts.push_back(part(Shape::kBox, Vec3(0.02, 0.22, 0.22), at(-0.2, 0, 0.475 + 0.22), wood));
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0})
      o.parts.push_back(
          part(Shape::kBox, Vec3(0.018, 0.018, 0.2125), at(sx * 0.19, sy * 0.19, 0.2125), wood));
}

void add_monitor(Builder& b, double x, double y, double yaw_deg) {
  // Screen faces -y of its frame before the yaw.
  auto& o = b.object("tv monitor", x, y, kTableHeight, yaw_deg, 0.02, 8.0);
  const Material frame = b.mat({30, 30, 32}, {45, 45, 50}, Pattern::kSolid, 0.05, 0.05);
  const Material screen = b.mat({40, 90, 170}, {230, 200, 90}, Pattern::kNoise, 0.035, 0.05);
  o.parts.push_back(part(Shape::kBox, Vec3(0.1, 0.08, 0.008), at(0, 0, 0.008), frame));
  o.parts.push_back(part(Shape::kBox, Vec3(0.02, 0.015, 0.07), at(0, 0.02, 0.016 + 0.07), frame));
  o.parts.push_back(part(Shape::kBox, Vec3(0.28, 0.02, 0.17), at(0, 0.0, 0.12 + 0.17), frame));
  // The picture: a thin panel in front of the frame.
  o.parts.push_back(part(Shape::kBox, Vec3(0.26, 0.003, 0.15), at(0, -0.022, 0.12 + 0.17), screen));
}

void add_keyboard(Builder& b, double x, double y, double yaw_deg) {
  auto& o = b.object("keyboard", x, y, kTableHeight, yaw_deg, 0.02, 6.0);
  o.parts.push_back(part(Shape::kBox, Vec3(0.22, 0.07, 0.0125), at(0, 0, 0.0125),
                         b.mat({35, 35, 38}, {200, 200, 205}, Pattern::kKeys, 0.019, 0.05)));
}

void add_mouse(Builder& b, double x, double y, double yaw_deg) {
  auto& o = b.object("mouse", x, y, kTableHeight, yaw_deg, 0.02, 20.0);
  o.parts.push_back(part(Shape::kEllipsoid, Vec3(0.032, 0.058, 0.02), at(0, 0, 0.02),
                         b.mat({185, 185, 190}, {90, 90, 95}, Pattern::kStripes, 0.02, 0.05)));
}

// The handle points along the cup's x; its yaw is random unless given.
void add_cup(Builder& b, double x, double y, Rgb colour, std::optional<double> yaw_deg = {}) {
  const double random_yaw_deg = b.rng().uniform(0.0, 360.0);
  auto& o = b.object("cup", x, y, kTableHeight, yaw_deg.value_or(random_yaw_deg), 0.02, 0.0);
  const Material m = b.mat(colour, {240, 240, 240}, Pattern::kStripes, 0.018, 0.06);
  o.parts.push_back(part(Shape::kCylinder, Vec3(0.04, 0.04, 0.05), at(0, 0, 0.05), m));
  o.parts.push_back(part(Shape::kBox, Vec3(0.015, 0.006, 0.03), at(0.05, 0, 0.055), m));  // handle
}

void add_bottle(Builder& b, double x, double y, double z = kTableHeight) {
  auto& o = b.object("bottle", x, y, z, 0.0, 0.02, 180.0);
  const Material glass = b.mat({40, 120, 60}, {20, 80, 35}, Pattern::kNoise, 0.02, 0.05);
  const Material label = b.mat({230, 225, 200}, {180, 40, 40}, Pattern::kStripes, 0.012, 0.05);
  o.parts.push_back(part(Shape::kCylinder, Vec3(0.035, 0.035, 0.055), at(0, 0, 0.055), glass));
  o.parts.push_back(part(Shape::kCylinder, Vec3(0.0355, 0.0355, 0.045), at(0, 0, 0.155), label));
  o.parts.push_back(part(Shape::kCylinder, Vec3(0.014, 0.014, 0.035), at(0, 0, 0.235), glass));
}

void add_book(Builder& b, double x, double y, double z, double yaw_deg, Rgb colour) {
  auto& o = b.object("book", x, y, z, yaw_deg, 0.015, 10.0);
  o.parts.push_back(part(Shape::kBox, Vec3(0.12, 0.085, 0.015), at(0, 0, 0.015),
                         b.mat(colour, {245, 240, 225}, Pattern::kNoise, 0.015, 0.08)));
}

void add_teddy(Builder& b, double x, double y, double yaw_deg, double z = kTableHeight) {
  auto& o = b.object("teddy bear", x, y, z, yaw_deg, 0.02, 20.0);
  const Material fur = b.mat({150, 100, 55}, {105, 65, 30}, Pattern::kNoise, 0.012, 0.15);
  const Material snout = b.mat({215, 185, 140}, {180, 150, 110}, Pattern::kNoise, 0.01, 0.1);
  o.parts.push_back(part(Shape::kEllipsoid, Vec3(0.075, 0.065, 0.09), at(0, 0, 0.09), fur));
  o.parts.push_back(part(Shape::kEllipsoid, Vec3(0.06, 0.06, 0.058), at(0, 0, 0.225), fur));
  o.parts.push_back(part(Shape::kEllipsoid, Vec3(0.022, 0.012, 0.022), at(-0.045, 0, 0.28), fur));
  o.parts.push_back(part(Shape::kEllipsoid, Vec3(0.022, 0.012, 0.022), at(0.045, 0, 0.28), fur));
  o.parts.push_back(part(Shape::kEllipsoid, Vec3(0.025, 0.02, 0.018), at(0, -0.055, 0.215), snout));
  o.parts.push_back(
      part(Shape::kEllipsoid, Vec3(0.025, 0.045, 0.025), at(-0.045, -0.05, 0.02), fur));
  o.parts.push_back(
      part(Shape::kEllipsoid, Vec3(0.025, 0.045, 0.025), at(0.045, -0.05, 0.02), fur));
}

// One table's worth of objects around (x, y); `mirror` flips the layout left-right.
void tabletop_objects(Builder& b, double x, double y, bool mirror, int books) {
  const double m = mirror ? -1.0 : 1.0;
  add_monitor(b, x, y + 0.25, 0.0);
  add_keyboard(b, x, y - 0.05, 0.0);
  add_mouse(b, x + m * 0.3, y - 0.05, 0.0);
  add_cup(b, x - m * 0.47, y - 0.15, {200, 40, 40});
  add_cup(b, x + m * 0.5, y + 0.2, {40, 90, 200});
  add_bottle(b, x - m * 0.6, y + 0.2);
  add_teddy(b, x - m * 0.42, y + 0.22, -15.0 * m);
  const Rgb book_colours[3] = {{170, 30, 40}, {30, 110, 60}, {220, 170, 30}};
  if (books >= 1) add_book(b, x + m * 0.5, y - 0.22, kTableHeight, 5.0, book_colours[0]);
  if (books >= 2) add_book(b, x + m * 0.5, y - 0.22, kTableHeight + 0.03, 15.0, book_colours[1]);
  if (books >= 3) add_book(b, x - m * 0.2, y - 0.26, kTableHeight, -10.0, book_colours[2]);
}

// The "edge" scene's table (0.9 x 0.6 m) and six objects, each 1-2.5 cm from an edge: two on the
// -y side (where the orbit starts), two on the +y side, one at each end. (The distance of a centre
// from the edge is the object's half footprint across the edge + 1.5-2 cm; the jitter is at most
// 5 mm and 3 degrees.)
void edge_table_with_objects(Builder& b) {
  const double hx = 0.45, hy = 0.3;
  add_table(b, 0, 0, hx, hy);
  b.limit_jitter(0.005, 3.0);
  add_cup(b, -0.05, -hy + 0.058, {200, 40, 40}, 0.0);  // radius 4 cm, handle along the edge
  add_bottle(b, -0.28, -hy + 0.055);                   // radius 3.55 cm
  add_mouse(b, hx - 0.05, -0.08, 0.0);                 // 6.4 x 11.6 cm, long side along the edge
  add_teddy(b, 0.12, hy - 0.085, 0.0);                 // back 6.5 cm behind its centre, facing -y
  add_cup(b, 0.3, hy - 0.058, {40, 90, 200}, 180.0);
  add_book(b, -hx + 0.105, 0.08, kTableHeight, 90.0, {30, 110, 60});  // 17 x 24 cm
}

// The "walkthrough" room (8 x 6 m): a desk with a full tabletop (A), a dining table (B) with six
// chairs packed round it (two side by side on each long side, 6 cm apart), a second desk (C) with
// two chairs, a row of four chairs side by side along the east wall, a teddy bear and a bottle on
// the floor: 12 chairs, 32 objects in all.
void walkthrough_room(Builder& b) {
  add_room(b, 4.0, 3.0, 2.7);
  add_table(b, -2.2, 1.2, 0.7, 0.4);  // A
  tabletop_objects(b, -2.2, 1.2, false, 3);
  add_table(b, 1.5, 0.8, 0.6, 0.4);  // B
  for (double dx : {-0.25, 0.25}) {
    add_chair(b, 1.5 + dx, 0.8 - 0.65, 90.0);
    add_chair(b, 1.5 + dx, 0.8 + 0.65, -90.0);
  }
  add_chair(b, 1.5 - 0.85, 0.8, 0.0);
  add_chair(b, 1.5 + 0.85, 0.8, 180.0);
  add_cup(b, 1.3, 0.7, {200, 40, 40});
  add_cup(b, 1.8, 0.9, {40, 90, 200});
  add_bottle(b, 1.55, 1.0);
  add_book(b, 1.2, 0.95, kTableHeight, 20.0, {30, 110, 60});
  add_table(b, -0.5, -1.8, 0.7, 0.4);  // C
  add_monitor(b, -0.5, -2.0, 180.0);
  add_keyboard(b, -0.5, -1.7, 180.0);
  add_mouse(b, -0.15, -1.7, 0.0);
  add_cup(b, -0.95, -1.6, {220, 170, 30});
  add_chair(b, -0.5, -1.05, -90.0);
  add_chair(b, -1.45, -1.8, 0.0);
  for (double y : {-2.45, -1.95, -1.45, -0.95}) add_chair(b, 3.45, y, 180.0);
  add_teddy(b, 0.4, -0.4, 30.0, 0.0);
  add_bottle(b, -1.3, 2.1, 0.0);
}

void add_couch(Builder& b, double x, double y, double yaw_deg) {
  // 2.0 m long (y of its frame), 0.9 m deep, seat at 0.45 m; faces +x before the yaw.
  auto& o = b.object("couch", x, y, 0.0, yaw_deg, 0.03, 4.0);
  const Material fabric = b.mat({120, 60, 55}, {85, 40, 35}, Pattern::kNoise, 0.05, 0.12);
  const Material cushion = b.mat({150, 85, 70}, {110, 60, 50}, Pattern::kChecker, 0.12, 0.1);
  o.parts.push_back(part(Shape::kBox, Vec3(0.45, 1.0, 0.19), at(0, 0, 0.19), fabric));  // base
  o.parts.push_back(part(Shape::kBox, Vec3(0.33, 0.85, 0.04), at(0.08, 0, 0.42), cushion));
  o.parts.push_back(part(Shape::kBox, Vec3(0.11, 1.0, 0.23), at(-0.34, 0, 0.61), fabric));  // back
  for (double sy : {-1.0, 1.0})                                                             // arms
    o.parts.push_back(part(Shape::kBox, Vec3(0.34, 0.075, 0.12), at(0.1, sy * 0.925, 0.5), fabric));
}

void add_bed(Builder& b, double x, double y, double yaw_deg) {
  // 2.0 m long (x of its frame), 1.6 m wide, mattress top at 0.54 m, headboard on the -x side.
  auto& o = b.object("bed", x, y, 0.0, yaw_deg, 0.03, 3.0);
  const Material wood = b.mat({120, 85, 55}, {85, 60, 35}, Pattern::kNoise, 0.06, 0.1);
  const Material linen = b.mat({205, 210, 225}, {150, 160, 190}, Pattern::kStripes, 0.08, 0.06);
  const Material pillow = b.mat({235, 230, 215}, {200, 195, 180}, Pattern::kNoise, 0.03, 0.05);
  o.parts.push_back(part(Shape::kBox, Vec3(1.0, 0.8, 0.15), at(0, 0, 0.15), wood));
  o.parts.push_back(part(Shape::kBox, Vec3(0.97, 0.78, 0.12), at(0.02, 0, 0.42), linen));
  o.parts.push_back(part(Shape::kBox, Vec3(0.03, 0.8, 0.5), at(-0.97, 0, 0.5), wood));
  for (double sy : {-1.0, 1.0})
    o.parts.push_back(
        part(Shape::kEllipsoid, Vec3(0.16, 0.3, 0.06), at(-0.75, sy * 0.38, 0.59), pillow));
}

void add_refrigerator(Builder& b, double x, double y, double yaw_deg) {
  // 0.7 x 0.7 x 1.8 m, door on +x of its frame before the yaw.
  auto& o = b.object("refrigerator", x, y, 0.0, yaw_deg, 0.02, 3.0);
  const Material body = b.mat({225, 228, 230}, {190, 195, 200}, Pattern::kNoise, 0.1, 0.04);
  const Material metal = b.mat({120, 125, 130}, {90, 95, 100}, Pattern::kSolid, 0.05, 0.05);
  o.parts.push_back(part(Shape::kBox, Vec3(0.35, 0.35, 0.9), at(0, 0, 0.9), body));
  o.parts.push_back(part(Shape::kBox, Vec3(0.015, 0.02, 0.25), at(0.365, 0.26, 1.15), metal));
  o.parts.push_back(part(Shape::kBox, Vec3(0.004, 0.34, 0.004), at(0.352, 0, 1.2), metal));
}

void add_toilet(Builder& b, double x, double y, double yaw_deg) {
  // Bowl in front (+x of its frame), tank behind: 0.38 x 0.68 m, 0.78 m high.
  auto& o = b.object("toilet", x, y, 0.0, yaw_deg, 0.02, 5.0);
  const Material china = b.mat({240, 240, 238}, {215, 215, 212}, Pattern::kNoise, 0.05, 0.03);
  o.parts.push_back(part(Shape::kCylinder, Vec3(0.12, 0.12, 0.19), at(0.05, 0, 0.19), china));
  o.parts.push_back(part(Shape::kEllipsoid, Vec3(0.24, 0.18, 0.08), at(0.08, 0, 0.36), china));
  o.parts.push_back(part(Shape::kBox, Vec3(0.1, 0.19, 0.2), at(-0.24, 0, 0.58), china));
}

// The "apartment" room (8 x 6 m): a bed with a teddy bear on it, a couch facing a television on a
// low table, a refrigerator in a corner, a dining table with two chairs, a cup and a bottle, and a
// toilet: the large furniture of a scan exported for 3D detection (issue #39 §5), 10 objects.
void apartment_room(Builder& b) {
  add_room(b, 4.0, 3.0, 2.6);
  add_bed(b, -2.6, 1.7, 0.0);
  add_teddy(b, -2.2, 1.5, -60.0, 0.54);
  add_couch(b, 1.0, 2.45, -90.0);
  add_table(b, 1.0, 0.9, 0.45, 0.2);
  add_monitor(b, 1.0, 0.95, 180.0);
  add_refrigerator(b, 3.55, 2.55, 180.0);
  add_table(b, 2.4, -1.6, 0.6, 0.4);
  add_chair(b, 2.4, -2.25, 90.0);
  add_chair(b, 2.4, -0.95, -90.0);
  add_cup(b, 2.2, -1.5, {200, 40, 40});
  add_bottle(b, 2.65, -1.75);
  add_toilet(b, -3.55, -2.5, 0.0);
}

// The walk through the apartment, each stretch looking at the furniture beside it: the bed, the
// couch, the refrigerator, the dining table, the toilet (9.9 m a loop).
std::vector<Waypoint> apartment_path() {
  const double eye_z = 1.5;
  auto w = [&](double ex, double ey, double tx, double ty, double tz) {
    return Waypoint{Vec3(ex, ey, eye_z), Vec3(tx, ty, tz)};
  };
  return {w(-1.0, -0.2, -2.6, 1.7, 0.5), w(0.6, -0.3, 1.0, 2.45, 0.5), w(2.6, 0.6, 3.55, 2.55, 0.9),
          w(2.6, 0.0, 2.4, -1.6, 0.6), w(-1.6, -1.2, -3.55, -2.5, 0.4)};
}

// The walk round the room: past desk A, along the dining table B, round its east end, past the
// chair row to desk C and back; 12.7 m a loop, looking at the table beside the way.
std::vector<Waypoint> walkthrough_path() {
  const double eye_z = 1.5, look_z = 0.75;
  auto w = [&](double ex, double ey, double tx, double ty) {
    return Waypoint{Vec3(ex, ey, eye_z), Vec3(tx, ty, look_z)};
  };
  return {w(-1.0, 0.0, -2.2, 1.2), w(0.0, 2.2, 1.5, 0.8), w(3.2, 0.0, 1.5, 0.8),
          w(1.5, -1.5, 3.4, -1.7), w(-2.0, -0.6, -0.5, -1.8)};
}

std::string preset_list() {
  std::string out;
  const auto& names = scene_presets();
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return out;
}

}  // namespace

void check_scene_preset(const std::string& preset) {
  const auto& names = scene_presets();
  if (std::find(names.begin(), names.end(), preset) == names.end())
    throw InputError("--preset",
                     "unknown scene preset '" + preset + "'; expected " + preset_list());
}

const std::vector<std::string>& paper_classes() {
  static const std::vector<std::string> names{"chair",  "cup",  "tv monitor", "teddy bear",
                                              "bottle", "book", "keyboard",   "mouse"};
  return names;
}

const std::vector<std::string>& scene_presets() {
  static const std::vector<std::string> names{"tabletop", "office", "edge", "walkthrough",
                                              "apartment"};
  return names;
}

Scene make_scene(const std::string& preset, std::uint64_t seed) {
  check_scene_preset(preset);
  Scene scene;
  Builder b(&scene, seed);
  if (preset == "tabletop") {
    add_room(b, 2.5, 2.5, 2.6);
    add_table(b, 0, 0, 0.7, 0.4);
    tabletop_objects(b, 0, 0, false, 3);
    add_chair(b, -0.3, -0.72, 90.0);
    add_chair(b, 0.35, 0.72, -90.0);
  } else if (preset == "office") {
    add_room(b, 3.5, 3.0, 2.7);
    add_table(b, -0.85, 0, 0.7, 0.4);
    add_table(b, 0.85, 0, 0.7, 0.4);
    tabletop_objects(b, -0.85, 0, false, 3);
    tabletop_objects(b, 0.85, 0, true, 2);
    add_chair(b, -0.9, -0.75, 90.0);
    add_chair(b, 0.8, -0.75, 90.0);
    add_chair(b, 0.0, 0.8, -90.0);
  } else if (preset == "walkthrough") {
    walkthrough_room(b);
  } else if (preset == "apartment") {
    apartment_room(b);
  } else {  // "edge"
    add_room(b, 2.5, 2.5, 2.6);
    edge_table_with_objects(b);
  }
  for (auto& o : scene.structure) o.finalize(16);
  for (auto& o : scene.objects) o.finalize(64);
  return scene;
}

CameraPathOptions preset_camera_path(const std::string& preset) {
  check_scene_preset(preset);
  CameraPathOptions path;
  if (preset == "edge") {
    // Low (35 cm above the table top) and close. Past the objects at the near edge the lines of
    // sight graze the table top 0.15-0.5 m behind them; past those at the far edge and the ends
    // they miss the table and reach the floor and walls, metres behind.
    path.radius_m = 1.4;
    path.height_m = 1.15;
    path.look_at_height_m = 0.8;
  } else if (preset == "walkthrough") {
    path.waypoints = walkthrough_path();
    path.walk_speed_m_per_s = 1.2;  // a loop in 10.6 s: 318 frames at 30 Hz
  } else if (preset == "apartment") {
    path.waypoints = apartment_path();
    path.walk_speed_m_per_s = 1.2;
  } else if (preset == "office") {
    path.radius_m = 2.3;
    path.height_m = 1.55;
    path.look_at_height_m = 0.75;
    path.start_angle_deg = -115.0;
    path.speed_deg_per_s = 15.0;  // 0.6 m/s at 2.3 m
  }
  return path;
}

}  // namespace objmap::sim

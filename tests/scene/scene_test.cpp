// The scene step on point sets made here: a room (floor, a wall, a table) seen by cameras that look
// down at the table, in a world frame that is not z-up (as ORB-SLAM2's first-camera frame).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "objmap/core/error.h"
#include "objmap/scene/scene.h"

namespace objmap::scene {
namespace {

// The surfaces and which of them are objects' tops, as fuse finds them (find_surfaces, then
// mark_object_tops).
std::vector<Surface> surfaces_and_tops(const std::vector<Vec3f>& map_points, const Vec3& up,
                                       const std::vector<SceneObject>& objects) {
  std::vector<Surface> surfaces = find_surfaces(map_points, up, SurfaceOptions{});
  mark_object_tops(surfaces, up, objects);
  return surfaces;
}

double angle_deg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

void add_rect(std::vector<Vec3f>& pts, double x0, double x1, double y0, double y1, double z,
              double step = 0.01) {
  for (double x = x0; x <= x1; x += step)
    for (double y = y0; y <= y1; y += step) pts.emplace_back(x, y, z);
}

// A z-up room: floor 3 x 3 m at z = 0, a wall at x = 3, a table top 1.2 x 0.8 m at 0.75 m.
std::vector<Vec3f> room(bool with_floor = true) {
  std::vector<Vec3f> pts;
  if (with_floor) add_rect(pts, 0.0, 3.0, 0.0, 3.0, 0.0);
  for (double y = 0.0; y <= 3.0; y += 0.01)
    for (double z = 0.0; z <= 2.0; z += 0.01) pts.emplace_back(3.0, y, z);
  add_rect(pts, 1.0, 2.2, 1.0, 1.8, 0.75);
  return pts;
}

// A small object's points: a box's sides and top standing at `base` (z-up).
PointCloud box_object(const Vec3& base, double half, double height) {
  PointCloud c;
  for (double x = -half; x <= half; x += 0.005)
    for (double z = 0.0; z <= height; z += 0.005) {
      c.push_back(Vec3f(base.x() + x, base.y() - half, base.z() + z), Rgb{});
      c.push_back(Vec3f(base.x() + x, base.y() + half, base.z() + z), Rgb{});
      c.push_back(Vec3f(base.x() - half, base.y() + x, base.z() + z), Rgb{});
    }
  for (double x = -half; x <= half; x += 0.005)
    for (double y = -half; y <= half; y += 0.005)
      c.push_back(Vec3f(base.x() + x, base.y() + y, base.z() + height), Rgb{});
  return c;
}

// Cameras at 1.5 m looking down `pitch_deg` at the table from headings 0-88°, rolled by
// ±roll_deg in turn; camera axes as TUM's: x right, y down, z forward.
std::vector<Pose> cameras(double pitch_deg, double roll_deg = 0.0) {
  std::vector<Pose> out;
  for (int i = 0; i < 12; ++i) {
    const double yaw = i * 8.0 * M_PI / 180.0;  // headings over 90°: the tilts do not cancel
    // Level camera looking along +x of the world: z_cam = x_w, x_cam = -y_w, y_cam = -z_w.
    Eigen::Matrix3d level;
    level.col(0) = -Vec3::UnitY();
    level.col(1) = -Vec3::UnitZ();
    level.col(2) = Vec3::UnitX();
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix() * level *
        Eigen::AngleAxisd(-pitch_deg * M_PI / 180.0, Vec3::UnitX()) *
        Eigen::AngleAxisd((i % 2 ? 1 : -1) * roll_deg * M_PI / 180.0, Vec3::UnitZ());
    Pose p = Pose::Identity();
    p.linear() = r;
    p.translation() = Vec3(1.6, 1.4, 1.5) - 1.2 * r.col(2);
    out.push_back(p);
  }
  return out;
}

// The same scene in another frame: slam_from_world applied to points and cameras.
Eigen::Isometry3d slam_from_world() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(1.1, Vec3(0.3, -0.8, 0.5).normalized())).toRotationMatrix();
  t.translation() = Vec3(0.4, -1.0, 2.0);
  return t;
}

TEST(Up, ParseGivenDirections) {
  EXPECT_EQ(*parse_up("z", "--up"), Vec3::UnitZ());
  EXPECT_EQ(*parse_up("-y", "--up"), -Vec3::UnitY());
  EXPECT_TRUE(parse_up("0,0,2", "--up")->isApprox(Vec3::UnitZ()));
  EXPECT_FALSE(parse_up("auto", "--up").has_value());
  try {
    parse_up("upward", "--up");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--up: 'upward' is not an up direction; expected auto, an axis (x, y, z, -x, -y, -z) "
              "or a vector x,y,z");
  }
  EXPECT_THROW(parse_up("0,0,0", "--up"), InputError);
  EXPECT_THROW(parse_up("1,2", "--up"), InputError);
}

TEST(Up, GravityRotationTakesUpToZ) {
  for (const Vec3& up : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(0.3, -0.5, 0.8).normalized()}) {
    const Eigen::Matrix3d r = gravity_from_world(up);
    EXPECT_TRUE((r * up).isApprox(Vec3::UnitZ(), 1e-12)) << up.transpose();
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  }
  EXPECT_TRUE(gravity_from_world(Vec3::UnitZ()).isIdentity(0.0));
}

TEST(Up, FoundFromTheTableAndFloorInAFrameThatIsNotZUp) {
  const Eigen::Isometry3d t = slam_from_world();
  std::vector<Vec3f> pts;
  for (const Vec3f& p : room()) pts.push_back((t * p.cast<double>()).cast<float>());
  std::vector<Pose> cams;
  for (const Pose& c : cameras(40.0, 20.0)) cams.push_back(t * c);  // rolled: the -y prior
  const UpEstimate e = estimate_up(cams, pts, UpOptions{});
  const Vec3 truth = t.linear() * Vec3::UnitZ();
  EXPECT_EQ(e.source, "planes");
  EXPECT_LT(angle_deg(e.up, truth), 0.5);
  EXPECT_GT(angle_deg(e.camera_prior, truth), 10.0);  // the cameras alone are off
  EXPECT_TRUE((e.gravity_from_world * e.up).isApprox(Vec3::UnitZ(), 1e-9));
  int used = 0;
  for (const auto& p : e.planes) used += p.used ? 1 : 0;
  EXPECT_EQ(used, 2);  // floor and table top; the wall is not
}

// A pose written with `decimals` decimals, as a TUM file holds it (position, unit quaternion).
Pose rounded(const Pose& p, int decimals) {
  const double scale = std::pow(10.0, decimals);
  const auto round = [&](double v) { return std::round(v * scale) / scale; };
  const Eigen::Quaterniond q(p.linear());
  Pose out = Pose::Identity();
  out.linear() = Eigen::Quaterniond(round(q.w()), round(q.x()), round(q.y()), round(q.z()))
                     .normalized()
                     .toRotationMatrix();
  out.translation() = p.translation().unaryExpr(round);
  return out;
}

TEST(Up, TheSameInAnyWorldFrameAndRoundingOfTheCameras) {
  // The room with a floor that leans 2 deg one way and a table top 5 deg another, both with 1 cm
  // of noise: up is their area-weighted mean, the same whichever frame the world is given in (the
  // grid is laid in the cameras' frame) and however the cameras' poses are rounded.
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Vec3f> pts;
  const Eigen::Matrix3d floor_tilt(Eigen::AngleAxisd(2.0 * M_PI / 180.0, Vec3::UnitX()));
  const Eigen::Matrix3d table_tilt(Eigen::AngleAxisd(5.0 * M_PI / 180.0, Vec3::UnitY()));
  for (const Vec3f& p : room()) {
    Vec3 q = p.cast<double>();
    if (q.z() == 0.0 && q.x() < 3.0) q = floor_tilt * (q - Vec3(1.5, 1.5, 0)) + Vec3(1.5, 1.5, 0);
    if (q.z() == 0.75) q = table_tilt * (q - Vec3(1.6, 1.4, 0.75)) + Vec3(1.6, 1.4, 0.75);
    pts.push_back((q + Vec3(noise(rng), noise(rng), noise(rng))).cast<float>());
  }
  std::vector<Vec3> ups;
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int k = 0; k < 5; ++k) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() =
        Eigen::Quaterniond(
            Eigen::Vector4d(uniform(rng), uniform(rng), uniform(rng), uniform(rng)).normalized())
            .toRotationMatrix();
    t.translation() = 5.0 * Vec3(uniform(rng), uniform(rng), uniform(rng));
    std::vector<Vec3f> moved;
    for (const Vec3f& p : pts) moved.push_back((t * p.cast<double>()).cast<float>());
    std::vector<Pose> cams;
    for (const Pose& c : cameras(40.0, 10.0)) cams.push_back(rounded(t * c, 5 + k));
    const UpEstimate e = estimate_up(cams, moved, UpOptions{});
    EXPECT_EQ(e.source, "planes");
    ups.push_back(t.linear().transpose() * e.up);
  }
  for (const Vec3& u : ups) {
    EXPECT_LT(angle_deg(u, ups.front()), 0.3) << u.transpose();
    // The floor (9 m2) leans 2 deg, the table (1 m2) 5 deg: up lies between, nearer the floor.
    EXPECT_LT(angle_deg(u, floor_tilt * Vec3::UnitZ()), 1.0) << u.transpose();
    EXPECT_GT(angle_deg(u, Vec3::UnitZ()), 1.5) << u.transpose();
  }
}

TEST(Up, WithoutPlanesUpIsTheCamerasMeanUpAxisAndItIsSaid) {
  const std::vector<Pose> cams = cameras(40.0);
  UpEstimate e = estimate_up(cams, {}, UpOptions{});
  EXPECT_EQ(e.source, "cameras");
  EXPECT_EQ(e.up, e.camera_prior);
  Vec3 mean_up = Vec3::Zero();
  for (const Pose& c : cams) mean_up -= c.linear().col(1);
  EXPECT_LT(angle_deg(e.up, mean_up), 1e-9);
  ASSERT_EQ(e.warnings.size(), 1u);  // no dense map (fuse --dense-map false): said
  EXPECT_NE(e.warnings[0].find("no dense map to find the floor and tables in"), std::string::npos)
      << e.warnings[0];
  // Points without a plane (a ball of 0.5 m): the same up, and no plane is said.
  std::vector<Vec3f> ball;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 120; ++j) {
      const double th = M_PI * (i + 0.5) / 60, ph = 2 * M_PI * j / 120;
      ball.push_back(Vec3f(0.5 * std::sin(th) * std::cos(ph), 0.5 * std::sin(th) * std::sin(ph),
                           1.0 + 0.5 * std::cos(th)));
    }
  e = estimate_up(cams, ball, UpOptions{});
  EXPECT_EQ(e.source, "cameras");
  ASSERT_EQ(e.warnings.size(), 1u);
  EXPECT_NE(e.warnings[0].find("no plane of the dense map"), std::string::npos) << e.warnings[0];
}

TEST(Up, AWallInFrontOfCamerasLookingDownIsNotTheFloor) {
  // Cameras look 50 deg down at a table in front of a wall that is larger than the table: the wall
  // is about as far from the cameras' up as the table, but they would look up at it.
  std::vector<Vec3f> pts;
  add_rect(pts, 1.0, 2.2, 1.0, 1.8, 0.75);
  for (double y = 0.0; y <= 3.0; y += 0.01)
    for (double z = 0.0; z <= 2.5; z += 0.01) pts.emplace_back(3.0, y, z);
  const Eigen::Isometry3d t = slam_from_world();
  std::vector<Vec3f> moved;
  for (const Vec3f& p : pts) moved.push_back((t * p.cast<double>()).cast<float>());
  std::vector<Pose> cams;
  for (const Pose& c : cameras(50.0, 10.0)) cams.push_back(t * c);
  const UpEstimate e = estimate_up(cams, moved, UpOptions{});
  EXPECT_EQ(e.source, "planes");
  EXPECT_LT(angle_deg(e.up, t.linear() * Vec3::UnitZ()), 0.5);
}

TEST(Up, CamerasThatAreNotUprightAreSaid) {
  // A camera on the ceiling looking straight down, turning about its axis: its y axes spin.
  std::vector<Pose> cams;
  for (int i = 0; i < 8; ++i) {
    Pose p = Pose::Identity();
    p.linear() = Eigen::AngleAxisd(i * M_PI / 4, Vec3::UnitZ()) *
                 Eigen::AngleAxisd(M_PI, Vec3::UnitX()).toRotationMatrix();
    p.translation() = Vec3(1.5, 1.5, 2.5);
    cams.push_back(p);
  }
  const UpEstimate e = estimate_up(cams, room(), UpOptions{});
  bool said = false;
  for (const auto& w : e.warnings) said |= w.find("agreement") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(Up, GivenDirectionIsUsedAsIs) {
  UpOptions o;
  o.mode = "-y";
  const UpEstimate e = estimate_up(cameras(30.0), room(), o);
  EXPECT_EQ(e.source, "given");
  EXPECT_EQ(e.up, -Vec3::UnitY());
  EXPECT_TRUE(e.planes.empty());
}

struct Fixture {
  PointCloud cup = box_object(Vec3(1.5, 1.3, 0.75), 0.04, 0.10);
  PointCloud chair = box_object(Vec3(0.5, 2.5, 0.0), 0.2, 0.45);
  PointCloud book = box_object(Vec3(1.9, 1.5, 0.75), 0.1, 0.03);
  PointCloud pen = box_object(Vec3(1.9, 1.5, 0.78), 0.02, 0.02);
  // The room with the objects' points, as a dense map holds them.
  std::vector<Vec3f> map(bool with_floor = true) const {
    std::vector<Vec3f> pts = room(with_floor);
    for (const PointCloud* c : {&cup, &chair, &book, &pen})
      pts.insert(pts.end(), c->points.begin(), c->points.end());
    return pts;
  }
  std::vector<SceneObject> objects() const {
    return {{1, "cup", Vec3(1.5, 1.3, 0.80), &cup},
            {2, "chair", Vec3(0.5, 2.5, 0.225), &chair},
            {3, "book", Vec3(1.9, 1.5, 0.765), &book},
            {4, "toothbrush", Vec3(1.9, 1.5, 0.79), &pen}};
  }
};

TEST(Surfaces, FloorAndTableFoundAtTheirHeightsWithTheObjectsOnThem) {
  Fixture f;
  const auto objects = f.objects();
  std::vector<Surface> surfaces = surfaces_and_tops(f.map(), Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  const Surface* floor = nullptr;
  const Surface* table = nullptr;
  for (const auto& s : surfaces) {
    if (s.label == "floor") floor = &s;
    if (s.label == "table") table = &s;
  }
  ASSERT_NE(floor, nullptr);
  ASSERT_NE(table, nullptr);
  EXPECT_NEAR(floor->height_m, 0.0, 0.01);
  EXPECT_NEAR(table->height_m, 0.75, 0.01);
  EXPECT_NEAR(table->area_m2, 1.2 * 0.8, 0.1);
  ASSERT_TRUE(relations[0].on);  // the cup on the table
  EXPECT_EQ(relations[0].on->kind, "surface");
  EXPECT_EQ(relations[0].on->id, table->id);
  EXPECT_EQ(relations[0].on->label, "table");
  EXPECT_NEAR(relations[0].on->gap_m, 0.0, 0.01);
  ASSERT_TRUE(relations[1].on);  // the chair on the floor
  EXPECT_EQ(relations[1].on->label, "floor");
  ASSERT_TRUE(relations[3].on);  // the toothbrush on the book, not on the table below it
  EXPECT_EQ(relations[3].on->kind, "object");
  EXPECT_EQ(relations[3].on->id, 3);
  ASSERT_EQ(relations[3].above.size(), 1u);
  EXPECT_EQ(relations[3].above[0].id, 3);
  ASSERT_EQ(relations[2].under.size(), 1u);
  EXPECT_EQ(relations[2].under[0].id, 4);
  // near: the book and the toothbrush (0.03 m), the cup 0.45 m away; the chair is not near.
  ASSERT_GE(relations[2].near.size(), 2u);
  EXPECT_EQ(relations[2].near[0].id, 4);
  for (const auto& n : relations[0].near) EXPECT_NE(n.id, 2);
}

TEST(Surfaces, WithTheFloorUnseenTheTableIsWhatSmallObjectsStandOn) {
  Fixture f;
  const auto objects = f.objects();
  std::vector<Surface> surfaces =
      surfaces_and_tops(f.map(/*with_floor=*/false), Vec3::UnitZ(), objects);
  relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  int tables = 0, floors = 0;
  for (const auto& s : surfaces) {
    tables += s.label == "table";
    floors += s.label == "floor";
    if (s.label == "table") {
      EXPECT_NE(s.label_rule.find("floor is not seen"), std::string::npos);
    }
  }
  EXPECT_EQ(tables, 1);
  EXPECT_EQ(floors, 0);
}

TEST(Surfaces, WallsInACornerAreNoSurface) {
  // Two walls meeting in a corner: a slice of them at any height is an L of points as wide as the
  // room, which a height histogram alone takes for a patch at every level.
  std::vector<Vec3f> pts = room();
  for (double x = 0.0; x <= 3.0; x += 0.01)
    for (double z = 0.0; z <= 2.0; z += 0.01) pts.emplace_back(x, 3.0, z);
  const std::vector<Surface> surfaces = find_surfaces(pts, Vec3::UnitZ(), SurfaceOptions{});
  ASSERT_EQ(surfaces.size(), 2u);
  EXPECT_NEAR(surfaces[0].height_m, 0.0, 0.01);  // the floor, largest first
  EXPECT_NEAR(surfaces[1].height_m, 0.75, 0.01);
}

TEST(Surfaces, ATiltedFloorCutInTwoIsOneSurface) {
  // The estimated up is 3 deg off the floor (as on TUM fr1): the floor's height runs 0.21 m across
  // its 4 m, and a rug-wide gap cuts it in two pieces whose median heights differ by 0.1 m.
  std::vector<Vec3f> pts;
  const double slope = std::tan(3.0 * M_PI / 180.0);
  for (double x = 0.0; x <= 4.0; x += 0.01)
    for (double y = 0.0; y <= 3.0; y += 0.01)
      if (x < 1.9 || x > 2.1) pts.emplace_back(x, y, slope * x);
  const std::vector<Surface> surfaces = find_surfaces(pts, Vec3::UnitZ(), SurfaceOptions{});
  ASSERT_EQ(surfaces.size(), 1u);
  EXPECT_NEAR(surfaces[0].area_m2, 3.8 * 3.0, 0.5);
}

TEST(Surfaces, AFloorLargerThanATableIsTheFloorWithOnlySmallObjectsOnIt) {
  std::vector<Vec3f> pts;
  add_rect(pts, 0.0, 3.0, 0.0, 3.0, 0.0);
  const PointCloud bag = box_object(Vec3(1.5, 1.5, 0.0), 0.1, 0.2);
  pts.insert(pts.end(), bag.points.begin(), bag.points.end());
  const std::vector<SceneObject> objects = {{1, "backpack", Vec3(1.5, 1.5, 0.1), &bag}};
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  // The floor, and the bag's 0.04 m2 top as its top.
  ASSERT_EQ(surfaces.size(), 2u);
  EXPECT_EQ(surfaces[0].label, "floor");
  EXPECT_EQ(surfaces[1].object, std::optional<int>(1));
  ASSERT_TRUE(relations[0].on);
  EXPECT_EQ(relations[0].on->label, "floor");
}

TEST(Surfaces, AFloorInPiecesAtOneLevelIsFloorEverywhere) {
  // A 3 x 2 m floor at 5 cm and, 0.6 m beyond it, a 1 m2 piece at 0 (under a desk the camera saw
  // from afar: a few cm lower through the estimated up's tilt). The lowest piece is not the
  // floor alone; a table top at 0.8 m is a table above the larger piece.
  std::vector<Vec3f> pts;
  add_rect(pts, 0.0, 3.0, 0.0, 2.0, 0.05);
  add_rect(pts, 0.0, 1.0, 2.6, 3.6, 0.0);
  add_rect(pts, 1.0, 2.0, 0.5, 1.3, 0.8);
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), {});
  relate_objects({}, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_EQ(surfaces.size(), 3u);
  EXPECT_EQ(surfaces[0].label, "floor");  // the 6 m2 piece, largest first
  EXPECT_NE(surfaces[0].label_rule.find("largest"), std::string::npos) << surfaces[0].label_rule;
  EXPECT_EQ(surfaces[1].label, "floor");  // the 1 m2 piece
  EXPECT_NE(surfaces[1].label_rule.find("floor's level"), std::string::npos);
  EXPECT_EQ(surfaces[2].label, "table");
  EXPECT_EQ(surfaces[2].label_rule, "a patch 0.75 m above the floor");
}

TEST(Surfaces, ALargeFloorAboveASmallLowPieceIsTheFloor) {
  // fr1_rpy_every4 in its first camera's frame with an up 3 deg off: the floor's 5.7 m2 lie at
  // -1.59 m and a 0.5 m2 piece of it, far from the cameras, at -1.72 m (13 cm lower: beyond the
  // 12 cm of one level). The large patch is the floor; the small one is not a table.
  std::vector<Vec3f> pts;
  add_rect(pts, 0.0, 3.0, 0.0, 2.0, 0.13);
  add_rect(pts, 0.0, 0.7, 2.6, 3.3, 0.0);
  add_rect(pts, 1.0, 2.0, 0.5, 1.3, 0.9);
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), {});
  relate_objects({}, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_EQ(surfaces.size(), 3u);
  EXPECT_EQ(surfaces[0].label, "floor");    // 6 m2, largest first
  EXPECT_EQ(surfaces[1].label, "table");    // the top at 0.9 m, 0.77 m above the floor
  EXPECT_EQ(surfaces[2].label, "surface");  // the low piece
}

TEST(Relations, AMonitorAtTheDesksBackEdgeStandsOnIt) {
  // The desk's visible outline ends where the monitor hides it: the monitor's centre lies 5.5 cm
  // beyond the outline's edge (y = 1.775, the last 4 cm cell's mean; more than the 3 cm margin)
  // with 27% of its footprint over the desk. A box with 8% of its footprint over the desk, its
  // bottom at the desk's height, stands on the desk too: the top holds under what hides it.
  std::vector<Vec3f> pts = room();
  const PointCloud monitor = box_object(Vec3(1.5, 1.83, 0.75), 0.12, 0.4);
  const PointCloud box = box_object(Vec3(2.0, 1.875, 0.75), 0.12, 0.1);
  const std::vector<SceneObject> objects = {{1, "tv monitor", Vec3(1.5, 1.83, 0.95), &monitor},
                                            {2, "box", Vec3(2.0, 1.875, 0.8), &box}};
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(relations[0].on);
  EXPECT_EQ(relations[0].on->label, "table");
  ASSERT_TRUE(relations[1].on);
  EXPECT_EQ(relations[1].on->label, "table");
}

TEST(Relations, ABookOnABookOfItsSizeIsOnThatBook) {
  // The upper book is seen whole, the lower one only by its sides: from above the lower one looks
  // no larger than the upper. The upper's bottom is 3 cm above the table and at the lower's top.
  std::vector<Vec3f> pts = room();
  const PointCloud lower = box_object(Vec3(1.5, 1.3, 0.75), 0.1, 0.03);
  const PointCloud upper = box_object(Vec3(1.5, 1.3, 0.78), 0.1, 0.03);
  for (const PointCloud* c : {&lower, &upper})
    pts.insert(pts.end(), c->points.begin(), c->points.end());
  const std::vector<SceneObject> objects = {{1, "book", Vec3(1.5, 1.3, 0.765), &lower},
                                            {2, "book", Vec3(1.5, 1.3, 0.795), &upper}};
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(relations[0].on);
  EXPECT_EQ(relations[0].on->label, "table");
  ASSERT_TRUE(relations[1].on);
  EXPECT_EQ(relations[1].on->kind, "object");
  EXPECT_EQ(relations[1].on->id, 1);
}

// A chair seen from above, as fr1_rpy's by the desk: its mask holds the back (0.55-1.1 m), not
// the seat, whose 0.4 x 0.4 m patch at 0.55 m the table rule labels; the legs are not seen. The
// floor is seen only in front of the chair, `gap_m` or more from its footprint (the back, y 2.46
// to 2.5); no floor when `gap_m` < 0.
struct ChairSeenFromAbove {
  PointCloud back;
  std::vector<Vec3f> map;
  explicit ChairSeenFromAbove(double gap_m) : map(room(/*with_floor=*/false)) {
    if (gap_m >= 0.0) add_rect(map, 0.0, 3.0, 0.0, 2.46 - gap_m, 0.0);
    for (double x = 0.4; x <= 0.8; x += 0.01)
      for (double y = 2.46; y <= 2.5; y += 0.01)
        for (double z = 0.55; z <= 1.1; z += 0.01) back.push_back(Vec3f(x, y, z), Rgb{});
    map.insert(map.end(), back.points.begin(), back.points.end());
    add_rect(map, 0.4, 0.8, 2.1, 2.5, 0.55);
  }
  std::vector<Relations> relate(const std::string& class_name) {
    const std::vector<SceneObject> objects = {{1, class_name, Vec3(0.6, 2.48, 0.8), &back}};
    surfaces = surfaces_and_tops(map, Vec3::UnitZ(), objects);
    return relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  }
  std::vector<Surface> surfaces;  // of the last relate()
};

TEST(Relations, AChairSeenFromAboveStandsOnTheFloorNotOnItsSeat) {
  // Its bottom (the back's lowest point) is 0.55 m above the floor: its legs are hidden (within
  // hidden_base_m, 1 m), so it stands on the floor, gap_m 0.55; the patch at its bottom is its own
  // seat, not a table it is on.
  for (double gap : {0.0, 0.8, 1.2}) {  // the floor seen up to the chair, or from further away
    SCOPED_TRACE("floor from " + std::to_string(gap) + " m");
    ChairSeenFromAbove scene(gap);
    const auto chair = scene.relate("chair");
    ASSERT_TRUE(chair[0].on);
    EXPECT_EQ(chair[0].on->label, "floor");
    EXPECT_NEAR(chair[0].on->gap_m, 0.55, 0.02);
    ASSERT_FALSE(scene.surfaces.empty());
    const Surface& seat = scene.surfaces.back();  // the smallest
    EXPECT_EQ(seat.label, "seat");
    EXPECT_EQ(seat.object, std::optional<int>(1));
    const auto box = scene.relate("box");  // no furniture: it stands where it is seen
    ASSERT_TRUE(box[0].on);
    EXPECT_EQ(box[0].on->label, "table");
    EXPECT_NEAR(box[0].on->gap_m, 0.0, 0.02);
  }
}

TEST(Relations, ADiningTableSeenByItsTopStandsOnTheFloorItsLegsHidden) {
  // Only the top slab (0.70-0.75 m) of a 1.2 x 0.8 m dining table is in its mask, in a room whose
  // floor is seen around it: the floor is 0.70 m below its bottom, its legs hidden: on the floor,
  // gap_m 0.70. With hidden_base_m 0.5 it stands on nothing seen.
  std::vector<Vec3f> map;
  add_rect(map, 0.0, 3.0, 0.0, 3.0, 0.0);
  PointCloud table;
  for (double z = 0.70; z <= 0.75; z += 0.01) add_rect(table.points, 0.5, 1.7, 0.5, 1.3, z, 0.02);
  table.colors.assign(table.points.size(), Rgb{});
  map.insert(map.end(), table.points.begin(), table.points.end());
  const std::vector<SceneObject> objects = {{1, "dining table", Vec3(1.1, 0.9, 0.725), &table}};
  std::vector<Surface> surfaces = surfaces_and_tops(map, Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(relations[0].on);
  EXPECT_EQ(relations[0].on->label, "floor");
  EXPECT_NEAR(relations[0].on->gap_m, 0.70, 0.02);
  RelationOptions strict;
  strict.hidden_base_m = 0.5;
  EXPECT_FALSE(relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, strict)[0].on);
  // With its legs seen down to 5 cm above the floor it stands on the floor, gap_m small.
  for (double x : {0.52, 1.66})  // four legs 3 x 3 cm, one point per 1 cm voxel
    for (double y : {0.52, 1.26})
      for (double z = 0.05; z < 0.70; z += 0.01)
        for (double dx : {0.0, 0.01, 0.02})
          for (double dy : {0.0, 0.01, 0.02}) table.push_back(Vec3f(x + dx, y + dy, z), Rgb{});
  const auto with_legs =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(with_legs[0].on);
  EXPECT_EQ(with_legs[0].on->label, "floor");
  EXPECT_LE(with_legs[0].on->gap_m, 0.15);
}

// A fragment of a chair (its top 10 cm, seen as another object of the class) inside the whole
// chair's box: its bottom lies 5 cm under the whole's top, within `on`'s window, yet it is one
// chair seen twice. Both list the other as a suspected duplicate; neither is on the other.
TEST(Relations, TwoObjectsOfOneClassThatInterpenetrateAreSuspectedDuplicatesNotOnEachOther) {
  std::vector<Vec3f> pts = room();
  const PointCloud whole = box_object(Vec3(0.5, 2.3, 0.0), 0.2, 0.9);
  const PointCloud fragment = box_object(Vec3(0.5, 2.3, 0.85), 0.2, 0.1);
  const std::vector<SceneObject> objects = {{1, "chair", Vec3(0.5, 2.3, 0.45), &whole},
                                            {2, "chair", Vec3(0.5, 2.3, 0.9), &fragment}};
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(relations[0].on);
  EXPECT_EQ(relations[0].on->label, "floor");
  EXPECT_FALSE(relations[1].on && relations[1].on->kind == "object");
  ASSERT_EQ(relations[0].duplicates.size(), 1u);
  EXPECT_EQ(relations[0].duplicates[0].id, 2);
  EXPECT_GE(relations[0].duplicates[0].overlap, 0.3);
  ASSERT_EQ(relations[1].duplicates.size(), 1u);
  EXPECT_EQ(relations[1].duplicates[0].id, 1);
  // Of another class it is on the chair (a box on a chair's top, its bottom at that top).
  const std::vector<SceneObject> other = {{1, "chair", Vec3(0.5, 2.3, 0.45), &whole},
                                          {2, "suitcase", Vec3(0.5, 2.3, 0.9), &fragment}};
  const auto on_chair =
      relate_objects(other, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(on_chair[1].on);
  EXPECT_EQ(on_chair[1].on->kind, "object");
  EXPECT_EQ(on_chair[1].on->id, 1);
  EXPECT_TRUE(on_chair[1].duplicates.empty());
}

// A bowl at the height of a chair's backrest top, over its seat (on a table behind the chair whose
// top is not seen): its bottom is at the chair's top, but not over the chair's top (the backrest),
// so it is not on the chair.
TEST(Relations, AnObjectIsOnAnotherOnlyOverItsTop) {
  PointCloud chair;
  const Vec3 c(0.6, 2.3, 0.0);
  for (double x = -0.2; x <= 0.2; x += 0.01)
    for (double y = -0.2; y <= 0.2; y += 0.01)
      chair.push_back(Vec3f(c.x() + x, c.y() + y, 0.45), Rgb{});
  for (double x = -0.2; x <= 0.2; x += 0.01)
    for (double z = 0.45; z <= 0.9; z += 0.01)
      chair.push_back(Vec3f(c.x() + x, c.y() + 0.2, z), Rgb{});
  for (double x = -0.2; x <= 0.2; x += 0.01)  // the backrest is 3 cm thick
    for (double z = 0.45; z <= 0.9; z += 0.01)
      for (double t : {0.18, 0.19}) chair.push_back(Vec3f(c.x() + x, c.y() + t, z), Rgb{});
  const PointCloud bowl = box_object(Vec3(c.x(), c.y() - 0.05, 0.9), 0.08, 0.07);
  std::vector<Vec3f> pts = room();
  pts.insert(pts.end(), chair.points.begin(), chair.points.end());
  const std::vector<SceneObject> objects = {{1, "chair", Vec3(c.x(), c.y(), 0.45), &chair},
                                            {2, "bowl", Vec3(c.x(), c.y() - 0.05, 0.935), &bowl}};
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  EXPECT_FALSE(relations[1].on) << relations[1].on->kind << " " << relations[1].on->id;
  // A book lying on the backrest is on the chair.
  const PointCloud book = box_object(Vec3(c.x(), c.y() + 0.2, 0.9), 0.02, 0.03);
  const std::vector<SceneObject> on_back = {{1, "chair", Vec3(c.x(), c.y(), 0.45), &chair},
                                            {2, "book", Vec3(c.x(), c.y() + 0.2, 0.915), &book}};
  const auto on =
      relate_objects(on_back, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(on[1].on);
  EXPECT_EQ(on[1].on->kind, "object");
  EXPECT_EQ(on[1].on->id, 1);
}

TEST(Relations, AChairSeenFromAboveWithNoFloorStaysWhereItIsSeen) {
  ChairSeenFromAbove scene(-1.0);  // no floor at all
  const auto chair = scene.relate("chair");
  ASSERT_TRUE(chair[0].on);
  EXPECT_NE(chair[0].on->label, "floor");
  EXPECT_NEAR(chair[0].on->gap_m, 0.0, 0.02);
}

TEST(Relations, AMonitorAtTheDesksBackEdgeStandsOnTheDeskItHides) {
  // The table top's visible outline ends at y = 1.8 m where the monitor hides the rest: the
  // monitor's footprint (y 1.82-1.98) lies beyond it, touching it, its bottom at the top's height.
  // A box at that height 0.5 m beyond the outline stands on nothing seen.
  const std::vector<Vec3f> map = room();
  const PointCloud monitor = box_object(Vec3(1.6, 1.9, 0.76), 0.08, 0.4);
  const PointCloud away = box_object(Vec3(1.6, 2.4, 0.76), 0.08, 0.2);
  const std::vector<SceneObject> objects = {{1, "tv monitor", Vec3(1.6, 1.9, 0.96), &monitor},
                                            {2, "box", Vec3(1.6, 2.4, 0.86), &away}};
  std::vector<Surface> surfaces = surfaces_and_tops(map, Vec3::UnitZ(), objects);
  const auto r =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(r[0].on);
  EXPECT_EQ(r[0].on->label, "table");
  EXPECT_NEAR(r[0].on->gap_m, 0.01, 0.02);
  EXPECT_FALSE(r[1].on) << r[1].on->label;
}

TEST(Relations, TheFloorHoldsForTheWholeRoom) {
  // A refrigerator (0.8 x 0.7 m, 1.8 m tall) 2.5 m from the only floor seen, its bottom at the
  // floor's height: on the floor. So is a box on nothing there (a suitcase); a box whose bottom is
  // 0.3 m up (on something unseen) is not.
  std::vector<Vec3f> map = room(/*with_floor=*/false);
  add_rect(map, 0.0, 3.0, 0.0, 1.5, 0.0);
  const PointCloud fridge = box_object(Vec3(0.9, 4.0, 0.02), 0.4, 1.8);
  const PointCloud low = box_object(Vec3(2.2, 4.5, 0.01), 0.2, 0.4);
  const PointCloud high = box_object(Vec3(2.2, 5.5, 0.3), 0.2, 0.4);
  map.insert(map.end(), fridge.points.begin(), fridge.points.end());
  const std::vector<SceneObject> objects = {{1, "refrigerator", Vec3(0.9, 4.0, 0.9), &fridge},
                                            {2, "suitcase", Vec3(2.2, 4.5, 0.2), &low},
                                            {3, "box", Vec3(2.2, 5.5, 0.5), &high}};
  std::vector<Surface> surfaces = surfaces_and_tops(map, Vec3::UnitZ(), objects);
  const auto r =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(r[0].on);
  EXPECT_EQ(r[0].on->label, "floor");
  ASSERT_TRUE(r[1].on);
  EXPECT_EQ(r[1].on->label, "floor");
  EXPECT_FALSE(r[2].on);
}

TEST(Relations, AChairOnThinLegsStandsOnTheFloor) {
  // A seat at 0.45 m and a back up to 0.9 m hold most of the chair's points, its four legs 5% (one
  // point per 1 cm voxel, as a fused object's cloud): its 2nd height percentile is 0.2 m up a leg.
  PointCloud chair;
  const Vec3 c(0.6, 2.3, 0.0);
  for (double x = -0.2; x <= 0.2; x += 0.01)
    for (double y = -0.2; y <= 0.2; y += 0.01)
      chair.push_back(Vec3f(c.x() + x, c.y() + y, 0.45), Rgb{});
  for (double x = -0.2; x <= 0.2; x += 0.01)
    for (double z = 0.45; z <= 0.9; z += 0.01)
      chair.push_back(Vec3f(c.x() + x, c.y() + 0.2, z), Rgb{});
  for (double lx : {-0.18, 0.18})
    for (double ly : {-0.18, 0.18})
      for (double z = 0.0; z < 0.45; z += 0.01)
        chair.push_back(Vec3f(c.x() + lx, c.y() + ly, z), Rgb{});
  std::vector<Vec3f> pts = room();
  pts.insert(pts.end(), chair.points.begin(), chair.points.end());
  const std::vector<SceneObject> objects = {{1, "chair", Vec3(c.x(), c.y(), 0.45), &chair}};
  std::vector<Surface> surfaces = surfaces_and_tops(pts, Vec3::UnitZ(), objects);
  const auto relations =
      relate_objects(objects, surfaces, Vec3::UnitZ(), SurfaceOptions{}, RelationOptions{});
  ASSERT_TRUE(relations[0].on);
  EXPECT_EQ(relations[0].on->label, "floor");
  EXPECT_LE(relations[0].on->gap_m, 0.05);  // the 0.5th percentile: 0.04 m up a leg
}

TEST(Surfaces, OptionsAreChecked) {
  SurfaceOptions o;
  o.min_area_m2 = 0.0;
  EXPECT_THROW(o.check(), InputError);
  RelationOptions r;
  r.near_radius_m = -1;
  EXPECT_THROW(r.check(), InputError);
}

}  // namespace
}  // namespace objmap::scene
